"""The render says when Cycles lights light-sampled emissive meshes brighter because of light
linking (lights/linking.py cycles_mesh_light_excess_said): a lamp whose receiver collection holds
only the ground, over emissive spheres that only emit, changes nothing physically, yet Cycles
renders the spheres' light 4.5% brighter (6.8% as Geometry Nodes instances: min419 of fuzz seed
419), while DACRT renders it unchanged (0.956x Cycles) and said nothing. Not said where the images agree: no linking, a
blocker collection, Emission Sampling None, or an emissive object with a receiver collection of
its own."""
import bpy

from . import scenes


def _scene(scene, link='receiver', sampling='AUTO', own_receivers=0):
    scene.dacrt.samples = 1
    scenes.camera((3, -6, 5), rotation=(0.9, 0, 0.45))
    ground = scenes.plane("Ground", size=14, materials=[scenes.diffuse("G", (0.8, 0.8, 0.8))])
    glow = scenes.emission("Glow", (1, 1, 1), 3.0)
    glow.cycles.emission_sampling = sampling
    spheres = [scenes.uv_sphere(f"Bulb{i}", radius=0.2, segments=8, rings=4, location=(i - 1, 0, 0.8),
                                materials=[glow]) for i in range(3)]
    lamp = scenes.light('AREA', 300.0, (-3, -1, 3.6), rotation=(0.6, -0.6, 0), size=1.0, name="L0")
    coll = bpy.data.collections.new("Recv")
    coll.objects.link(ground)
    if link:
        setattr(lamp.light_linking, f"{link}_collection", coll)
    for sphere in spheres[:own_receivers]:
        sphere.light_linking.receiver_collection = coll
    scenes.render_rgba(scene)


def _excess(said):
    return [t for t in said if "Cycles renders their light 4-7% brighter" in t]


def test_a_lamps_receiver_collection_over_emissive_meshes_is_said(scene, said):
    _scene(scene)
    texts = _excess(said)
    assert len(texts) == 1, said
    assert "light linking receiver collections of 'L0' with emissive objects 'Bulb0', 'Bulb1', 'Bulb2'" in texts[0], said


def test_a_lamps_blocker_collection_says_nothing(scene, said):
    """Cycles is 3.9% brighter with it too, but DACRT follows it (0.999x)."""
    _scene(scene, link='blocker')
    assert not _excess(said), said


def test_without_linking_nothing_is_said(scene, said):
    _scene(scene, link=None)
    assert not _excess(said), said


def test_emission_sampling_none_says_nothing(scene, said):
    _scene(scene, sampling='NONE')
    assert not _excess(said), said


def test_an_emitter_with_its_own_receivers_says_nothing(scene, said):
    _scene(scene, own_receivers=1)
    assert not _excess(said), said


def test_emissive_geometry_nodes_instances_are_said(scene, said):
    """Fuzz seed 419's emitters: ico spheres a Geometry Nodes grid instances."""
    scene.dacrt.samples = 1
    scenes.camera((3, -6, 5), rotation=(0.9, 0, 0.45))
    ground = scenes.plane("Ground", size=14, materials=[scenes.diffuse("G", (0.8, 0.8, 0.8))])
    host = scenes.plane("Host", size=3, location=(0, 0, 0.8))
    ng = bpy.data.node_groups.new("Bulbs", 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gin, gout = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    on_points, ico = ng.nodes.new('GeometryNodeInstanceOnPoints'), ng.nodes.new('GeometryNodeMeshIcoSphere')
    ico.inputs['Radius'].default_value = 0.2
    set_mat = ng.nodes.new('GeometryNodeSetMaterial')
    set_mat.inputs['Material'].default_value = scenes.emission("Glow", (1, 1, 1), 3.0)
    ng.links.new(gin.outputs[0], on_points.inputs['Points'])
    ng.links.new(ico.outputs[0], set_mat.inputs['Geometry'])
    ng.links.new(set_mat.outputs[0], on_points.inputs['Instance'])
    ng.links.new(on_points.outputs[0], gout.inputs[0])
    host.modifiers.new("GN", 'NODES').node_group = ng
    lamp = scenes.light('AREA', 300.0, (-3, -1, 3.6), rotation=(0.6, -0.6, 0), size=1.0, name="L0")
    coll = bpy.data.collections.new("Recv")
    coll.objects.link(ground)
    lamp.light_linking.receiver_collection = coll
    scenes.render_rgba(scene)
    texts = _excess(said)
    assert len(texts) == 1 and "with emissive objects 'Host'" in texts[0], said
