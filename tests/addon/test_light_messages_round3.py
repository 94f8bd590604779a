"""Messages about lights, the Light Path node and worlds that said the wrong thing (the images
were right): a lamp whose node tree emits nothing in Cycles called 'zero strength'; 'its own
value used' without whose; approximation warnings where nothing emits (a world or lamp at
strength 0) or nothing differs (a sun's Light Falloff Smooth); a split world's lighting side
skipped as 'World', as if the camera saw none of it."""
import math

from . import scenes


def _floor():
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])


def _point(name, energy=300.0):
    lamp = scenes.light('POINT', energy, location=(0, -1, 2.2), name=name)
    lamp.data.use_nodes = True
    return lamp.data.node_tree


def test_lamp_tree_without_cycles_emission_says_why(scene, said):
    """Output targeted at EEVEE, no output, a muted Emission: Cycles emits nothing from each; the
    skipped-light message says so and why, not 'zero strength' (300 W in the panel)."""
    scenes.camera((0, 0, 5))
    _floor()
    nt = _point('EeveeOnly')
    next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT').target = 'EEVEE'
    nt = _point('NoOutput')
    nt.nodes.remove(next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT'))
    nt = _point('MutedEmission')
    next(n for n in nt.nodes if n.type == 'EMISSION').mute = True
    nt = _point('Unlinked')
    nt.links.remove(next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT').inputs['Surface'].links[0])
    _point('Dimmed', 0.0)
    scenes.render_rgba(scene)
    text = next(t for t in said if "node tree emits nothing" in t)
    assert text.startswith("skipped 4 light(s) whose node tree emits nothing, as in Cycles: "), text
    assert "EeveeOnly (its Light Output targets EEVEE, not Cycles)" in text, text
    assert "NoOutput (no Light Output in its node tree)" in text, text
    assert "MutedEmission (the muted 'Emission' node passes no emission)" in text, text
    assert "Unlinked (nothing linked into its Light Output's Surface)" in text, text
    assert "skipped 1 light(s) with zero strength: Dimmed" in said, said
    assert not any("approximated" in t for t in said), said


def test_own_value_names_the_socket_and_value(scene, said):
    """A Light Path deep in a chain stands at the own value of the input it is linked into (here
    a Map Range's Value, 1, which the ramp maps to black), not the Diffuse Color's: the message
    names that input and the value."""
    mat, nt, out = scenes._material("Floor")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    lp = nt.nodes.new('ShaderNodeLightPath')
    mr = nt.nodes.new('ShaderNodeMapRange')
    mr.inputs['From Min'].default_value, mr.inputs['From Max'].default_value = 4.0, 12.0
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    nt.links.new(lp.outputs['Ray Length'], mr.inputs['Value'])
    nt.links.new(mr.outputs[0], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=10, materials=[mat])
    scenes.light('SUN', 3.0)
    scenes.render_rgba(scene)
    text = next(t for t in said if "'Floor'" in t)
    assert "value from 'Light Path' node; its own value used (the 'Map Range' node's Value input, 1)" in text, text
