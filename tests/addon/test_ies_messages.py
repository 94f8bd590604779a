"""What of an IES Texture in a light's node tree is not applied is said by name (the lamp then
emits evenly at the node's own value, as before): its Vector linked, its Fac
through a sum (not a factor on the emission), two IES Textures on one lamp. A Fac through
products (Math Multiply, into the Color) is applied and nothing is said. A profile that is
applied reaches the lamp (scenedata.Light.ies); a sun's too (it had been said not applied),
a delta sun's as one factor."""
import bpy

from addon.export import lights as export_lights
from . import scenes

TEXT = ("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 50\n0 45 90\n0\n1000 500 0\n")


def _lamp(kind, name):
    lamp = scenes.light(kind, 10.0, location=(0, 0, 2), name=name)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    ies = nt.nodes.new('ShaderNodeTexIES')
    ies.name = f'{name} profile'
    text = bpy.data.texts.get('profile.ies') or bpy.data.texts.new('profile.ies')
    text.from_string(TEXT)
    ies.mode, ies.ies = 'INTERNAL', text
    return lamp, nt, em, ies


def _export(lamp):
    messages = []
    out = export_lights.export_light(lamp, lamp.matrix_world, messages)
    return out, [t for _, t in messages]


def test_applied_through_products_says_nothing(scene):
    lamp, nt, em, ies = _lamp('SPOT', 'Product')
    mul = nt.nodes.new('ShaderNodeMath')
    mul.operation = 'MULTIPLY'
    mul.inputs[1].default_value = 3.0
    nt.links.new(ies.outputs['Fac'], mul.inputs[0])
    nt.links.new(mul.outputs[0], em.inputs['Color'])
    out, said = _export(lamp)
    assert out is not None and out.ies is not None and not said, said
    assert abs(out.ies.intensity.max() - 1000 * 0.0706650768394) < 1e-3


def test_unsupported_uses_are_named(scene):
    cases = {}
    lamp, nt, em, ies = _lamp('POINT', 'Vector')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Object'], ies.inputs['Vector'])
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    cases['Vector'] = (lamp, "its Vector input is linked")
    lamp, nt, em, ies = _lamp('POINT', 'Sum')
    add = nt.nodes.new('ShaderNodeMath')
    add.operation = 'ADD'
    add.inputs[1].default_value = 1.0
    nt.links.new(ies.outputs['Fac'], add.inputs[0])
    nt.links.new(add.outputs[0], em.inputs['Strength'])
    cases['Sum'] = (lamp, "its Fac does not scale the light's emission")
    lamp, nt, em, ies = _lamp('POINT', 'Two')
    second = nt.nodes.new('ShaderNodeTexIES')
    second.ies = ies.ies
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    nt.links.new(second.outputs['Fac'], em.inputs['Color'])
    cases['Two'] = (lamp, "more than one IES Texture")
    for name, (lamp, why) in cases.items():
        out, said = _export(lamp)
        assert out is not None and getattr(out, 'ies', None) is None, name
        text = [t for t in said if f"IES Texture '{name} profile'" in t and "not applied" in t]
        assert text and why in text[0] and f"light '{name}'" in text[0], (name, said)


def test_a_suns_profile_is_applied(scene):
    """A sun with an angle carries the profile (per direction over its cone); a delta sun the
    profile's mean round v = 0 as a factor (0.0707 x 1000 here), nothing said for either."""
    lamp, nt, em, ies = _lamp('SUN', 'Sun')
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    lamp.data.angle = 0.3
    out, said = _export(lamp)
    assert out is not None and out.ies is not None and not said, said
    strength = float(out.strength[0])
    lamp.data.angle = 0.0
    out, said = _export(lamp)
    assert out is not None and out.ies is None and not said, said
    assert abs(float(out.strength[0]) / strength - 1000 * 0.0706650768394) < 1e-2


def test_a_delta_suns_profile_varying_round_its_pole_is_said(scene):
    """A sun of Angle 0 travels along the profile's pole, where Cycles reads one horizontal angle
    as its transform rounds: with a profile that varies round the pole DACRT's mean there is said
    (with one that does not, as above, nothing is)."""
    from tests.iesfiles import PROFILES
    lamp, nt, em, ies = _lamp('SUN', 'Delta')
    ies.ies.from_string(PROFILES['asymmetric'])
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    lamp.data.angle = 0.0
    out, said = _export(lamp)
    assert out is not None and out.ies is None
    text = [t for t in said if "light 'Delta'" in t and "IES Texture 'Delta profile' on a sun of Angle 0" in t]
    assert text and "varies round the pole" in text[0], said
    lamp.data.angle = 0.2
    out, said = _export(lamp)
    assert out.ies is not None and not said, said
