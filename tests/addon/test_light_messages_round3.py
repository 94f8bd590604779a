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


def test_zero_strength_world_and_lamp_warn_of_nothing(scene, said):
    """A world of Strength 0 with a Noise colour and a lamp of node Strength 0 with a Checker
    colour emit nothing, exactly as in Cycles: no 'approximated' warning for their colours."""
    scenes.camera((0, 0, 5))
    _floor()
    scenes.light('SUN', 3.0, name='Key')
    nt = _point('Fill', 200.0)
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    em.inputs['Strength'].default_value = 0.0
    ck = nt.nodes.new('ShaderNodeTexChecker')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Normal'], ck.inputs['Vector'])
    nt.links.new(ck.outputs['Color'], em.inputs['Color'])
    # a Principled emission of strength 0 with a textured colour: the same
    nt = _point('Glow', 200.0)
    pr = nt.nodes.new('ShaderNodeBsdfPrincipled')
    pr.inputs['Emission Strength'].default_value = 0.0
    nt.links.new(nt.nodes.new('ShaderNodeTexNoise').outputs['Color'], pr.inputs['Emission Color'])
    nt.links.new(pr.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT').inputs['Surface'])
    w, wt, out = scenes.world_tree()
    bg = wt.nodes.new('ShaderNodeBackground')
    bg.inputs['Strength'].default_value = 0.0
    wt.links.new(wt.nodes.new('ShaderNodeTexNoise').outputs['Color'], bg.inputs['Color'])
    wt.links.new(bg.outputs[0], out.inputs['Surface'])
    scenes.render_rgba(scene)
    assert not any("approximated" in t for t in said), said
    assert "skipped 2 light(s) with zero strength: Fill, Glow" in said, said


def test_zero_weight_mix_side_warns_of_nothing(scene, said):
    """A light Mix Shader at factor 0: its second side adds nothing, so a texture there is no
    approximation."""
    scenes.camera((0, 0, 5))
    _floor()
    nt = _point('Mixed', 100.0)
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.0
    textured = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(nt.nodes.new('ShaderNodeTexChecker').outputs['Color'], textured.inputs['Color'])
    nt.links.new(em.outputs[0], mix.inputs[1])
    nt.links.new(textured.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.render_rgba(scene)
    assert not any("approximated" in t for t in said), said


def _falloff_lamp(kind, output, smooth):
    lamp = scenes.light(kind, 3.0 if kind == 'SUN' else 100.0, location=(0, 0, 2), rotation=(0.4, 0.2, 0),
                        name=kind.title())
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    fo = nt.nodes.new('ShaderNodeLightFalloff')
    fo.inputs['Smooth'].default_value = smooth
    nt.links.new(fo.outputs[output], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Strength'])


def test_sun_falloff_smooth_is_exact(scene, said):
    """Cycles smooths a Light Falloff only at a finite squared ray length; a sun's is FLT_MAX
    (svm_node_light_falloff), so a sun's Smooth changes nothing: no warning. A point light's
    Smooth does, which the lamp applies per ray (not warned: its falloff); a sun's Linear output
    does not either (Cycles passes a sun's Strength through the node unchanged:
    test_light_messages_round2); a negative Smooth is no smoothing."""
    scenes.camera((0, 0, 5))
    _floor()
    _falloff_lamp('SUN', 'Quadratic', 1.0)
    scenes.render_rgba(scene)
    assert not any("approximated" in t for t in said), said
    said.clear()
    bpy_scene_reset(scene)
    _falloff_lamp('POINT', 'Quadratic', -1.0)
    scenes.render_rgba(scene)
    assert not any("approximated" in t for t in said), said
    said.clear()
    bpy_scene_reset(scene)
    _falloff_lamp('POINT', 'Quadratic', 1.0)
    _falloff_lamp('SUN', 'Linear', 1.0)
    scenes.render_rgba(scene)
    assert not any("light 'Point'" in t or "light 'Sun'" in t for t in said), said


def bpy_scene_reset(scene):
    """The scene emptied of objects (the fixture's settings kept), with a camera and floor."""
    import bpy
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)
    scenes.camera((0, 0, 5))
    _floor()


def test_split_world_lighting_side_named_as_such(scene, said):
    """A world Mix Shader by Is Camera Ray with Ray Visibility Diffuse off: the camera sees its
    camera side; only its other side lights nothing, and the message says which side."""
    scenes.camera((0, -6, 2.5), rotation=(math.radians(70), 0, 0))
    _floor()
    w, nt, out = scenes.world_tree()
    b1 = nt.nodes.new('ShaderNodeBackground')
    b1.inputs['Color'].default_value = (0.3, 0.5, 1.0, 1)
    b2 = nt.nodes.new('ShaderNodeBackground')
    b2.inputs['Color'].default_value = (1.0, 0.2, 0.1, 1)
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    nt.links.new(b1.outputs[0], mix.inputs[1])
    nt.links.new(b2.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    w.cycles_visibility.diffuse = False
    scenes.light('SUN', 2.0, rotation=(0.5, 0.3, 0))
    rgba = scenes.render_rgba(scene)
    text = next(t for t in said if "neither camera nor diffuse" in t)
    assert text.endswith(": World (its non-camera side)"), text
    assert rgba[-1, :, 0].mean() > 0.5          # (the camera side, red, at the top of the frame)
