"""Shader AOVs fed by chains that read the view agree with Cycles: Texture Coordinate
Reflection, Geometry Incoming and Layer Weight Facing are computed per point with the camera
ray's direction (AOVs are written by camera rays only). A smooth sphere and a tilted plane, and
a sheet of 70% Transparent over part of them whose shader writes the same AOVs (so the AOVs of
the surfaces behind it add, as Cycles writes every surface's up to the first one at least as
opaque as the Pass Alpha Threshold): a COLOR AOV of Reflection x 0.5 + 0.5, a VALUE AOV of
Facing + Incoming's Z. They had been read at the sockets' own values (the vector 0, Facing its
average), said: the colour AOV's pixels 0.12 off on average, 38% of them by more than 0.1
(now 0.002 and none)."""
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering
from tests.parity.test_index_passes import _sheet

pytestmark = pytest.mark.usefixtures('parity_addon')


def _view_aovs(mat):
    """AOV Output nodes 'refl' (Reflection x 0.5 + 0.5) and 'facing' (Layer Weight Facing +
    Incoming.z) in mat's tree."""
    nt = mat.node_tree
    tc = nt.nodes.new('ShaderNodeTexCoord')
    refl = nt.nodes.new('ShaderNodeOutputAOV')
    refl.aov_name = 'refl'
    nt.links.new(scenes.as_colour(nt, tc.outputs['Reflection']), refl.inputs['Color'])
    lw = nt.nodes.new('ShaderNodeLayerWeight')
    lw.inputs['Blend'].default_value = 0.4
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(geo.outputs['Incoming'], sep.inputs[0])
    add = nt.nodes.new('ShaderNodeMath')
    add.operation = 'ADD'
    nt.links.new(lw.outputs['Facing'], add.inputs[0])
    nt.links.new(sep.outputs['Z'], add.inputs[1])
    facing = nt.nodes.new('ShaderNodeOutputAOV')
    facing.aov_name = 'facing'
    nt.links.new(add.outputs[0], facing.inputs['Value'])


def test_view_reading_aovs_match_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    scenes.camera((0.5, -6.0, 2.0), rotation=(1.25, 0.0, 0.08), lens=35)
    scenes.world((1.0, 1.0, 1.0), 1.0)
    vl = sc.view_layers[0]
    for name, kind in (('refl', 'COLOR'), ('facing', 'VALUE')):
        aov = vl.aovs.add()
        aov.name, aov.type = name, kind
    solid = scenes.diffuse('Solid', (0.6, 0.6, 0.6))
    sheet = _sheet('Sheet', 0.7, (0.5, 0.5, 0.5))
    for mat in (solid, sheet):
        _view_aovs(mat)
    scenes.uv_sphere('S', radius=1.0, location=(-1.2, 0, 0.2), materials=(solid,))
    plane = scenes.plane('P', size=2.0, location=(1.4, 0, 0.2), materials=(solid,))
    plane.rotation_euler = (1.1, 0.3, 0.2)
    front = scenes.plane('F', size=1.5, location=(-0.6, -2.0, 0.6), materials=(sheet,))
    front.rotation_euler = (1.3, 0.0, 0.4)
    spec = SimpleNamespace(cycles_samples=64, dacrt_samples=64, bounces=0, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    got = {}
    for engine, exr in rendering.render_layers(sc, spec, tmp_path).items():
        got[engine] = {'refl': np.stack([exr[f"{vl.name}.refl.{c}"] for c in 'RGB'], axis=-1),
                       'facing': exr[f"{vl.name}.facing.X"]}
    c, d = got['CYCLES'], got['DACRT']
    assert np.ptp(c['refl'][..., 2]) > 0.3 and np.ptp(c['facing']) > 0.3       # the vectors vary
    for key in ('refl', 'facing'):
        # (the sheet's transparency is picked per sample and silhouettes split a pixel's
        # samples: the pixels' mean difference, not each pixel's)
        diff = np.abs(d[key] - c[key])
        assert diff.mean() < 0.01 and np.mean(diff > 0.1) < 0.03, (key, diff.mean(), np.mean(diff > 0.1))
