"""The Caustics / Filter Glossy messages (settings.cycles_glossy_messages) count only what Cycles
renders of a material (reflectors.glossy_kinds over reflectors.rendered_closures), read as the
export reads its inputs:

- the shaders that reach the active Cycles Material Output, as Cycles compiles it (reroutes,
  muted nodes passed through, groups through their active Group Output, a Mix Shader of Fac 0 or
  1 down to one shader), not every node in the tree: a new material's Principled left unlinked
  beside the Diffuse the user linked had brought the Filter Glossy INFO at Cycles' defaults and a
  false Reflective WARNING with the toggle off, though Cycles renders it bit-identically with the
  toggles on or off (and DACRT's image matched it);
- a Toon BSDF's Glossy component, which Cycles drops past a diffuse bounce with Reflective
  Caustics off (4.8% darker there) and which had been left unsaid;
- a roughness or layer weight fed by a constant (a Value node, a Math chain) at its value: a
  Principled of roughness 0.95 from a Value node, which Filter Glossy leaves alone (Cycles
  bit-identical at 1 and 0), had got the Filter Glossy INFO, a Metallic from a Value of 0 the
  Reflective WARNING. A roughness that varies (a texture) still counts as possibly sharp.

DACRT's messages at 1 sample, 32x24; where Cycles renders, 32 samples (its images compared
with the setting on and off at the same seed)."""
import math

import bpy
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes

FILTER = "Filter Glossy"
REFLECTIVE = "Caustics > Reflective is off"
REFRACTIVE = "Caustics > Refractive is off"
ALL = (FILTER, REFLECTIVE, REFRACTIVE)


def _new_material(name):
    """A material as Blender makes a new one: a Principled BSDF linked to the output."""
    m = bpy.data.materials.new(name)
    nt = m.node_tree
    return m, nt, next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL'), \
        next(n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED')


def _group(glossy_linked):
    """A node group holding a Diffuse and a Glossy BSDF; its output the Glossy (through a reroute)
    where glossy_linked, else the Diffuse (the Glossy left unlinked inside)."""
    grp = bpy.data.node_groups.new('G', 'ShaderNodeTree')
    grp.interface.new_socket('Shader', in_out='OUTPUT', socket_type='NodeSocketShader')
    go = grp.nodes.new('NodeGroupOutput')
    d, g = grp.nodes.new('ShaderNodeBsdfDiffuse'), grp.nodes.new('ShaderNodeBsdfGlossy')
    if glossy_linked:
        r = grp.nodes.new('NodeReroute')
        grp.links.new(g.outputs[0], r.inputs[0])
        grp.links.new(r.outputs[0], go.inputs[0])
    else:
        grp.links.new(d.outputs[0], go.inputs[0])
    return grp


def _material(case):
    """(material, whether a sharp glossy reflection renders in Cycles) for each case."""
    m, nt, out, p = _new_material(case)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    surface = out.inputs['Surface']
    if case == 'unlinked_principled':               # the Principled left beside a linked Diffuse
        nt.links.new(d.outputs[0], surface)
        return m, False
    if case == 'linked_principled':
        return m, True
    nt.nodes.remove(p)
    if case == 'unlinked_glass':
        nt.nodes.new('ShaderNodeBsdfGlass')
        nt.links.new(d.outputs[0], surface)
        return m, False
    if case in ('mix_fac_0', 'mix_fac_1', 'mix_fac_value_0'):
        g, mx = nt.nodes.new('ShaderNodeBsdfGlossy'), nt.nodes.new('ShaderNodeMixShader')
        mx.inputs['Fac'].default_value = 1.0 if case == 'mix_fac_1' else 0.0
        if case == 'mix_fac_value_0':              # a Fac that folds to 0 (Cycles' constant folding)
            mx.inputs['Fac'].default_value = 0.5
            v, mul = nt.nodes.new('ShaderNodeValue'), nt.nodes.new('ShaderNodeMath')
            v.outputs[0].default_value, mul.operation = 0.7, 'MULTIPLY'
            mul.inputs[1].default_value = 0.0
            nt.links.new(v.outputs[0], mul.inputs[0])
            nt.links.new(mul.outputs[0], mx.inputs['Fac'])
        nt.links.new(d.outputs[0], mx.inputs[1])
        nt.links.new(g.outputs[0], mx.inputs[2])
        nt.links.new(mx.outputs[0], surface)
        return m, case == 'mix_fac_1'
    if case in ('eevee_output_glossy', 'cycles_output_glossy'):
        o2 = nt.nodes.new('ShaderNodeOutputMaterial')
        g = nt.nodes.new('ShaderNodeBsdfGlossy')
        glossy_out, diffuse_out = (o2, out) if case == 'eevee_output_glossy' else (out, o2)
        glossy_out.target, diffuse_out.target = ('EEVEE', 'CYCLES') if case == 'eevee_output_glossy' \
            else ('CYCLES', 'EEVEE')
        nt.links.new(g.outputs[0], glossy_out.inputs['Surface'])
        nt.links.new(d.outputs[0], diffuse_out.inputs['Surface'])
        return m, case == 'cycles_output_glossy'
    if case == 'muted_glossy':                      # no pass-through: no closure (black in both)
        g = nt.nodes.new('ShaderNodeBsdfGlossy')
        g.mute = True
        nt.links.new(g.outputs[0], surface)
        return m, False
    if case in ('muted_mix_diffuse_first', 'muted_mix_glossy_first'):
        # a muted Mix Shader passes its first shader through, whatever its Fac
        g, mx = nt.nodes.new('ShaderNodeBsdfGlossy'), nt.nodes.new('ShaderNodeMixShader')
        mx.mute = True
        first, second = (d, g) if case == 'muted_mix_diffuse_first' else (g, d)
        nt.links.new(first.outputs[0], mx.inputs[1])
        nt.links.new(second.outputs[0], mx.inputs[2])
        nt.links.new(mx.outputs[0], surface)
        return m, case == 'muted_mix_glossy_first'
    if case in ('group_unused_glossy', 'group_glossy'):
        gn = nt.nodes.new('ShaderNodeGroup')
        gn.node_tree = _group(case == 'group_glossy')
        nt.links.new(gn.outputs[0], surface)
        return m, case == 'group_glossy'
    if case == 'muted_link_glossy':                 # a muted link: no surface, black in both
        g = nt.nodes.new('ShaderNodeBsdfGlossy')
        nt.links.new(g.outputs[0], surface).is_muted = True
        return m, False
    raise ValueError(case)


def _scene(sc, m, bounces=2):
    scenes.world((0.5, 0.5, 0.5), 1.0)
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    scenes.light('POINT', 200, location=(1, -1, 3))
    scenes.plane(size=8, materials=[m])
    scenes.uv_sphere(location=(0, 0, 1), materials=[m])
    rendering.matched(sc, 1, bounces=bounces)
    sc.cycles.samples = 32
    sc.cycles.blur_glossy = 1.0                     # Cycles' default
    sc.cycles.caustics_reflective = sc.cycles.caustics_refractive = False


def _said(sc, said, *keys):
    said.clear()
    sc.render.engine = 'DACRT'
    bpy.ops.render.render()
    return {k: [t for t in said if k in t] for k in keys}


@pytest.mark.parametrize('case', ['unlinked_principled', 'linked_principled', 'unlinked_glass', 'mix_fac_0',
                                  'mix_fac_value_0', 'mix_fac_1', 'eevee_output_glossy', 'cycles_output_glossy',
                                  'muted_glossy', 'muted_mix_diffuse_first', 'muted_mix_glossy_first',
                                  'group_unused_glossy', 'group_glossy', 'muted_link_glossy'])
def test_only_shaders_cycles_renders_count(scene, said, case):
    m, glossy = _material(case)
    _scene(scene, m)
    got = _said(scene, said, *ALL)
    if glossy:          # a sharp glossy reflection reaches the Cycles output: both said, once
        assert len(got[FILTER]) == 1 and len(got[REFLECTIVE]) == 1 and not got[REFRACTIVE], got
    else:
        assert not any(got.values()), got


@pytest.mark.parametrize('case', ['unlinked_principled', 'linked_principled'])
def test_said_where_cycles_image_changes(scene, said, tmp_path, case):
    """Cycles' image with the Caustics settings at Cycles' defaults and with Filter Glossy 0 and
    both toggles off: bit-identical where the Principled is unlinked (and DACRT, which matches it,
    says nothing), different where it renders (and DACRT says so)."""
    m, glossy = _material(case)
    _scene(scene, m)
    cy = scene.cycles
    scene.render.engine = 'CYCLES'
    cy.blur_glossy, cy.caustics_reflective, cy.caustics_refractive = 1.0, True, True
    on = rendering.render_combined(scene, str(tmp_path / 'on.exr'))
    cy.blur_glossy, cy.caustics_reflective, cy.caustics_refractive = 0.0, False, False
    off = rendering.render_combined(scene, str(tmp_path / 'off.exr'))
    assert np.array_equal(on, off) != glossy
    cy.blur_glossy = 1.0
    got = _said(scene, said, *ALL)
    assert bool(got[FILTER]) == glossy and bool(got[REFLECTIVE]) == glossy and not got[REFRACTIVE], got
    if not glossy:
        scene.dacrt.samples = 16
        d = rendering.mean_of(scene, 'DACRT', tmp_path / 'd.exr')
        assert abs(d / float(on[..., :3].mean()) - 1.0) < 0.03


def _toon(component):
    m, nt, out = scenes._material('toon')
    t = nt.nodes.new('ShaderNodeBsdfToon')
    t.component = component
    t.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    nt.links.new(t.outputs[0], out.inputs['Surface'])
    return m


def _toon_scene(sc, component):
    scenes.black_world()
    scenes.camera(location=(0, -4.5, 1.2), rotation=(math.radians(88), 0, 0), lens=24)
    scenes.light('POINT', 300, location=(0, -1, 2.5), shadow_soft_size=0.2)
    toon = _toon(component)
    scenes.plane(size=10, materials=[scenes.diffuse('white', (0.8, 0.8, 0.8))])
    scenes.uv_sphere(location=(0, 0.5, 0.8), radius=0.8, materials=[toon])
    back = scenes.plane("Back", size=10, location=(0, 3, 2), materials=[toon])
    back.rotation_euler = (math.radians(90), 0, 0)
    rendering.matched(sc, 1, bounces=3)
    sc.cycles.samples = 128
    sc.cycles.light_sampling_threshold = 0.0
    sc.cycles.caustics_reflective = False


def test_toon_glossy_said_under_reflective_caustics_off(scene, said, tmp_path):
    """Cycles drops the Toon's Glossy component past a diffuse bounce (its image darker with the
    toggle off), not its Diffuse one; Filter Glossy does not blur it (no microfacet)."""
    _toon_scene(scene, 'GLOSSY')
    got = _said(scene, said, *ALL)
    assert len(got[REFLECTIVE]) == 1 and not got[FILTER] and not got[REFRACTIVE], got
    scene.cycles.caustics_reflective = True
    assert not _said(scene, said, REFLECTIVE)[REFLECTIVE]
    off_on = []
    for on in (False, True):
        scene.cycles.caustics_reflective = on
        off_on.append(rendering.mean_of(scene, 'CYCLES', tmp_path / f'c{on}.exr'))
    assert off_on[0] < 0.98 * off_on[1], off_on         # measured 0.3083 vs 0.3240 at 512 spp


def test_toon_diffuse_not_said(scene, said):
    _toon_scene(scene, 'DIFFUSE')
    assert not any(_said(scene, said, *ALL).values())


def _principled(sc, **linked):
    """A Principled (specular from its Specular IOR Level) whose inputs named in `linked` come
    from Value nodes of those values (or, for 'texture', a Noise Texture into that input)."""
    m, nt, out, p = _new_material('p')
    for name, v in linked.items():
        name = name.replace('_', ' ')
        if v == 'texture':
            nt.links.new(nt.nodes.new('ShaderNodeTexNoise').outputs['Fac'], p.inputs[name])
        elif isinstance(v, tuple):                  # Value * factor (a Math chain that folds)
            val, mul = nt.nodes.new('ShaderNodeValue'), nt.nodes.new('ShaderNodeMath')
            val.outputs[0].default_value, mul.operation = v[0], 'MULTIPLY'
            mul.inputs[1].default_value = v[1]
            nt.links.new(val.outputs[0], mul.inputs[0])
            nt.links.new(mul.outputs[0], p.inputs[name])
        else:
            val = nt.nodes.new('ShaderNodeValue')
            val.outputs[0].default_value = v
            nt.links.new(val.outputs[0], p.inputs[name])
    _scene(sc, m)
    return p


@pytest.mark.parametrize('inputs, expect', [
    ({'Roughness': 0.95}, {REFLECTIVE}),                 # rough: never blurred
    ({'Roughness': 0.3}, {FILTER, REFLECTIVE}),
    ({'Roughness': (0.4, 2.0)}, {REFLECTIVE}),            # Value x 2 = 0.8
    ({'Roughness': 'texture'}, {FILTER, REFLECTIVE}),     # varies: possibly sharp
    ({'Specular_IOR_Level': 0.0, 'Metallic': 0.0}, set()),
    ({'Specular_IOR_Level': 0.0, 'Metallic': 1.0}, {FILTER, REFLECTIVE}),
    ({'Specular_IOR_Level': 0.0, 'Metallic': (1.0, 0.0)}, set()),   # Value x 0
    ({'Specular_IOR_Level': 0.0, 'Coat_Weight': 0.0}, set()),
    ({'Specular_IOR_Level': 0.0, 'Coat_Weight': 0.5}, {FILTER, REFLECTIVE}),
    ({'Specular_IOR_Level': 0.0, 'Transmission_Weight': 0.0}, set()),
    ({'Specular_IOR_Level': 0.0, 'Transmission_Weight': 1.0}, {FILTER, REFLECTIVE, REFRACTIVE}),
    ({'Specular_IOR_Level': 0.0, 'Metallic': 'texture'}, {FILTER, REFLECTIVE}),
    ({'Alpha': 0.0}, set()),                              # fully transparent: no closure
    ({'IOR': 1.0}, set()),                                # specular of IOR 1: none (Cycles' eta 1)
])
def test_constant_inputs_read_at_their_value(scene, said, inputs, expect):
    _principled(scene, **inputs)
    got = _said(scene, said, *ALL)
    assert {k for k, v in got.items() if v} == expect, got


def test_filter_glossy_from_value_roughness_against_cycles(scene, said, tmp_path):
    """Roughness from a Value of 0.95: Cycles' image is the same at Filter Glossy 1 and 0 (its
    bsdf_blur acts below 0.71), and nothing is said; from 0.3 it changes, and the INFO is said."""
    for rough, blurred in ((0.95, False), (0.3, True)):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        sc = bpy.context.scene
        sc.render.resolution_x, sc.render.resolution_y = 32, 24
        _principled(sc, Roughness=rough)
        sc.cycles.caustics_reflective = sc.cycles.caustics_refractive = True
        imgs = []
        sc.render.engine = 'CYCLES'
        for blur in (1.0, 0.0):
            sc.cycles.blur_glossy = blur
            imgs.append(rendering.render_combined(sc, str(tmp_path / f'c{rough}_{blur}.exr')))
        assert np.array_equal(*imgs) != blurred, rough
        sc.cycles.blur_glossy = 1.0
        assert bool(_said(sc, said, FILTER)[FILTER]) == blurred, rough


@pytest.mark.parametrize('rough, sharp', [(0.9, False), (0.2, True)])
def test_roughness_read_out_of_a_group(scene, said, rough, sharp):
    """A Glossy BSDF inside a group, its Roughness from the Group Input: the Group node's own
    value is what Cycles reads."""
    grp = bpy.data.node_groups.new('G', 'ShaderNodeTree')
    grp.interface.new_socket('Roughness', in_out='INPUT', socket_type='NodeSocketFloat')
    grp.interface.new_socket('Shader', in_out='OUTPUT', socket_type='NodeSocketShader')
    gi, go, g = grp.nodes.new('NodeGroupInput'), grp.nodes.new('NodeGroupOutput'), grp.nodes.new('ShaderNodeBsdfGlossy')
    grp.links.new(gi.outputs[0], g.inputs['Roughness'])
    grp.links.new(g.outputs[0], go.inputs[0])
    m, nt, out = scenes._material('grouped')
    gn = nt.nodes.new('ShaderNodeGroup')
    gn.node_tree = grp
    gn.inputs[0].default_value = rough
    nt.links.new(gn.outputs[0], out.inputs['Surface'])
    _scene(scene, m)
    got = _said(scene, said, *ALL)
    assert bool(got[FILTER]) == sharp and len(got[REFLECTIVE]) == 1 and not got[REFRACTIVE], got
