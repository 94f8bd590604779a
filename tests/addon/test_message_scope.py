"""Messages about a material's shaders say only what Cycles renders of it: the shaders that reach
the active Cycles Material Output (reflectors.rendered_closures, nodegraph.closure_link:
reroutes, muted nodes passed through, groups through their active Group Output, a Mix Shader of
constant Fac <= 0 / >= 1 down to one shader), not every node in the tree:

- the light's Glossy ray visibility message (reflectors.has_glossy_closure, which had looked at
  every node): Cycles renders a Diffuse beside an unlinked Glossy bit-identically with the
  light's Glossy visibility on or off, and DACRT (which matches it) need not say anything;
- the "material(s) approximated" reasons (the material export's shader walk, which had
  evaluated both shaders of a Mix of Fac 0 and said "Glossy BSDF as diffuse" for the one Cycles
  drops; a Principled whose Alpha folds to 0 had its every layer said, though Cycles renders
  only its transparency), and a Principled layer whose weight folds to 0 (a Value, a Math chain);
  a NaN input (a script's) on a node Cycles does not compile (unlinked, on an EEVEE-only output).

DACRT's messages at 1 sample, 32x24; where Cycles renders, 16 samples (DACRT 1), compared at one seed."""
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


@pytest.mark.parametrize('case', CASES)
def test_glossy_as_diffuse_said_only_where_glossy_renders(scene, said, case):
    m, glossy = _material(case)
    _scene(scene, m)
    got = _said(scene, said, APPROX)[APPROX]
    assert len(got) == (1 if glossy else 0), got
    if glossy:
        assert GLOSSY_AS_DIFFUSE in got[0], got


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


def mix_and_diffuse_images(scene, m, tmp_path, said):
    """{(how, engine): image}: material m's Mix rendered by Cycles and DACRT ('mix'), then its
    Diffuse linked straight to the output ('diffuse'); nothing of the Glossy said in any."""
    nt = m.node_tree
    images = {}
    for how in ('mix', 'diffuse'):
        if how == 'diffuse':
            out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
            nt.links.new(next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE').outputs[0], out.inputs['Surface'])
        for engine in ('CYCLES', 'DACRT'):
            scene.render.engine = engine
            said.clear()
            images[how, engine] = rendering.render_combined(scene, str(tmp_path / f'{how}{engine}.exr'))
            assert not any(APPROX in t or GLOSSY_VIS in t for t in said), said
    return images


@pytest.mark.parametrize('case', ['mix_fac_0', 'mix_fac_value_0', 'mix_fac_1_glossy_first'])
def test_dropped_glossy_renders_as_the_diffuse_alone(scene, said, tmp_path, case):
    """A Mix of Fac folding to 0 or 1 renders, in Cycles and in DACRT, as the one shader it keeps
    (bit-identical to the Diffuse linked straight to the output), so nothing of the Glossy is
    said."""
    m, _ = _material(case)
    _scene(scene, m)
    images = mix_and_diffuse_images(scene, m, tmp_path, said)
    for engine in ('CYCLES', 'DACRT'):
        assert np.array_equal(images['mix', engine], images['diffuse', engine]), engine
    c, d = images['mix', 'CYCLES'][..., :3].mean(), images['mix', 'DACRT'][..., :3].mean()
    assert d == pytest.approx(c, rel=0.03)


def _principled(inp, value=0.0):
    """A Principled (coat, sheen, metal, subsurface, transmission all 0.5) whose input `inp`
    reads a Math chain that folds to `value` (a Value node x 0 where value is 0)."""
    m = bpy.data.materials.new(inp)
    nt = m.node_tree
    p = next(n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED')
    for name in ('Coat Weight', 'Sheen Weight', 'Metallic', 'Subsurface Weight', 'Transmission Weight'):
        p.inputs[name].default_value = 0.5
    nt.links.new(_folded(nt, 0.7, value), p.inputs[inp])
    return m, p


LAYER_WORDS = {'Coat Weight': "coat", 'Sheen Weight': "sheen", 'Metallic': "metal",
               'Subsurface Weight': "subsurface", 'Transmission Weight': "transmission"}


@pytest.mark.parametrize('inp', list(LAYER_WORDS))
def test_principled_layer_of_folded_weight_0_unsaid(scene, said, inp):
    """A Principled layer whose weight folds to 0 renders nothing in Cycles (no closure of weight
    0) and is not said; the others (0.5) are."""
    m, _ = _principled(inp)
    _scene(scene, m)
    got = _said(scene, said, APPROX)[APPROX]
    assert len(got) == 1, got
    words = {w for k, w in LAYER_WORDS.items() if f"Principled {w}" in got[0]}
    assert words == set(LAYER_WORDS.values()) - {LAYER_WORDS[inp]}, got


def test_principled_of_alpha_0_renders_only_its_transparency(scene, said, tmp_path):
    """A Principled whose Alpha folds to 0: Cycles scales every layer by it and allocates none,
    so only its white Transparent BSDF renders (bit-identical to a Transparent BSDF alone); its
    coat, sheen, metal, ... had been said as approximated."""
    m, p = _principled('Alpha')
    floor = bpy.data.materials.new('Floor')
    floor.node_tree.nodes.remove(next(n for n in floor.node_tree.nodes if n.type == 'BSDF_PRINCIPLED'))
    floor.node_tree.links.new(floor.node_tree.nodes.new('ShaderNodeBsdfDiffuse').outputs[0],
                              next(n for n in floor.node_tree.nodes if n.type == 'OUTPUT_MATERIAL').inputs[0])
    _scene(scene, floor)
    scenes.uv_sphere(name='Ball', location=(0.5, 0, 1.2), radius=0.8, materials=[m])
    got = _said(scene, said, APPROX, GLOSSY_VIS)
    assert not any(got.values()), got
    scene.render.engine = 'CYCLES'
    principled = rendering.render_combined(scene, str(tmp_path / 'p.exr'))
    nt = m.node_tree
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0],
                 next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    assert np.array_equal(principled, rendering.render_combined(scene, str(tmp_path / 't.exr')))
    scene.render.engine = 'DACRT'
    dacrt = rendering.render_combined(scene, str(tmp_path / 'd.exr'))
    assert dacrt[..., :3].mean() == pytest.approx(principled[..., :3].mean(), rel=0.03)


@pytest.mark.parametrize('case', ['unlinked', 'linked', 'eevee_output', 'cycles_output'])
def test_nan_input_said_only_where_its_node_renders(scene, said, tmp_path, case):
    """A NaN Roughness (a script's) on the Glossy is said only where Cycles compiles the node:
    not when it is left unlinked or on an EEVEE-only output (nothing reads it: Cycles'
    image bit-identical with the Roughness NaN or 0.3)."""
    m, glossy = _material(case)
    rough = next(n for n in m.node_tree.nodes if n.type == 'BSDF_GLOSSY').inputs['Roughness']
    rough.default_value = float('nan')
    _scene(scene, m)
    got = [t for t in _said(scene, said, APPROX)[APPROX] if "NaN" in t]
    assert len(got) == (1 if glossy else 0), got
    if case == 'unlinked':
        scene.render.engine = 'CYCLES'
        nan = rendering.render_combined(scene, str(tmp_path / 'nan.exr'))
        rough.default_value = 0.3
        assert np.array_equal(nan, rendering.render_combined(scene, str(tmp_path / 'r.exr')))
