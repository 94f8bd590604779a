"""Image files read as Cycles reads them (addon/export/images.py, colorspaces.py, imageuser.py),
against Cycles on the sun-lit plane (sunplane: direct light only, one texel colour per case, so
the means agree within float and half-float rounding, measured 0.02%):

- an 8-bit PNG in a colour space other than sRGB: converted to scene linear through Blender's
  OCIO config (Linear Rec.2020, ACEScg and the 'scene_linear' role had been 0.72 / 1.19 / 1.21,
  0.45 / 0.30 / 0.17 and 0.64 / 0.25 / 0.13 of Cycles; Filmic sRGB, read as sRGB, 0.87 / 1.23 /
  1.08); 16-bit and float files, which Blender converts on load, agreed before and still do;
- a grey+alpha PNG: not multiplied by its alpha (Cycles associates 4-channel files only; it had
  been 0.22x Cycles), yet divided by it when the Alpha output drives a cut-out (had been 0.21x);
- a 16-bit RGBA PNG read 'Closest': associated before the sRGB decoding (had been 2.1-4.9x);
- an image sequence: the file of the frame its image user shows at the scene's frame (cyclic,
  with an offset; had rendered magenta)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES = 8, 4
TOLERANCE = 0.003      # of each channel's mean; Cycles stores converted images as half floats
COLOUR = np.array([[[179, 77, 38]]], np.uint8)            # (0.7, 0.3, 0.15) in bytes


def _render_both(tmp_path, wire, after=None):
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, SAMPLES)
    if after is not None:
        after()
    return {e: sunplane.render_rgb(e, tmp_path).mean(axis=(0, 1)) for e in ('DACRT', 'CYCLES')}


def _agree(means, case):
    d, c = means['DACRT'], means['CYCLES']
    assert c.max() > 0.01, (case, c)
    assert np.abs(d - c).max() / c.max() < TOLERANCE, (case, d.round(5).tolist(), c.round(5).tolist(), (d / c).round(4))


@pytest.mark.parametrize('space, fmt', [('Linear Rec.2020', 'uint8'), ('ACEScg', 'uint8'), ('scene_linear', 'uint8'),
                                        ('Filmic sRGB', 'uint8'), ('Linear Rec.2020', 'uint16'), ('ACEScg', 'float')])
def test_colour_space_converted_as_cycles(tmp_path, space, fmt):
    """8-bit files are converted here; 16-bit and float ones Blender converts on load."""
    px = COLOUR.repeat(2, 0).repeat(2, 1)
    px = {'uint8': px, 'uint16': px.astype(np.uint16) * 257, 'float': (px / 255.0).astype(np.float32)}[fmt]
    path = scenes.write_image(tmp_path / ("c.exr" if fmt == 'float' else "c.png"), px, fmt)

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.image.colorspace_settings.name = space
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    _agree(_render_both(tmp_path, wire), f"{space} {fmt}")


GREY = np.array([[[102, 128], [255, 128]], [[255, 128], [102, 128]]], np.uint8)   # grey 0.4 / 1, alpha 0.5


@pytest.mark.parametrize('cutout', [False, True], ids=['colour', 'cutout'])
def test_grey_alpha_png(tmp_path, cutout):
    """Colour into the Diffuse (Alpha unlinked): the straight grey, decoded. As a cut-out (Alpha
    the factor of a Transparent / Diffuse mix, over the black world): alpha x the grey divided
    by alpha (0.8 and 2.0), decoded."""
    path = scenes.write_image(tmp_path / "ga.png", GREY)

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    means = _render_both(tmp_path, wire, sunplane.alpha_cutout if cutout else None)
    _agree(means, 'cutout' if cutout else 'colour')
    g, a = GREY[..., 0] / 255.0, GREY[..., 1] / 255.0
    decode = lambda c: np.where(c < 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    albedo = a * decode(g / a) if cutout else decode(g)
    want = albedo.mean() * 2.0 / np.pi                                  # sunplane: E / pi = 2 / pi
    assert np.abs(means['DACRT'] - want).max() / want < TOLERANCE, (means['DACRT'], want)


def test_16bit_rgba_closest(tmp_path):
    px = np.broadcast_to(np.array([65535, 32768, 13107, 16384], np.uint16), (2, 2, 4)).copy()
    path = scenes.write_image(tmp_path / "a16.png", px, 'uint16')

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    _agree(_render_both(tmp_path, wire), '16-bit RGBA')


def test_image_sequence_reads_the_frame_shown(tmp_path):
    """Frames 1-3 red, green, blue; the user starts at scene frame 4, cyclic, offset 1: scene
    frame 8 is the user's frame 5, 2 once wrapped, 3 with the offset: blue."""
    for i, rgb in enumerate(([200, 30, 30], [30, 200, 30], [30, 30, 200])):
        scenes.write_image(tmp_path / f"seq_{i + 1:03d}.png", np.array([[rgb]], np.uint8).repeat(2, 0).repeat(2, 1))

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(str(tmp_path / "seq_001.png"))
        tex.image.source = 'SEQUENCE'
        user = tex.image_user
        user.frame_duration, user.frame_start, user.frame_offset, user.use_cyclic = 3, 4, 1, True
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    means = _render_both(tmp_path, wire, lambda: bpy.context.scene.frame_set(8))
    _agree(means, 'sequence')
    assert means['CYCLES'][2] > 10 * means['CYCLES'][:2].max(), "Cycles must show the blue frame"
