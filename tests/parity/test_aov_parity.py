"""Shader AOVs fed by nodes evaluated per object or per point agree with Cycles: Object Info
Random (through a Color Ramp), Location and Index, Geometry Position, Texture Coordinate
Generated and Object, a per-vertex Color Attribute, Light Path Is Camera Ray, on a floor, a
cube, a ball and a linked duplicate of the cube (its own Random). Each was written as 0 before.
Tiny frames (32x24), 16 samples, the same pixel filter in both engines."""
import math
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

AOVS = {'rand': 'VALUE', 'ramp': 'COLOR', 'loc': 'COLOR', 'index': 'VALUE', 'pos': 'COLOR', 'gen': 'COLOR',
        'obj': 'COLOR', 'paint': 'COLOR', 'cam': 'COLOR'}


def _aov(nt, name, output, socket):
    node = nt.nodes.new('ShaderNodeOutputAOV')
    node.aov_name = name
    nt.links.new(output, node.inputs[socket])


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 2), rotation=(math.radians(75), 0, 0))
    mat = scenes.diffuse("Grey", (0.5, 0.5, 0.5))
    nt = mat.node_tree
    info, geo, tc = (nt.nodes.new(t) for t in ('ShaderNodeObjectInfo', 'ShaderNodeNewGeometry', 'ShaderNodeTexCoord'))
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (0.1, 0.8, 0.2, 1.0)
    ramp.color_ramp.elements[1].color = (0.9, 0.1, 0.6, 1.0)
    nt.links.new(info.outputs['Random'], ramp.inputs['Fac'])
    attr = nt.nodes.new('ShaderNodeVertexColor')
    attr.layer_name = 'paint'
    lp = nt.nodes.new('ShaderNodeLightPath')
    for name, output in (('rand', info.outputs['Random']), ('ramp', ramp.outputs['Color']),
                         ('loc', info.outputs['Location']), ('index', info.outputs['Object Index']),
                         ('pos', geo.outputs['Position']), ('gen', tc.outputs['Generated']),
                         ('obj', tc.outputs['Object']), ('paint', attr.outputs['Color']),
                         ('cam', lp.outputs['Is Camera Ray'])):
        _aov(nt, name, output, 'Value' if AOVS[name] == 'VALUE' else 'Color')
    floor = scenes.plane("Floor", size=8, materials=[mat])
    layer = floor.data.color_attributes.new('paint', 'FLOAT_COLOR', 'POINT')
    for i, d in enumerate(layer.data):          # a different colour at each corner
        d.color = ((0.9, 0.1, 0.1, 1), (0.1, 0.9, 0.1, 1), (0.1, 0.1, 0.9, 1), (0.9, 0.9, 0.1, 1))[i % 4]
    cube = scenes.cube("Cube", size=1, location=(1, 0, 0.5), materials=[mat])
    cube.pass_index = 3
    twin = bpy.data.objects.new("Twin", cube.data)   # a linked duplicate: its own name, its own Random
    twin.location = (-1.5, 1.0, 0.5)
    sc.collection.objects.link(twin)
    scenes.uv_sphere("Ball", radius=0.6, location=(-0.2, 1.5, 0.6), materials=[mat])
    scenes.world((0.3, 0.4, 0.6), 1.0)
    vl = sc.view_layers[0]
    for name, kind in AOVS.items():
        a = vl.aovs.add()
        a.name, a.type = name, kind
    return sc


def test_per_object_and_per_point_aovs_match_cycles(tmp_path):
    sc = _scene()
    spec = SimpleNamespace(cycles_samples=16, dacrt_samples=16, bounces=1, clamp=(0.0, 0.0),
                           filter_type='BLACKMAN_HARRIS', filter_width=1.5)
    got = rendering.render_layers(sc, spec, tmp_path)
    c, d = got['CYCLES'], got['DACRT']
    for name, kind in AOVS.items():
        channels = 'X' if kind == 'VALUE' else 'RGBA'
        for ch in channels:
            key = f"ViewLayer.{name}.{ch}"
            cm, dm = float(c[key].mean()), float(d[key].mean())
            # means: within 1% of the pass's scale (positions reach a few metres)
            scale = max(float(np.abs(c[key]).max()), 0.05)
            assert abs(dm - cm) < 0.01 * scale, (key, dm, cm)
            diff = np.abs(d[key] - c[key])
            assert diff.mean() < 0.02 * scale, (key, diff.mean(), scale)
        if name != 'index':
            assert np.abs(d[f"ViewLayer.{name}.{channels[0]}"]).max() > 0.05, name     # not blank
    # the two cubes' Random differ, and each is Cycles'
    rand_c, rand_d = c["ViewLayer.rand.X"], d["ViewLayer.rand.X"]
    assert len(np.unique(np.round(rand_c, 3))) >= 4
    assert np.mean(np.abs(rand_d - rand_c) < 1e-3) > 0.8          # (edges: the samples split)
