"""A diffuse colour reading two images (or an image and a procedural texture) is looked up per
point, as Cycles does: a UV-mapped plane under a white world without bounces (radiance = albedo),
seen square by an orthographic camera; 4x4 blocks of the frame against Cycles'. The export had
read the second image as its average colour (blocks 0.06-0.48 off) and a procedural beside an
image as its own value."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _images(tmp_path):
    rng = np.random.default_rng(3)
    a = (rng.random((4, 4, 4)) * 255).astype(np.uint8)
    a[..., 3] = 255
    b = (rng.random((2, 2, 4)) * 255).astype(np.uint8)           # with alpha
    return (bpy.data.images.load(scenes.write_image(tmp_path / "a.png", a)),
            bpy.data.images.load(scenes.write_image(tmp_path / "b.png", b)))


def multiply(nt, ta, tb):
    return scenes.mix_node(nt, 'MULTIPLY', ta.outputs['Color'], tb.outputs['Color'], 1.0).outputs['Result']


def alpha_mask(nt, ta, tb):
    m = scenes.mix_node(nt, 'MIX', ta.outputs['Color'], (0.1, 0.8, 0.2), 0.5)
    nt.links.new(tb.outputs['Alpha'], m.inputs['Factor'])
    return m.outputs['Result']


def noise_mask(nt, ta, tb):
    n = nt.nodes.new('ShaderNodeTexNoise')
    n.inputs['Scale'].default_value = 3.0
    m = scenes.mix_node(nt, 'MIX', ta.outputs['Color'], (0.1, 0.8, 0.2), 0.5)
    nt.links.new(n.outputs['Fac'], m.inputs['Factor'])
    return m.outputs['Result']


def mapped_linear(nt, ta, tb):
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.inputs['Scale'].default_value = (2, 2, 1)
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    nt.links.new(mp.outputs[0], tb.inputs['Vector'])
    ta.interpolation = tb.interpolation = 'Linear'          # 8-bit sRGB: blended encoded
    return multiply(nt, ta, tb)


def albedo_plane_blocks(colour):
    """The scene of this file and test_same_image_twice.py: a UV-mapped plane whose Principled
    (no specular layer) takes its Base Color from colour(node tree), under a white world without
    bounces (radiance = albedo), seen square by an orthographic camera at 32 x 32, 64 spp.
    Returns {engine: 4 x 4 block means (4, 4, 3)}."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.world((1, 1, 1))
    mat = bpy.data.materials.new("M")
    nt = mat.node_tree
    bsdf = nt.nodes['Principled BSDF']
    bsdf.inputs['Specular IOR Level'].default_value = 0
    nt.links.new(colour(nt), bsdf.inputs['Base Color'])
    scenes.plane("P", size=2, materials=(mat,)).data.uv_layers.new(name='UVMap')
    rendering.fair_scene_settings(sc)
    blocks = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device, sc.cycles.max_bounces = 64, False, 'CPU', 0
        sc.dacrt.samples, sc.dacrt.max_bounces = 64, 0
        img = scenes.render_rgba(sc)
        blocks[engine] = img[..., :3].reshape(4, 8, 4, 8, 3).mean(axis=(1, 3))
    return blocks


@pytest.mark.parametrize("chain", [multiply, alpha_mask, noise_mask, mapped_linear], ids=lambda f: f.__name__)
def test_two_textures_in_one_colour_match_cycles(tmp_path, chain):
    def colour(nt):
        ia, ib = _images(tmp_path)
        ta, tb = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeTexImage')
        ta.image, tb.image = ia, ib
        ta.interpolation = tb.interpolation = 'Closest'
        return chain(nt, ta, tb)
    blocks = albedo_plane_blocks(colour)
    diff = np.abs(blocks['DACRT'] - blocks['CYCLES'])
    # 64 samples of a world-lit albedo: a block's mean is within ~0.002 of Cycles'
    assert diff.max() < 0.005, (diff.max(), blocks)
