"""Messages about a material's shaders say only what Cycles renders of it: the shaders that reach
the active Cycles Material Output (reflectors.rendered_closures, nodegraph.closure_link:
reroutes, muted nodes passed through, groups through their active Group Output, a Mix Shader of
constant Fac <= 0 / >= 1 down to one shader), not every node in the tree:

- the light's Glossy ray visibility message (reflectors.has_glossy_closure, which had looked at
  every node): Cycles renders a Diffuse beside an unlinked Glossy bit-identically with the
  light's Glossy visibility on or off, and DACRT (which matches it) need not say anything;

DACRT's messages at 1 sample, 32x24; where Cycles renders, 16 samples, compared at one seed."""
import math

import bpy
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes

GLOSSY_VIS = "ray visibility Glossy"
APPROX = "material(s) approximated"
GLOSSY_AS_DIFFUSE = "Glossy BSDF as diffuse"


def _folded(nt, value, times):
    """A Math node's output folding to value * times (a Value node times a constant)."""
    v, mul = nt.nodes.new('ShaderNodeValue'), nt.nodes.new('ShaderNodeMath')
    v.outputs[0].default_value, mul.operation = value, 'MULTIPLY'
    mul.inputs[1].default_value = times
    nt.links.new(v.outputs[0], mul.inputs[0])
    return mul.outputs[0]


def _group(glossy_linked):
    """A node group holding a Diffuse and a Glossy BSDF, its output the Glossy where
    glossy_linked, else the Diffuse (the Glossy left unused inside)."""
    grp = bpy.data.node_groups.new('G', 'ShaderNodeTree')
    grp.interface.new_socket('Shader', in_out='OUTPUT', socket_type='NodeSocketShader')
    go = grp.nodes.new('NodeGroupOutput')
    d, g = grp.nodes.new('ShaderNodeBsdfDiffuse'), grp.nodes.new('ShaderNodeBsdfGlossy')
    grp.links.new((g if glossy_linked else d).outputs[0], go.inputs[0])
    return grp


def _material(case):
    """(material, whether a Glossy BSDF renders in Cycles) for each case: a Diffuse and a Glossy
    BSDF (roughness 0.3), only some reaching the Cycles output."""
    m = bpy.data.materials.new(case)
    nt = m.node_tree
    for n in [n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED']:
        nt.nodes.remove(n)
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
    surface = out.inputs['Surface']
    d, g = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeBsdfGlossy')
    g.inputs['Roughness'].default_value = 0.3
    if case == 'unlinked':
        nt.links.new(d.outputs[0], surface)
        return m, False
    if case == 'linked':
        nt.links.new(g.outputs[0], surface)
        return m, True
    if case.startswith('mix_'):
        mx = nt.nodes.new('ShaderNodeMixShader')
        first, second = (g, d) if case == 'mix_fac_1_glossy_first' else (d, g)
        nt.links.new(first.outputs[0], mx.inputs[1])
        nt.links.new(second.outputs[0], mx.inputs[2])
        nt.links.new(mx.outputs[0], surface)
        mx.inputs['Fac'].default_value = {'mix_fac_0': 0.0, 'mix_fac_1_glossy_first': 1.0, 'mix_fac_half': 0.5,
                                          'mix_fac_1': 1.0, 'mix_fac_negative': -0.5}.get(case, 0.5)
        if case == 'mix_fac_value_0':               # a Fac Cycles' constant folding makes 0
            nt.links.new(_folded(nt, 0.7, 0.0), mx.inputs['Fac'])
        return m, case in ('mix_fac_half', 'mix_fac_1')
    if case in ('eevee_output', 'cycles_output'):
        o2 = nt.nodes.new('ShaderNodeOutputMaterial')
        glossy_out, diffuse_out = (o2, out) if case == 'eevee_output' else (out, o2)
        glossy_out.target, diffuse_out.target = ('EEVEE', 'CYCLES') if case == 'eevee_output' else ('CYCLES', 'EEVEE')
        nt.links.new(g.outputs[0], glossy_out.inputs['Surface'])
        nt.links.new(d.outputs[0], diffuse_out.inputs['Surface'])
        return m, case == 'cycles_output'
    if case == 'muted_mix':                         # a muted Mix passes its first shader through
        mx = nt.nodes.new('ShaderNodeMixShader')
        mx.mute = True
        mx.inputs['Fac'].default_value = 1.0
        nt.links.new(d.outputs[0], mx.inputs[1])
        nt.links.new(g.outputs[0], mx.inputs[2])
        nt.links.new(mx.outputs[0], surface)
        return m, False
    if case in ('group_unused', 'group_glossy'):
        gn = nt.nodes.new('ShaderNodeGroup')
        gn.node_tree = _group(case == 'group_glossy')
        nt.links.new(gn.outputs[0], surface)
        return m, case == 'group_glossy'
    raise ValueError(case)


CASES = ['unlinked', 'linked', 'mix_fac_0', 'mix_fac_value_0', 'mix_fac_negative', 'mix_fac_1_glossy_first',
         'mix_fac_half', 'mix_fac_1', 'eevee_output', 'cycles_output', 'muted_mix', 'group_unused',
         'group_glossy']


def _scene(sc, m, samples=1):
    scenes.world((0.2, 0.2, 0.2), 1.0)
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    lamp = scenes.light('POINT', 300, location=(1, -1, 3))
    lamp.visible_glossy = False
    scenes.plane(size=8, materials=[m])
    scenes.uv_sphere(location=(0, 0, 1), materials=[m])
    rendering.matched(sc, samples, bounces=1)
    sc.cycles.samples = 16
    return lamp


def _said(sc, said, *keys):
    said.clear()
    sc.render.engine = 'DACRT'
    bpy.ops.render.render()
    return {k: [t for t in said if k in t] for k in keys}


@pytest.mark.parametrize('case', CASES)
def test_glossy_visibility_said_only_where_glossy_renders(scene, said, case):
    m, glossy = _material(case)
    _scene(scene, m)
    got = _said(scene, said, GLOSSY_VIS)[GLOSSY_VIS]
    assert len(got) == (1 if glossy else 0), got


@pytest.mark.parametrize('case', ['unlinked', 'mix_fac_0', 'linked'])
def test_cycles_image_and_glossy_visibility(scene, said, tmp_path, case):
    """Cycles with the light's Glossy visibility on and off: bit-identical where the Glossy does
    not reach the output (and DACRT says nothing), different where it does."""
    m, glossy = _material(case)
    lamp = _scene(scene, m)
    scene.render.engine = 'CYCLES'
    off = rendering.render_combined(scene, str(tmp_path / 'off.exr'))
    lamp.visible_glossy = True
    on = rendering.render_combined(scene, str(tmp_path / 'on.exr'))
    assert np.array_equal(on, off) != glossy
