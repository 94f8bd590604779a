"""Image files stored with their alpha multiplied in (OpenEXR always; TIFFs written so, 8- and
16-bit) render their values as stored, as Cycles reads them (addon/export/images.py): its loader
associates only files stored straight, so a Non-Color or Channel Packed image keeps the stored
colour and an associated one is not associated again. The export had divided alpha back out of
every such file and associated it again only where Cycles associates, so data and
channel-packed images rendered divided by alpha (the texel of alpha 0.5 twice Cycles' in a
Non-Color EXR; blocks off by up to 0.60-1.15x the brightest, every case below failing), an
8-bit TIFF set to Straight was rounded twice, and a texel of alpha 0 lost its colour (black
where Cycles shows it). Still images, UDIM tiles, image-sequence frames and Environment Textures
alike; nothing is reported about them, as nothing differs.

Sun-lit plane (sunplane: direct light only), 2x2 texels read Closest, one 4x4-pixel block each:
every block against Cycles' render within 0.3% of the brightest and, where the colour space has
one, against the closed form E / pi x the stored value (decoded for sRGB; x alpha for a cut-out)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from addon.texture import srgb_to_linear

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES = 8, 4
TOLERANCE = 0.003
# stored (associated) RGBA, row 0 at the bottom; texel (0, 1) has alpha 0 and a colour
STORED = np.array([[[0.30, 0.20, 0.10, 0.5], [0.25, 0.50, 0.05, 0.0]],
                   [[0.10, 0.40, 0.30, 1.0], [0.05, 0.15, 0.45, 0.75]]], np.float32)
TOP = {'uint8': 255, 'uint16': 65535}



def _write(path, px, fmt):
    """px (h, w, 4) written with its alpha marked associated (how OpenEXR stores it, and how a
    TIFF says so); integer formats rounded; returns (path, the values as stored)."""
    import OpenImageIO as oiio
    h, w, c = px.shape
    data = np.rint(px * TOP[fmt]).astype(np.dtype(fmt)) if fmt in TOP else px
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, c, fmt))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(data[::-1]))
    assert buf.write(str(path)), buf.geterror()
    stored = data.astype(np.float32) / TOP[fmt] if fmt in TOP else np.asarray(px, np.float32)
    if fmt == 'half':
        stored = stored.astype(np.float16).astype(np.float32)
    return str(path), stored


def _albedo(stored, space):
    """The albedo Cycles renders of stored texels: the values, sRGB ones decoded; None where
    the colour space needs OpenColorIO."""
    if space in ('Non-Color', 'Linear Rec.709'):
        return stored[..., :3]
    if space == 'sRGB':
        return srgb_to_linear(stored[..., :3])
    return None


def _blocks(rgb, grid):
    h, w = grid
    return rgb.reshape(h, SIZE // h, w, SIZE // w, 3).mean((1, 3))


def _check(tmp_path, wire, space, want_texels, grid, image_name, said, after=None):
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, SAMPLES)
    if after is not None:
        after()
    said.clear()
    got = {e: _blocks(sunplane.render_rgb(e, tmp_path), grid) for e in ('DACRT', 'CYCLES')}
    d, c = got['DACRT'], got['CYCLES']
    err = np.abs(d - c).max() / c.max()
    assert err < TOLERANCE, (err, d.round(4).tolist(), c.round(4).tolist())
    if want_texels is not None:
        want = want_texels * 2.0 / np.pi                  # sunplane: E / pi = 2 / pi
        assert np.abs(d - want).max() / want.max() < TOLERANCE, (d.round(4).tolist(), want.round(4).tolist())
    assert not [t for t in said if image_name in t], said


@pytest.mark.parametrize('ext, fmt, space, alpha_mode', [
    ('exr', 'float', 'Non-Color', 'STRAIGHT'),           # (0.3, 0.2, 0.1) at alpha 0.5 had been x2
    ('exr', 'half', 'Linear Rec.709', 'CHANNEL_PACKED'),
    ('exr', 'float', 'ACEScg', 'CHANNEL_PACKED'),
    ('exr', 'float', 'Linear Rec.709', 'STRAIGHT'),      # the alpha-0 texel had been black
    ('tif', 'uint16', 'sRGB', 'CHANNEL_PACKED'),         # had been off by 1.15x the brightest
    ('tif', 'uint16', 'Non-Color', 'PREMUL'),
    ('tif', 'uint8', 'sRGB', 'CHANNEL_PACKED'),
    ('tif', 'uint8', 'Non-Color', 'PREMUL'),
    ('tif', 'uint8', 'sRGB', 'STRAIGHT'),                # rounded twice; alpha-0 texel black
], ids=lambda v: str(v))
def test_still_image_values_as_stored(tmp_path, said, ext, fmt, space, alpha_mode):
    path, stored = _write(tmp_path / f"a.{ext}", STORED, fmt)

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.image.colorspace_settings.name, tex.image.alpha_mode = space, alpha_mode
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    _check(tmp_path, wire, space, _albedo(stored, space), (2, 2), 'a.' + ext, said)


def test_cutout_of_a_non_color_exr(tmp_path, said):
    """Alpha as the factor of a Transparent / Diffuse mix over the black world: alpha x the
    stored colour (had been the stored colour: off by 0.375x the brightest block)."""
    path, stored = _write(tmp_path / "cut.exr", STORED, 'float')

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.image.colorspace_settings.name = 'Non-Color'
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    _check(tmp_path, wire, 'Non-Color', stored[..., :3] * stored[..., 3:4], (2, 2), 'cut.exr', said, sunplane.alpha_cutout)


@pytest.mark.parametrize('ext, fmt, space, alpha_mode', [('exr', 'float', 'Non-Color', 'STRAIGHT'),
                                                         ('tif', 'uint16', 'sRGB', 'CHANNEL_PACKED')])
def test_udim_tiles_values_as_stored(tmp_path, said, ext, fmt, space, alpha_mode):
    """Tiles 1001 and 1002 (the second read from its file through OpenImageIO), UVs scaled x2 in
    U: the left half of the plane shows 1001's 2x2 texels, the right half 1002's."""
    _, first = _write(tmp_path / f"t.1001.{ext}", STORED, fmt)
    _, second = _write(tmp_path / f"t.1002.{ext}", STORED[::-1], fmt)

    def wire(nt, tex, diffuse):
        img = bpy.data.images.load(str(tmp_path / f"t.1001.{ext}"))
        img.source = 'TILED'
        img.colorspace_settings.name, img.alpha_mode = space, alpha_mode
        tex.image = img
        m = nt.nodes.new('ShaderNodeMapping')
        m.inputs['Scale'].default_value = (2.0, 1.0, 1.0)
        nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], m.inputs['Vector'])
        nt.links.new(m.outputs[0], tex.inputs['Vector'])
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    want = _albedo(np.concatenate([first, second], axis=1), space)
    _check(tmp_path, wire, space, want, (2, 4), 't.1001', said)


@pytest.mark.parametrize('ext, fmt, space, alpha_mode', [('exr', 'float', 'Non-Color', 'STRAIGHT'),
                                                         ('tif', 'uint8', 'sRGB', 'CHANNEL_PACKED')])
def test_sequence_frame_values_as_stored(tmp_path, said, ext, fmt, space, alpha_mode):
    """Frames 1-3, the second flipped; at scene frame 2 the second's values."""
    for f in (1, 2, 3):
        _, stored = _write(tmp_path / f"s_{f:03d}.{ext}", STORED[::-1] if f == 2 else STORED, fmt)
        if f == 2:
            shown = stored

    def wire(nt, tex, diffuse):
        img = bpy.data.images.load(str(tmp_path / f"s_001.{ext}"))
        img.source = 'SEQUENCE'
        img.colorspace_settings.name, img.alpha_mode = space, alpha_mode
        tex.image = img
        tex.image_user.frame_duration = 3
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    _check(tmp_path, wire, space, _albedo(shown, space), (2, 2), 's_001', said,
           lambda: bpy.context.scene.frame_set(2))


@pytest.mark.parametrize('ext, fmt, space, alpha_mode', [('exr', 'float', 'Non-Color', 'STRAIGHT'),
                                                         ('tif', 'uint16', 'sRGB', 'CHANNEL_PACKED')])
def test_environment_values_as_stored(tmp_path, said, ext, fmt, space, alpha_mode):
    """An Environment Texture of one stored colour (0.3, 0.2, 0.1) at alpha 0.5 seen by the
    camera: the world's radiance is the stored value (had been (0.6, 0.4, 0.2); decoded from
    the sRGB TIFF, 4.3x / 4.0x / 3.3x Cycles')."""
    px = np.broadcast_to(np.array([0.3, 0.2, 0.1, 0.5], np.float32), (2, 4, 4)).copy()
    path, stored = _write(tmp_path / f"env.{ext}", px, fmt)
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    img = bpy.data.images.load(path)
    img.colorspace_settings.name, img.alpha_mode = space, alpha_mode
    scenes.environment_world(img, interpolation='Closest')
    sc.render.resolution_x = sc.render.resolution_y = 4
    sc.cycles.device, sc.cycles.use_denoising = 'CPU', False
    sc.cycles.samples = sc.dacrt.samples = 1
    said.clear()
    got = {}
    for engine in ('DACRT', 'CYCLES'):
        sc.render.engine = engine
        got[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr")))[..., :3].mean((0, 1))
    want = _albedo(stored, space)[0, 0]
    assert np.abs(got['CYCLES'] - want).max() < 1e-3 * want.max() + 1e-4, (got['CYCLES'], want)
    assert np.abs(got['DACRT'] - want).max() < 1e-3 * want.max() + 1e-4, (got['DACRT'], want)
    assert not [t for t in said if 'env.' in t], said
