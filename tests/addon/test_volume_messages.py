"""What the render says of volumes it skips: a mesh object whose Geometry Nodes make a volume
(Mesh to Volume) is named as that, placed directly or through a collection instance (instanced,
it had been called a volume object: its instance's parent is the instancer, not the object);
a Volume object is a volume object either way."""
import math

import bpy
import pytest

from . import scenes


def _gn_volume_cube():
    ob = scenes.cube("GNVol", size=1.0, location=(0, 0, 1))
    ng = bpy.data.node_groups.new("M2V", 'GeometryNodeTree')
    ng.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    m2v = ng.nodes.new('GeometryNodeMeshToVolume')
    ng.links.new(gi.outputs[0], m2v.inputs[0])
    ng.links.new(m2v.outputs[0], go.inputs[0])
    ob.modifiers.new("GN", 'NODES').node_group = ng
    return ob


def _volume_object():
    ob = bpy.data.objects.new("VolObj", bpy.data.volumes.new("VolObj"))
    bpy.context.scene.collection.objects.link(ob)
    return ob


def _instanced(ob, sc):
    col = bpy.data.collections.new("C")
    sc.collection.objects.unlink(ob)
    col.objects.link(ob)
    inst = bpy.data.objects.new("Inst", None)
    inst.instance_type, inst.instance_collection = 'COLLECTION', col
    sc.collection.objects.link(inst)


@pytest.mark.parametrize('instanced', [False, True], ids=['placed', 'instanced'])
@pytest.mark.parametrize('make, said_of', [
    (_gn_volume_cube, "skipped 'GNVol': volume geometry its Geometry Nodes make is not rendered (the rest of "
                      "the object is)"),
    (_volume_object, "skipped 'VolObj': volume objects are not rendered"),
], ids=['geometry_nodes', 'volume_object'])
def test_skipped_volume_is_named_for_what_it_is(scene, said, instanced, make, said_of):
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(58), 0, 0))
    scenes.plane("Floor", size=12, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    ob = make()
    if instanced:
        _instanced(ob, scene)
    scene.dacrt.samples = 1
    bpy.ops.render.render()
    named = [t for t in said if ob.name in t]
    assert any(said_of in t for t in named), named
    if make is _gn_volume_cube:
        assert not any("volume objects" in t for t in named), named
