"""The Normal pass where a bent surface has no closure agrees with Cycles: a Principled BSDF
bent by a World-space Normal Map, its Base Color a Checker of black and grey, Specular IOR
Level 0. Where the colour is black Cycles allocates no closure (under CLOSURE_WEIGHT_CUTOFF)
and its average normal is the unbent sd->N. Mean per-pixel difference from Cycles within 0.03
(fuzz 9020: the black squares had kept the bent normal, 0.43 off on average)."""
import os

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_normal_pass_where_the_colour_is_black_matches_cycles(tmp_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 1), rotation=(1.4, 0, 0))
    mat = scenes.principled('P', (0.5, 0.5, 0.5))
    nt = mat.node_tree
    p = nt.nodes['Principled BSDF']
    p.inputs['Specular IOR Level'].default_value = 0.0
    checker = nt.nodes.new('ShaderNodeTexChecker')
    checker.inputs['Scale'].default_value = 3.0
    checker.inputs['Color1'].default_value = (0.0, 0.0, 0.0, 1.0)
    checker.inputs['Color2'].default_value = (0.6, 0.6, 0.6, 1.0)
    nt.links.new(checker.outputs['Color'], p.inputs['Base Color'])
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nmap.space = 'WORLD'
    nmap.inputs['Strength'].default_value = 0.8
    nmap.inputs['Color'].default_value = (0.1, 0.2, 0.9, 1.0)
    nt.links.new(nmap.outputs['Normal'], p.inputs['Normal'])
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=1.5, location=(0, 0, 1))
    bpy.context.object.data.materials.append(mat)
    scenes.world((0.3, 0.3, 0.3), 1.0)
    sc.view_layers[0].use_pass_normal = True
    sc.cycles.samples = sc.dacrt.samples = 16
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        ch = scenes.read_exr(scenes.render_exr(os.path.join(tmp_path, f'{engine}.exr'), sc, multilayer=True))
        got[engine] = np.stack([ch[f'ViewLayer.Normal.{c}'] for c in 'XYZ'], -1)
    c, d = got['CYCLES'], got['DACRT']
    seen = np.abs(c).sum(-1) > 0
    assert seen.sum() > 200
    diff = np.abs(c - d).max(-1)[seen]
    assert diff.mean() < 0.03, (diff.mean(), np.mean(diff > 0.1))
