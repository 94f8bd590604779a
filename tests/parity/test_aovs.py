"""Shader AOVs agree with Cycles: AOV Output nodes in the Cornell box's materials (one inside a
node group, one fed by a Math node, two of one name adding up, one from an image), in the
world, and on two sheets that are
partly transparent, where Cycles writes every surface's AOVs up to the first one at least as
opaque as the Pass Alpha Threshold. A COLOR and a VALUE AOV; each pass's channel means, and its
pixels, against Cycles' at the same pixel filter."""
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering
from tests.parity.test_index_passes import _sheet

pytestmark = pytest.mark.usefixtures('parity_addon')


def _aov(mat, name, color=None, value=None, group=False):
    """An AOV Output node named `name` in mat's tree (inside a node group when group) with a
    constant colour and value; a value of ('MULTIPLY', a, b) comes from a Math node."""
    nt = mat.node_tree
    tree = nt
    if group:
        tree = bpy.data.node_groups.new(f"{mat.name}AOV", 'ShaderNodeTree')
        g = nt.nodes.new('ShaderNodeGroup')
        g.node_tree = tree
    node = tree.nodes.new('ShaderNodeOutputAOV')
    node.aov_name = name
    if color is not None:
        node.inputs['Color'].default_value = (*color, 1.0)
    if isinstance(value, tuple):
        math = tree.nodes.new('ShaderNodeMath')
        math.operation, math.inputs[0].default_value, math.inputs[1].default_value = value
        tree.links.new(math.outputs[0], node.inputs['Value'])
    elif value is not None:
        node.inputs['Value'].default_value = value
    return node


def _aov_passes(sc, tmp_path, channels):
    """(Cycles', DACRT's) {AOV name: its pass, (H, W, C) of the channels named, (H, W) for one}
    of the scene's first view layer, both engines at the same 64 spp, one bounce."""
    vl = sc.view_layers[0]
    spec = SimpleNamespace(cycles_samples=64, dacrt_samples=64, bounces=1, clamp=(0.0, 0.0),
                           filter_type='BLACKMAN_HARRIS', filter_width=1.5)

    def passes(exr):
        return {name: exr[f"{vl.name}.{name}.{cs}"] if len(cs) == 1 else
                np.stack([exr[f"{vl.name}.{name}.{c}"] for c in cs], axis=-1) for name, cs in channels.items()}
    got = {engine: passes(exr) for engine, exr in rendering.render_layers(sc, spec, tmp_path).items()}
    return got['CYCLES'], got['DACRT']


def _pixels_agree(key, dacrt, cycles):
    """The same values away from edges, where the filter's samples split."""
    diff = np.abs(dacrt - cycles)
    assert diff.mean() < 0.01 and np.mean(diff > 0.05) < 0.03, (key, diff.mean(), np.mean(diff > 0.05))


def test_shader_aovs_match_cycles(tmp_path):
    sc = rendering.small_cornell()
    vl = sc.view_layers[0]
    tint = vl.aovs.add()
    tint.name, tint.type = "tint", 'COLOR'
    mask = vl.aovs.add()
    mask.name, mask.type = "mask", 'VALUE'
    mats = bpy.data.materials
    _aov(mats["White"], "tint", color=(0.2, 0.4, 0.6), value=0.25)
    _aov(mats["Red"], "tint", color=(0.9, 0.1, 0.1))
    _aov(mats["Red"], "mask", value=('MULTIPLY', 0.5, 1.5))          # 0.75, from a Math node
    _aov(mats["Green"], "mask", value=0.5, group=True)
    _aov(mats["Green"], "mask", value=0.25)                            # adds up to 0.75
    # sheets: one mostly opaque (its own AOVs end the pass), one mostly
    # transparent (its AOVs and those of the red wall behind it add up)
    for name, transparency, x in (("Card", 0.3, 0.35), ("Veil", 0.8, -0.75)):
        mat = _sheet(name, transparency, (0.3, 0.6, 0.9))
        _aov(mat, "tint", color=(0.0, 0.5, 1.0))
        _aov(mat, "mask", value=1.0)
        sheet = scenes.plane(name, size=0.5, location=(x, -0.8, 0.8), materials=[mat])
        sheet.rotation_euler = (np.pi / 2, 0.0, 0.0)                   # facing the camera
    # a poster on the back wall whose AOVs come from a 4x4 image (tint its colour, mask twice
    # its colour's luminance through a Math node), read on its UV map
    texels = np.zeros((4, 4, 4), np.float32)
    texels[..., 3] = 1.0
    texels[..., 0] = np.linspace(0.0, 1.0, 4)[None, :]
    texels[..., 1] = np.linspace(1.0, 0.0, 4)[:, None]
    texels[..., 2] = 0.5
    poster_mat = scenes.diffuse("Poster", (0.6, 0.6, 0.6))
    nt = poster_mat.node_tree
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = scenes.float_image("PosterImage", texels), 'Closest'
    tint_out = _aov(poster_mat, "tint")
    nt.links.new(tex.outputs['Color'], tint_out.inputs['Color'])
    mask_out = _aov(poster_mat, "mask", value=('MULTIPLY', 1.0, 2.0))
    nt.links.new(tex.outputs['Color'], mask_out.inputs['Value'].links[0].from_node.inputs[0])
    poster = scenes.plane("Poster", size=0.6, location=(0.1, 0.98, 1.3), materials=[poster_mat])
    poster.rotation_euler = (np.pi / 2, 0.0, 0.0)
    poster.data.uv_layers.new(name="UVMap").data.foreach_set("uv", [0, 0, 1, 0, 1, 1, 0, 1])
    # the world, seen through the box's open front
    world = sc.world.node_tree.nodes.new('ShaderNodeOutputAOV')
    world.aov_name, world.inputs['Color'].default_value = "tint", (0.3, 0.3, 0.0, 1.0)
    world = sc.world.node_tree.nodes.new('ShaderNodeOutputAOV')
    world.aov_name, world.inputs['Value'].default_value = "mask", 0.125
    c, d = _aov_passes(sc, tmp_path, {'tint': "RGBA", 'mask': "X"})
    # the AOVs are there and tell the surfaces apart (not a blank or a copy of another pass)
    assert c['tint'][..., 3].max() > 0.99 and c['tint'][..., 2].max() > 0.6 and c['mask'].max() > 0.99
    assert np.ptp(c['mask']) > 0.5 and np.ptp(c['tint'][..., 0]) > 0.5
    for key in ('tint', 'mask'):
        cm = c[key].reshape(-1, 1 if key == 'mask' else 4).mean(axis=0)
        dm = d[key].reshape(-1, 1 if key == 'mask' else 4).mean(axis=0)
        assert np.all(np.abs(dm - cm) < 0.01 * np.maximum(cm, 0.05)), (key, dm, cm)
        _pixels_agree(key, d[key], c[key])
    # the poster's image: green above 0.8 is written by nothing else
    assert min(np.sum(e['tint'][..., 1] > 0.8) for e in (c, d)) >= 3
    # the mostly transparent sheet adds its value (1) to the red wall's behind it (0.75)
    assert c['mask'].max() > 1.5 and d['mask'].max() > 1.5


def test_procedural_aovs_match_cycles(tmp_path):
    """AOVs fed by procedural textures (addon/export/procedurals.py) are computed per shading
    point: a COLOR AOV of a Noise's colour on Generated coordinates and a VALUE AOV of a Voronoi
    distance on Object coordinates, on the Cornell box's back wall (they were 0, reported)."""
    sc = rendering.small_cornell()
    vl = sc.view_layers[0]
    for name, kind in (("grain", 'COLOR'), ("cells", 'VALUE')):
        aov = vl.aovs.add()
        aov.name, aov.type = name, kind
    mat = scenes.diffuse("Wall", (0.7, 0.7, 0.7))
    nt = mat.node_tree
    noise = nt.nodes.new('ShaderNodeTexNoise')
    noise.inputs['Scale'].default_value = 3.0
    nt.links.new(noise.outputs['Color'], _aov(mat, "grain").inputs['Color'])
    coords = nt.nodes.new('ShaderNodeTexCoord')
    cells = nt.nodes.new('ShaderNodeTexVoronoi')
    cells.inputs['Scale'].default_value = 4.0
    nt.links.new(coords.outputs['Object'], cells.inputs['Vector'])
    nt.links.new(cells.outputs['Distance'], _aov(mat, "cells").inputs['Value'])
    wall = scenes.plane("Wall", size=1.6, location=(0.0, 0.97, 1.0), materials=[mat])
    wall.rotation_euler = (np.pi / 2, 0.0, 0.0)
    c, d = _aov_passes(sc, tmp_path, {'grain': "RGB", 'cells': "X"})
    assert np.ptp(c['cells']) > 0.3 and np.ptp(c['grain'][..., 0]) > 0.3     # the patterns show
    for key in ('grain', 'cells'):
        _pixels_agree(key, d[key], c[key])


def test_procedural_aov_reading_light_path_matches_cycles(tmp_path):
    """An AOV's procedural chain that also reads Light Path is computed per point, the Light Path
    outputs as the camera rays that write AOVs read them: a Checker's colour mixed with black by
    Is Camera Ray (1) and a Noise's Fac plus 2 x Is Diffuse Ray (0), on the Cornell box's back
    wall. The chains had been read at the textures' own values, said (fuzz 9010: 0.08x)."""
    sc = rendering.small_cornell()
    vl = sc.view_layers[0]
    for name, kind in (("checks", 'COLOR'), ("grain", 'VALUE')):
        aov = vl.aovs.add()
        aov.name, aov.type = name, kind
    mat = scenes.diffuse("Wall", (0.7, 0.7, 0.7))
    nt = mat.node_tree
    lp = nt.nodes.new('ShaderNodeLightPath')
    checker = nt.nodes.new('ShaderNodeTexChecker')
    checker.inputs['Scale'].default_value = 4.0
    mix = scenes.mix_node(nt, 'MIX', (0.0, 0.0, 0.0), checker.outputs['Color'])
    nt.links.new(lp.outputs['Is Camera Ray'], mix.inputs['Factor'])
    nt.links.new(mix.outputs['Result'], _aov(mat, "checks").inputs['Color'])
    noise = nt.nodes.new('ShaderNodeTexNoise')
    noise.inputs['Scale'].default_value = 3.0
    madd = nt.nodes.new('ShaderNodeMath')
    madd.operation = 'MULTIPLY_ADD'
    nt.links.new(lp.outputs['Is Diffuse Ray'], madd.inputs[0])
    madd.inputs[1].default_value = 2.0
    nt.links.new(noise.outputs['Fac'], madd.inputs[2])
    nt.links.new(madd.outputs[0], _aov(mat, "grain").inputs['Value'])
    wall = scenes.plane("Wall", size=1.6, location=(0.0, 0.97, 1.0), materials=[mat])
    wall.rotation_euler = (np.pi / 2, 0.0, 0.0)
    c, d = _aov_passes(sc, tmp_path, {'checks': "RGB", 'grain': "X"})
    assert np.ptp(c['checks'][..., 0]) > 0.3 and np.ptp(c['grain']) > 0.2     # the patterns show
    for key in ('checks', 'grain'):
        _pixels_agree(key, d[key], c[key])
