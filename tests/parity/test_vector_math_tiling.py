"""A normal map's image tiled or offset by a Vector Math node of constants (UV x 2.5, UV / s,
UV + offset, a constant - UV, UV x s + offset: how many asset groups expose "Tiling") against
Cycles. These are affine maps of the UV map (mapping.vector_math_affine) and compose exactly
into the image's transform, as a Mapping node does.

Before, the image was read on the plain UV map ("texture coordinates from 'Vector Math' read as
the UV map", naming no image): UV x 2.5 rendered the normal-mapped plane 1.31x Cycles, 8-px
blocks off by up to 0.23. A chain that is still no affine map is said naming the image."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')

# (operation, {input index: value}, index the UV is linked to)
_CHAINS = {
    'scale': ('SCALE', {3: 2.5}, 0),
    'multiply': ('MULTIPLY', {1: (2.5, 1.5, 1.0)}, 0),
    'divide': ('DIVIDE', {1: (0.4, 0.5, 1.0)}, 0),
    'add': ('ADD', {0: (0.3, 0.15, 0.0)}, 1),
    'constant_minus_uv': ('SUBTRACT', {0: (0.2, 0.0, 0.0)}, 1),
    'multiply_add': ('MULTIPLY_ADD', {1: (2.0, 2.0, 1.0), 2: (0.25, 0.0, 0.0)}, 0),
}


def _normal_image(tmp_path):
    """A 16 x 1 Non-Color normal map whose tilt along u is a cosine (a ridged surface)."""
    u = (np.arange(16) + 0.5) / 16
    g = 0.6 * np.cos(2 * np.pi * u)
    n = np.stack([-g, np.zeros_like(g), np.ones_like(g)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    px = np.round((n + 1) / 2 * 255).astype(np.uint8)[None]
    img = bpy.data.images.load(scenes.write_image(tmp_path / "ridges.png", px))
    img.colorspace_settings.name = 'Non-Color'
    return img


def _scene(tmp_path, operation, values, uv_input):
    """A 4 x 4 plane (Diffuse 0.8) whose normal map's image reads the UV map through one Vector
    Math node, under a low sun from +x, seen from above; 48 x 48 pixels."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat = scenes.normal_map_material("Tiled", _normal_image(tmp_path))
    nt = mat.node_tree
    tex = next(n for n in nt.nodes if n.type == 'TEX_IMAGE')
    tex.extension = 'REPEAT'
    vm = nt.nodes.new('ShaderNodeVectorMath')
    vm.operation = operation
    for i, v in values.items():
        vm.inputs[i].default_value = v
    coords = nt.nodes.new('ShaderNodeTexCoord')
    nt.links.new(coords.outputs['UV'], vm.inputs[uv_input])
    nt.links.new(vm.outputs['Vector'], tex.inputs['Vector'])
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.plane("Plane", size=4.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (0.0, math.radians(60.0), 0.0)
    return tex


def _blocks(img, size=8):
    h, w = img.shape[:2]
    return img[..., 0].reshape(h // size, size, w // size, size).mean((1, 3))


@pytest.mark.parametrize('chain', sorted(_CHAINS))
def test_vector_math_tiled_normal_map_matches_cycles(chain, tmp_path, said):
    """Each 8-px block within 0.01 of Cycles' (the ridges move blocks by up to 0.2 when the
    tiling is left out; measured within 0.001 after)."""
    _scene(tmp_path, *_CHAINS[chain])
    _settings(16, 0)
    img = _rgb(tmp_path)
    d, c = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    assert c.max() > 1.2 * c.min(), "the ridges must show"
    np.testing.assert_allclose(d, c, atol=0.01)
    assert not any("read as the UV map" in t for t in said), said


def test_a_chain_that_is_no_affine_map_names_the_image(tmp_path, said):
    """A Vector Math Sine of the UV is no affine map: still read on the UV map, said naming
    the normal map's image and the node."""
    tex = _scene(tmp_path, 'SINE', {}, 0)
    _settings(1, 0)
    sc = bpy.context.scene
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "dacrt.exr", sc)
    text = ' '.join(said)
    assert f"image '{tex.image.name}'" in text and "'Vector Math' Sine" in text, said
