"""Cycles' Simplify > Texture Limit renders an image bigger than the limit halved until it fits
(a 512x512 texel-noise image at limit 128 renders in 4x4-texel blocks of one value each, its
per-pixel spread 0.046 against 0.184 at full size; measured). DACRT downscales float and 8-bit
images so (tests/parity/test_texture_limit.py); one Cycles converts to floats of its own (an
8-bit image in a colour space such as ACEScg) it renders at full size, and had said nothing. The
render now names each such image, its size and Cycles' (an image texture and a world's
environment), and says nothing when Simplify is off, the image fits, or it downscales the image
as Cycles."""
import bpy
import numpy as np
import pytest

from . import scenes


def _image(name, size, kind):
    """A packed (size / 2) x size grey image: 'float', 'bytes' (sRGB) or 'ACEScg' bytes."""
    if kind == 'float':
        return scenes.float_image(name, np.full((size, size // 2, 4), 0.5, np.float32))
    img = bpy.data.images.new(name, size // 2, size)
    img.pixels.foreach_set(np.full(size * (size // 2) * 4, 0.5, np.float32))
    img.pack()
    if kind == 'ACEScg':
        img.colorspace_settings.name = 'ACEScg'
    return img


def _scene(scene, size, env=False, kind='ACEScg'):
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    if env:
        scenes.environment_world(_image("Sky", size, kind))
        scenes.plane("Floor", size=2.0)
    else:
        mat, nt, out = scenes._material("Textured")
        d, tex = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeTexImage')
        tex.image = _image("Noise", size, kind)
        nt.links.new(tex.outputs['Color'], d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        scenes.plane("Floor", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
        scenes.light('SUN', 2.0)
    scene.render.resolution_x = scene.render.resolution_y = 8
    scene.dacrt.samples = 1


@pytest.mark.parametrize('simplify, limit, size, env, kind, said_size', [
    (True, '128', 512, False, 'ACEScg', "(256x512) is rendered at full size; Cycles' Simplify > Texture Limit (128) "
                                        "renders it 64x128"),
    (True, '256', 300, True, 'ACEScg', "(150x300) is rendered at full size; Cycles' Simplify > Texture Limit (256) "
                                       "renders it 75x150"),
    (True, '128', 512, False, 'float', None),     # downscaled as Cycles
    (True, '128', 512, True, 'bytes', None),      # downscaled as Cycles
    (True, '512', 512, False, 'ACEScg', None),    # fits: Cycles renders it as it is
    (False, '128', 512, False, 'ACEScg', None),   # Simplify off: the limit is not applied
])
def test_texture_limit_is_said_where_cycles_applies_it(scene, said, simplify, limit, size, env, kind, said_size):
    _scene(scene, size, env, kind)
    scene.render.use_simplify = simplify
    scene.cycles.texture_limit_render = limit
    scenes.render_rgba(scene)
    hits = [t for t in said if "Texture Limit" in t]
    if said_size is None:
        assert hits == [], said
    else:
        name = "Sky" if env else "Noise"
        assert len(hits) == 1 and f"image '{name}' {said_size}" in hits[0], said
