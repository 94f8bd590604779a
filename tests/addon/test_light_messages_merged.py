"""A light node tree the export approximates is said once for all the lights showing it (12
linked duplicates of one lamp with a Light Falloff had made 12 warnings differing only in the
name), as approximated materials are named together; different trees stay apart. (A lamp
applies one Light Falloff now: these feed two Emissions added, which it does not.)"""
import bpy

from . import scenes


def _falloff_lamp(name, output):
    data = bpy.data.lights.new(name, 'POINT')
    data.energy = 20.0
    data.use_nodes = True
    nt = data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    falloff, second, add = (nt.nodes.new(t) for t in ('ShaderNodeLightFalloff', 'ShaderNodeEmission',
                                                      'ShaderNodeAddShader'))
    nt.links.new(falloff.outputs[output], em.inputs['Strength'])
    nt.links.new(falloff.outputs[output], second.inputs['Strength'])
    nt.links.new(em.outputs[0], add.inputs[0])
    nt.links.new(second.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT').inputs['Surface'])
    return data


def test_light_tree_messages_name_all_their_lights_once(scene, said):
    scenes.camera((0, 0, 8))
    scenes.plane("Floor", size=10)
    lamp, other = _falloff_lamp("Lamp", 'Linear'), _falloff_lamp("Other", 'Constant')
    for i in range(12):
        ob = scenes.link(bpy.data.objects.new(f"Lamp{i}", lamp))
        ob.location = (i * 0.5 - 3, 0, 2)
    scenes.link(bpy.data.objects.new("Odd", other)).location = (0, 2, 2)
    scene.dacrt.samples = 1
    scenes.render_rgba(scene)
    texts = [t for t in said if "node tree approximated" in t]
    assert len(texts) == 2, texts
    linear = next(t for t in texts if "Linear" in t)
    names = ', '.join(f"'Lamp{i}'" for i in range(12))
    assert linear.startswith(f"lights {names}: node tree approximated: Light Falloff Linear"), linear
    assert any(t.startswith("light 'Odd': node tree approximated: Light Falloff Constant") for t in texts), texts
