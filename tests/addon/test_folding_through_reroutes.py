"""A Mix Shader's Fac that folds to a constant on its way through a Reroute, a node group (a
Value inside it, or an input's own value) or a muted node: Cycles flattens groups and reroutes
and passes muted nodes along their internal links before its ConstantFolder runs, so the Mix of
Fac 0 there is the Diffuse alone (bit-identical), as with the Value linked straight to the Fac.
nodegraph.Folder had read every constant that crossed such a socket as unknown, so DACRT said
three false messages (the light's Glossy visibility, Filter Glossy, "Glossy BSDF as diffuse")
for a Glossy Cycles drops. A constant crossing sockets of its own type stays that constant; one
converted on the way (a float through a group's Color socket) arrives converted.

DACRT's messages at 1 sample, 32x24; Cycles at 16 samples where it renders."""
import math

import bpy
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes
from .test_message_scope import mix_and_diffuse_images

GLOSSY_VIS = "ray visibility Glossy"
FILTER_GLOSSY = "Filter Glossy"
GLOSSY_AS_DIFFUSE = "Glossy BSDF as diffuse"
KEYS = (GLOSSY_VIS, FILTER_GLOSSY, GLOSSY_AS_DIFFUSE)


def _float_group(nt, name, body):
    """A Group node in nt whose tree has a Float input 'In' and a Float output 'Fac', its insides
    made by body(group tree, Group Input, Group Output)."""
    grp = bpy.data.node_groups.new(name, 'ShaderNodeTree')
    grp.interface.new_socket('In', in_out='INPUT', socket_type='NodeSocketFloat')
    grp.interface.new_socket('Fac', in_out='OUTPUT', socket_type='NodeSocketFloat')
    gi, go = grp.nodes.new('NodeGroupInput'), grp.nodes.new('NodeGroupOutput')
    body(grp, gi, go)
    gn = nt.nodes.new('ShaderNodeGroup')
    gn.node_tree = grp
    return gn


def _value(nt, value):
    v = nt.nodes.new('ShaderNodeValue')
    v.outputs[0].default_value = value
    return v.outputs[0]


def _reroute(nt, out):
    r = nt.nodes.new('NodeReroute')
    nt.links.new(out, r.inputs[0])
    return r.outputs[0]


def _fac(nt, case, value):
    """The output feeding the Mix's Fac for each way of reaching a constant `value`."""
    if case == 'value':                              # the control: linked straight
        return _value(nt, value)
    if case == 'reroute':
        return _reroute(nt, _reroute(nt, _value(nt, value)))
    if case == 'group_value':                        # a Value inside a group, out through its output
        return _float_group(nt, 'GV', lambda g, gi, go: g.links.new(_value(g, value), go.inputs[0])).outputs[0]
    if case == 'group_input_default':                # the Group node's own input value, passed through
        gn = _float_group(nt, 'GI', lambda g, gi, go: g.links.new(gi.outputs[0], go.inputs[0]))
        gn.inputs[0].default_value = value
        return gn.outputs[0]
    if case == 'group_reroute_inside':               # a Value outside, through a reroute inside a group
        gn = _float_group(nt, 'GR', lambda g, gi, go: g.links.new(_reroute(g, gi.outputs[0]), go.inputs[0]))
        nt.links.new(_value(nt, value), gn.inputs[0])
        return gn.outputs[0]
    if case == 'muted_math':                         # a muted Math (value + 1) passes its first input
        m = nt.nodes.new('ShaderNodeMath')
        m.operation, m.mute = 'ADD', True
        m.inputs[1].default_value = 1.0
        nt.links.new(_value(nt, value), m.inputs[0])
        return m.outputs[0]
    if case == 'math_via_reroute':                   # Math of a rerouted Value x 1 (Cycles folds x * 1)
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = 'MULTIPLY'
        m.inputs[1].default_value = 1.0
        nt.links.new(_reroute(nt, _value(nt, value)), m.inputs[0])
        return m.outputs[0]
    raise ValueError(case)


CASES = ['value', 'reroute', 'group_value', 'group_input_default', 'group_reroute_inside', 'muted_math',
         'math_via_reroute']


def _material(case, value):
    """Mix Shader(Diffuse, Glossy roughness 0.3) whose Fac reads `value` by way of `case`."""
    m = bpy.data.materials.new(case)
    nt = m.node_tree
    for n in [n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED']:
        nt.nodes.remove(n)
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
    d, g = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeBsdfGlossy')
    g.inputs['Roughness'].default_value = 0.3
    mx = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(d.outputs[0], mx.inputs[1])
    nt.links.new(g.outputs[0], mx.inputs[2])
    nt.links.new(_fac(nt, case, value), mx.inputs['Fac'])
    nt.links.new(mx.outputs[0], out.inputs['Surface'])
    return m


def _scene(sc, m):
    scenes.world((0.2, 0.2, 0.2), 1.0)
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    lamp = scenes.light('POINT', 300, location=(1, -1, 3))
    lamp.visible_glossy = False
    scenes.plane(size=8, materials=[m])
    scenes.uv_sphere(location=(0, 0, 1), materials=[m])
    rendering.matched(sc, 1, bounces=1)
    sc.cycles.samples = 16


def _said(sc, said):
    said.clear()
    sc.render.engine = 'DACRT'
    bpy.ops.render.render()
    return {k: [t for t in said if k in t] for k in KEYS}


@pytest.mark.parametrize('case', CASES)
def test_glossy_dropped_by_a_fac_folding_to_0_is_not_said(scene, said, case):
    _scene(scene, _material(case, 0.0))
    got = _said(scene, said)
    assert not any(got.values()), got


@pytest.mark.parametrize('case', CASES)
def test_glossy_kept_by_a_fac_folding_to_1_is_said(scene, said, case):
    """The same chains at 1 keep the Glossy (the second shader): all three are said, so the
    folding did not drop a shader Cycles renders."""
    _scene(scene, _material(case, 1.0))
    got = _said(scene, said)
    assert all(got.values()), got


def test_float_through_a_color_group_socket_arrives_converted(scene):
    """A constant crossing a socket of another type is converted there (a float 0.25 through a
    group's Color socket arrives as grey 0.25), not left unknown nor passed as the float."""
    from addon import nodegraph
    m = bpy.data.materials.new('conv')
    nt = m.node_tree
    grp = bpy.data.node_groups.new('C', 'ShaderNodeTree')
    grp.interface.new_socket('In', in_out='INPUT', socket_type='NodeSocketColor')
    grp.interface.new_socket('Out', in_out='OUTPUT', socket_type='NodeSocketColor')
    gi, go = grp.nodes.new('NodeGroupInput'), grp.nodes.new('NodeGroupOutput')
    grp.links.new(gi.outputs[0], go.inputs[0])
    gn = nt.nodes.new('ShaderNodeGroup')
    gn.node_tree = grp
    nt.links.new(_value(nt, 0.25), gn.inputs[0])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    nt.links.new(gn.outputs[0], mix.inputs['A'])
    st = nodegraph.Folder().input_state(nodegraph.input_by_id(mix, 'A_Color'))
    assert isinstance(st, nodegraph._Const)
    assert st.value == pytest.approx((0.25, 0.25, 0.25))


def test_cycles_renders_the_rerouted_mix_as_the_diffuse_alone(scene, said, tmp_path):
    """What backs "nothing of the Glossy is said": Cycles' image of the Mix whose Fac 0 comes
    through reroutes is bit-identical to the Diffuse linked to the output, and DACRT's matches."""
    m = _material('reroute', 0.0)
    _scene(scene, m)
    images = mix_and_diffuse_images(scene, m, tmp_path, said)
    assert np.array_equal(images['mix', 'CYCLES'], images['diffuse', 'CYCLES'])
    assert np.array_equal(images['mix', 'DACRT'], images['diffuse', 'DACRT'])
    c, d = images['mix', 'CYCLES'][..., :3].mean(), images['mix', 'DACRT'][..., :3].mean()
    assert d == pytest.approx(c, rel=0.03)
