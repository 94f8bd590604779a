"""A Mix Shader cut-out whose factor nodes compute from an image (a black-and-white opacity
map's Color, its Alpha through Greater Than, an Invert with the shaders the other way round),
against Cycles: a checker of opaque orange and see-through squares over a green floor, under a
sun and a blue world; 4x4 blocks of the frame. Only a raw Alpha output had been read: these
factors stood at their own value 0.5 (reported), blocks 0.35 off."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def color(nt, tex, m):
    nt.links.new(tex.outputs['Color'], m)


def greater_than(nt, tex, m):
    g = nt.nodes.new('ShaderNodeMath')
    g.operation = 'GREATER_THAN'
    g.inputs[1].default_value = 0.5
    nt.links.new(tex.outputs['Alpha'], g.inputs[0])
    nt.links.new(g.outputs[0], m)


def invert(nt, tex, m):
    i = nt.nodes.new('ShaderNodeInvert')
    nt.links.new(tex.outputs['Color'], i.inputs['Color'])
    nt.links.new(i.outputs[0], m)


@pytest.mark.parametrize("factor, transparent_first", [(color, True), (greater_than, True), (invert, False)],
                         ids=['color', 'greater_than', 'invert_swapped'])
def test_cutout_factor_from_image_nodes_matches_cycles(tmp_path, factor, transparent_first):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.world((0.2, 0.4, 0.9))
    px = np.zeros((4, 4, 4), np.uint8)
    px[::2, ::2, :3] = px[1::2, 1::2, :3] = 255
    px[..., 3] = np.where(px[..., 0] > 0, 255, 0)
    mat, nt, out = scenes._material("Cut")
    for n in list(nt.nodes):
        if n.type != 'OUTPUT_MATERIAL':
            nt.nodes.remove(n)
    dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
    dif.inputs['Color'].default_value = (0.9, 0.3, 0.1, 1)
    tr, mix = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeMixShader')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = bpy.data.images.load(scenes.write_image(tmp_path / "mask.png", px)), 'Closest'
    first, second = (tr, dif) if transparent_first else (dif, tr)
    nt.links.new(first.outputs[0], mix.inputs[1])
    nt.links.new(second.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    factor(nt, tex, mix.inputs['Fac'])
    scenes.plane("Sheet", size=2, materials=(mat,)).data.uv_layers.new(name='UVMap')
    scenes.plane("Floor", size=8, location=(0, 0, -1), materials=(scenes.diffuse("G", (0.2, 0.8, 0.2)),))
    scenes.light('SUN', 2.0)
    rendering.fair_scene_settings(sc)
    blocks = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device = 64, False, 'CPU'
        sc.dacrt.samples = 64
        blocks[engine] = scenes.render_rgba(sc)[..., :3].reshape(4, 8, 4, 8, 3).mean(axis=(1, 3))
    diff = np.abs(blocks['DACRT'] - blocks['CYCLES'])
    assert diff.max() < 0.02, (diff.max(), blocks)           # measured 0.005-0.006 (64 spp noise)
