"""The export's walk over the depsgraph's instances (export/scene.py: Exporter._walk_instances):
only shader node trees decide whether Object Info is gathered per instance (a Geometry Nodes
Object Info node had switched it on for every scatter)."""
import bpy
import numpy as np

from addon.export import scene as export_scene

from . import scenes


class _Walked:
    """What one export's walk left: whether it gathered Object Info and instance attributes, and
    its placements (the exporter's own tables are cleared once the export is done)."""
    def __init__(self, exporter):
        self.object_info = exporter._object_info
        self.instance_attributes = exporter._instance_attributes is not None
        self.placements = {k: list(v) for k, v in exporter.placements.items()}


def _exporters(monkeypatch):
    """A _Walked for each export from here on."""
    seen = []
    walk = export_scene.Exporter._walk_instances

    def recording(self):
        walk(self)
        seen.append(_Walked(self))
    monkeypatch.setattr(export_scene.Exporter, '_walk_instances', recording)
    return seen


def _points(name, points):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(p) for p in points], [], [])
    return me


def _scatter(name, points, source, as_instance=True, seed=0, store=None, nested=None, own_face=False):
    """A mesh object of `points` whose Geometry Nodes put `source` on each (Object Info's As
    Instance: object instances, else geometry ones) with a random rotation and scale; store:
    an instance attribute of that name, a random colour; nested: points the whole set is put on
    again (storing 'outer' there); own_face: the object's own quad joined beside them."""
    me = _points(name, points)
    if own_face:
        n = len(points)
        me = bpy.data.meshes.new(name)
        me.from_pydata([tuple(p) for p in points] + [(3, 3, 0), (3.4, 3, 0), (3.4, 3.4, 0), (3, 3.4, 0)], [],
                       [(n, n + 1, n + 2, n + 3)])
    ob = scenes.link(bpy.data.objects.new(name, me))
    ng = bpy.data.node_groups.new(name, 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    m2p = ng.nodes.new('GeometryNodeMeshToPoints')
    ng.links.new(gi.outputs[0], m2p.inputs['Mesh'])
    info = ng.nodes.new('GeometryNodeObjectInfo')        # (the usual way to pick what is scattered)
    info.inputs['Object'].default_value = source
    info.inputs['As Instance'].default_value = as_instance
    iop = ng.nodes.new('GeometryNodeInstanceOnPoints')
    ng.links.new(m2p.outputs[0], iop.inputs['Points'])
    ng.links.new(info.outputs['Geometry'], iop.inputs['Instance'])
    rot = ng.nodes.new('FunctionNodeRandomValue')
    rot.data_type = 'FLOAT_VECTOR'
    rot.inputs['Min'].default_value, rot.inputs['Max'].default_value = (0, 0, 0), (6.3, 6.3, 6.3)
    rot.inputs['Seed'].default_value = seed
    ng.links.new(rot.outputs['Value'], iop.inputs['Rotation'])
    scale = ng.nodes.new('FunctionNodeRandomValue')
    scale.data_type = 'FLOAT_VECTOR'
    scale.inputs['Min'].default_value, scale.inputs['Max'].default_value = (0.5, 0.5, 0.5), (1.7, 1.3, 2.1)
    scale.inputs['Seed'].default_value = seed + 1
    ng.links.new(scale.outputs['Value'], iop.inputs['Scale'])
    out = iop.outputs[0]

    def stored(geometry, attribute, seed):
        st = ng.nodes.new('GeometryNodeStoreNamedAttribute')
        st.data_type, st.domain = 'FLOAT_COLOR', 'INSTANCE'
        st.inputs['Name'].default_value = attribute
        value = ng.nodes.new('FunctionNodeRandomValue')
        value.data_type = 'FLOAT_VECTOR'
        value.inputs['Seed'].default_value = seed
        ng.links.new(geometry, st.inputs['Geometry'])
        ng.links.new(value.outputs['Value'], st.inputs['Value'])
        return st.outputs[0]
    if store:
        out = stored(out, store, seed + 2)
    if nested is not None:
        outer = ng.nodes.new('GeometryNodeObjectInfo')
        outer.inputs['Object'].default_value = bpy.data.objects.new(name + "Outer", _points(name + "Outer", nested))
        iop2 = ng.nodes.new('GeometryNodeInstanceOnPoints')
        ng.links.new(outer.outputs['Geometry'], iop2.inputs['Points'])
        ng.links.new(out, iop2.inputs['Instance'])
        out = stored(iop2.outputs[0], 'outer', seed + 3)
    if own_face:
        join = ng.nodes.new('GeometryNodeJoinGeometry')
        ng.links.new(out, join.inputs[0])
        ng.links.new(gi.outputs[0], join.inputs[0])
        out = join.outputs[0]
    ng.links.new(out, go.inputs[0])
    ob.modifiers.new("GN", 'NODES').node_group = ng
    return ob


def _grid(n, size=4.0, z=0.0):
    k = int(np.ceil(np.sqrt(n)))
    return [((i % k) / k * size - size / 2, (i // k) / k * size - size / 2, z) for i in range(n)]


def _lit(scene):
    scenes.camera((0, 0, 12), kind='ORTHO', ortho_scale=7.0)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    scenes.world((0.1, 0.1, 0.1))


def test_a_geometry_nodes_object_info_does_not_gather_object_info(scene, monkeypatch):
    """A Geometry Nodes Object Info node (what picks the scattered object) is no shader's: no
    instance's Object Info is gathered when no material reads one (it had been, for every
    instance of every scatter), and the image is the one gathering it gives."""
    _lit(scene)
    src = scenes.cube("Src", size=0.25, location=(0, 0, -40), materials=(scenes.diffuse("D", (0.6, 0.4, 0.3)),))
    _scatter("Scatter", _grid(40), src, as_instance=False, seed=2)
    seen = _exporters(monkeypatch)
    plain = scenes.render_rgba(scene)
    ex = seen[-1]
    assert not ex.object_info and not ex.instance_attributes
    assert all(p.info is None for places in ex.placements.values() for p in places)
    init = export_scene.Exporter.__init__

    def gathering(self, *args, **kw):
        init(self, *args, **kw)
        self._object_info = True
    monkeypatch.setattr(export_scene.Exporter, '__init__', gathering)
    gathered = scenes.render_rgba(scene)
    assert seen[-1].object_info
    assert np.array_equal(plain, gathered)


def test_object_info_in_a_material_s_nested_group_is_still_gathered(scene, monkeypatch):
    """An Object Info node inside a shader group inside another group of a material switches
    the gathering on; a shader group no material uses does not."""
    _lit(scene)
    src = scenes.cube("Src", size=0.25, location=(0, 0, -40), materials=(scenes.diffuse("D", (0.6, 0.4, 0.3)),))
    _scatter("Scatter", _grid(4), src, as_instance=False)
    unused = bpy.data.node_groups.new("Unused", 'ShaderNodeTree')
    unused.nodes.new('ShaderNodeObjectInfo')
    seen = _exporters(monkeypatch)
    scenes.render_rgba(scene)
    assert not seen[-1].object_info
    inner = bpy.data.node_groups.new("Inner", 'ShaderNodeTree')
    inner.nodes.new('ShaderNodeObjectInfo')
    outer = bpy.data.node_groups.new("Outer", 'ShaderNodeTree')
    outer.nodes.new('ShaderNodeGroup').node_tree = inner
    mat = bpy.data.materials["D"]
    mat.node_tree.nodes.new('ShaderNodeGroup').node_tree = outer
    scenes.render_rgba(scene)
    assert seen[-1].object_info
