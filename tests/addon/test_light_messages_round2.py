"""Messages about lights that said the wrong thing, found by the lights hunt (the images were
right, or as right as DACRT can make them):
- a sun's Light Falloff Linear or Constant output warned "approximated", though Cycles passes a
  sun's Strength through the node unchanged (0.2301 in both engines for all three outputs);
- a Diffuse, Transparent or Holdout added or mixed beside a lamp's Emission warned
  "approximated", though Cycles' light shader emits nothing from them either (0.2194 in both);
- an emitter whose Strength reads 0 only because a node not evaluated here stood at its own
  value was summed up as "no emissive materials" (Cycles lit the scene with it, 0.1005);
- an IES Texture on a lamp was only "not evaluated", not said to be ignored as a profile."""
import re

import bpy
import numpy as np

from . import scenes


def _floor():
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])


def _lamp(kind, name, energy, **props):
    lamp = scenes.light(kind, energy, location=(0, -1, 2.2), name=name, **props)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    return nt, next(n for n in nt.nodes if n.type == 'EMISSION'), next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')


def _about(said, name):
    return [t for t in said if f"'{name}'" in t or f" {name}" in t]


def test_sun_light_falloff_outputs_warn_of_nothing(scene, said):
    """A sun's Strength from a Light Falloff's Linear or Constant output (Smooth 0 or 1): as its
    Quadratic in Cycles, so no warning; a point light's Linear output neither (the lamp applies
    it per ray: tests/parity/test_light_falloff_lamps.py), but a point light's Linear output
    feeding both of two Emissions added (the lamp applies one falloff) still warns."""
    scenes.camera((0, 0, 5))
    _floor()
    for output, smooth in (('Linear', 0.0), ('Constant', 1.0)):
        nt, em, _ = _lamp('SUN', f'Sun{output}', 2.0)
        falloff = nt.nodes.new('ShaderNodeLightFalloff')
        falloff.inputs['Strength'].default_value = 0.5
        falloff.inputs['Smooth'].default_value = smooth
        nt.links.new(falloff.outputs[output], em.inputs['Strength'])
    nt, em, _ = _lamp('POINT', 'PointLinear', 100.0)
    falloff = nt.nodes.new('ShaderNodeLightFalloff')
    nt.links.new(falloff.outputs['Linear'], em.inputs['Strength'])
    second = nt.nodes.new('ShaderNodeEmission')
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(falloff.outputs['Linear'], second.inputs['Strength'])
    nt.links.new(em.outputs[0], add.inputs[0])
    nt.links.new(second.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT').inputs['Surface'])
    scenes.render_rgba(scene)
    assert not any("SunLinear" in t or "SunConstant" in t for t in said), said
    assert any("PointLinear" in t and "Light Falloff Linear" in t for t in said), said


def test_bsdf_beside_a_lamp_emission_warns_of_nothing(scene, said):
    """Add(Emission, Diffuse / Transparent / Holdout) and Mix(Emission, Transparent, 0.3) in a
    point light's tree: their BSDFs emit nothing in Cycles' light shader either: no warning, and
    the lamps light (not skipped). A tree of a Diffuse BSDF alone is skipped as dark, with that
    cause, and not warned of as approximated."""
    scenes.camera((0, 0, 5))
    _floor()
    for kind in ('ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent', 'ShaderNodeHoldout'):
        nt, em, out = _lamp('POINT', f'Add{kind[10:]}', 300.0)
        add = nt.nodes.new('ShaderNodeAddShader')
        nt.links.new(em.outputs[0], add.inputs[0])
        nt.links.new(nt.nodes.new(kind).outputs[0], add.inputs[1])
        nt.links.new(add.outputs[0], out.inputs['Surface'])
    nt, em, out = _lamp('POINT', 'MixTransparent', 300.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.3
    nt.links.new(em.outputs[0], mix.inputs[1])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    nt, em, out = _lamp('POINT', 'DiffuseOnly', 300.0)
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], out.inputs['Surface'])
    scenes.render_rgba(scene)
    assert not any("approximated" in t for t in said), said
    skipped = next(t for t in said if "node tree emits nothing" in t)
    assert "DiffuseOnly (Diffuse BSDF emits no light" in skipped, skipped
    assert not any(n in skipped for n in ('AddBsdfDiffuse', 'AddBsdfTransparent', 'AddHoldout',
                                          'MixTransparent')), skipped


def _incoming_emitter():
    """An emissive panel whose Strength is 8 x length(Geometry Tangent): per sample in
    Cycles; here the Tangent stands at its own value, so the strength reads 0. (Incoming,
    which this read before, is now computed per point.)"""
    mat, nt, out = scenes._material("e")
    em = nt.nodes.new('ShaderNodeEmission')
    g = nt.nodes.new('ShaderNodeNewGeometry')
    dot = nt.nodes.new('ShaderNodeVectorMath')
    dot.operation = 'LENGTH'
    nt.links.new(g.outputs['Tangent'], dot.inputs[0])
    mul = nt.nodes.new('ShaderNodeMath')
    mul.operation = 'MULTIPLY'
    mul.inputs[1].default_value = 8.0
    nt.links.new(dot.outputs['Value'], mul.inputs[0])
    nt.links.new(mul.outputs[0], em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def test_emitter_dark_by_a_stand_in_is_named(scene, said):
    """The only emitter's Strength reads 0 because the Geometry node stands at its own value:
    the summary names the material and the node (Cycles lights the scene with it), not "no
    emissive materials"."""
    scenes.camera((0, 0, 5))
    _floor()
    panel = scenes.plane("Panel", size=2, location=(0, 0, 2), materials=[_incoming_emitter()])
    panel.rotation_euler = (np.pi, 0, 0)
    scenes.render_rgba(scene)
    assert not any("no emissive materials" in t for t in said), said
    text = next(t for t in said if "image will be black" in t)
    assert "emissive material(s) read 0 here" in text and "'e' (Emission: " in text, text
    assert "'Geometry' node" in text and "Cycles evaluates them" in text, text


def test_emitter_of_zero_strength_still_says_no_emissive_materials(scene, said):
    """An Emission of a plain Strength 0 emits nothing in Cycles too: the summary stays "no
    emissive materials"."""
    scenes.camera((0, 0, 5))
    _floor()
    mat, nt, out = scenes._material("Off")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Strength'].default_value = 0.0
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Panel", size=2, location=(0, 0, 2), materials=[mat])
    scenes.render_rgba(scene)
    assert any("no emissive materials" in t for t in said), said


def test_ies_texture_is_named_as_not_applied(scene, said):
    """An IES Texture into a point light's Strength is applied (tests/parity/test_ies_lights.py);
    one without a profile (no Text) is what Cycles cannot load: said, naming the light and the
    node, with what Cycles renders (100 x Strength evenly), inside a node group too."""
    scenes.camera((0, 0, 5))
    _floor()
    nt, em, _ = _lamp('POINT', 'Spot', 300.0)
    ies = nt.nodes.new('ShaderNodeTexIES')
    ies.name = 'Profile'
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    # inside a node group (its output's own value, 0, had stood in and the lamp was skipped as
    # dark; the IES note had been left out there: regression hunt)
    nt2, em2, _ = _lamp('POINT', 'Grouped', 300.0)
    group = bpy.data.node_groups.new('IES group', 'ShaderNodeTree')
    group.interface.new_socket('Fac', in_out='OUTPUT', socket_type='NodeSocketFloat')
    inner = group.nodes.new('ShaderNodeTexIES')
    inner.name = 'Inner profile'
    group.links.new(inner.outputs['Fac'], group.nodes.new('NodeGroupOutput').inputs[0])
    node = nt2.nodes.new('ShaderNodeGroup')
    node.node_tree = group
    nt2.links.new(node.outputs[0], em2.inputs['Strength'])
    scenes.render_rgba(scene)
    text = next(t for t in said if "light 'Spot'" in t)
    assert "IES Texture 'Profile' cannot be read" in text and "100 x its Strength" in text, text
    text = [t for t in said if "light 'Grouped'" in t]
    assert any("IES Texture 'Inner profile' cannot be read" in t for t in text), text


def test_one_sided_emission_sampling_under_a_coat_is_said(scene, said):
    """A coated Principled emitter's light samples see its emission undimmed (as Cycles'); DACRT
    samples Front / Back on both sides, so the side Cycles leaves to BSDF rays lights undimmed
    too (regression hunt: Back, coat 1, 1.056x Cycles): said for Front and Back, not for Auto
    or Front and Back, nor without a coat."""
    scenes.camera((0, 0, 5))
    _floor()
    for name, sides, coat in (('CoatBack', 'BACK', 1.0), ('CoatFront', 'FRONT', 1.0), ('CoatBoth', 'FRONT_BACK', 1.0),
                              ('CoatAuto', 'AUTO', 1.0), ('NoCoatBack', 'BACK', 0.0)):
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        p = mat.node_tree.nodes['Principled BSDF']
        p.inputs['Emission Color'].default_value = (1.0, 0.5, 0.2, 1.0)
        p.inputs['Emission Strength'].default_value = 5.0
        p.inputs['Coat Weight'].default_value = coat
        mat.cycles.emission_sampling = sides
        scenes.plane(name, size=1.0, location=(0.0, 0.0, 1.0), materials=[mat])
    scenes.render_rgba(scene)
    summary = next(t for t in said if "material(s) approximated" in t)
    reasons = {}                     # "'A' (why); 'B', 'C' (why)": each material's reasons
    for part in summary.split(": ", 1)[1].split("); "):
        names, _, why = part.partition(" (")
        reasons.update((n, why) for n in re.findall(r"'([^']*)'", names))
    assert set(reasons) == {'CoatBack', 'CoatFront', 'CoatBoth', 'CoatAuto', 'NoCoatBack'}, summary
    for name, said_it in (('CoatBack', True), ('CoatFront', True), ('CoatBoth', False), ('CoatAuto', False),
                          ('NoCoatBack', False)):
        assert ("sampled on both sides" in reasons[name]) == said_it, (name, reasons[name])
