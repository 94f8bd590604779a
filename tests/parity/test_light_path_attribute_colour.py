"""A colour that a Light Path ray-type output chooses between a mesh's Color Attribute and a
constant (a Mix by Ray Depth): the builds per ray kind (export/rayvariants.py) differ only in
how the albedo follows the attribute (MaterialBuilder._extra), which the materials' fields do
not hold, so they had been taken for one: every ray saw the bounce rays' constant, the camera's
Diffuse Color 0.31 / 0.24 / 0.49 where Cycles shows the attribute's 0.42 / 0.47 / 0.56, with no
word. A variant's triangle copies share the attribute's colours, so such a material is built
once, its Light Path read at its own value, and said. With a constant in place of the attribute
the builds differ in their fields: per ray kind, as Cycles, unsaid (the control)."""
import os

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .normalpass import normal_pass_scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _diffuse_colour(tmp_path, attribute):
    sc = normal_pass_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.5, location=(0, 0, 1), segments=8, ring_count=6)
    me = bpy.context.object.data
    cols = np.random.default_rng(1).random((len(me.vertices), 4)).astype(np.float32)
    cols[:, 3] = 1.0
    me.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT').data.foreach_set('color', cols.ravel())
    mat = bpy.data.materials.new('Depth mix')
    nt = mat.node_tree
    nt.nodes.clear()
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], nt.nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    mix.inputs['B'].default_value = (0.35, 0.27, 0.56, 1.0)
    if attribute:
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = 'Col'
        nt.links.new(a.outputs['Color'], mix.inputs['A'])
    else:
        mix.inputs['A'].default_value = (0.9, 0.1, 0.1, 1.0)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Ray Depth'], mix.inputs['Factor'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    me.materials.append(mat)
    scenes.world((0.3, 0.3, 0.3), 1.0)
    sc.view_layers[0].use_pass_diffuse_color = True
    sc.cycles.samples = sc.dacrt.samples = 16
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        ch = scenes.read_exr(scenes.render_exr(os.path.join(tmp_path, f'{engine}.exr'), sc, multilayer=True))
        got[engine] = np.stack([ch[k] for c in 'RGB' for k in ch if k.startswith('ViewLayer.Diff') and
                                k.endswith('.' + c)], -1)
    seen = got['CYCLES'].sum(-1) > 0
    return got['CYCLES'][seen].mean(0), got['DACRT'][seen].mean(0)


@pytest.mark.parametrize('attribute', [True, False])
def test_light_path_choice_of_an_attribute_colour_is_cycles_or_said(tmp_path, said, attribute):
    cycles, dacrt = _diffuse_colour(tmp_path, attribute)
    told = any("'Depth mix'" in s and "'Light Path' node" in s for s in said)
    if attribute:
        assert told, (cycles, dacrt, said)
    else:
        assert not told and np.allclose(dacrt, cycles, rtol=0.02), (cycles, dacrt, said)
