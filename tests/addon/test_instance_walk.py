"""The export's walk over the depsgraph's instances (export/scene.py: Exporter._walk_instances):
only shader node trees decide whether Object Info is gathered per instance (a Geometry Nodes
Object Info node had switched it on for every scatter), and the walk that reads the matrices in
bulk and each (object, data, instancer)'s settings once exports exactly what reading every
instance on its own does (scene.BULK_WALK off), on scatters with random rotation and scale,
nested instances, instance attributes, Object Info, particles and collection instances."""
import dataclasses

import bpy
import numpy as np
import pytest

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


def _object_info_material(name):
    """Diffuse coloured by Object Info Random (each instance's random id)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    info = nt.nodes.new('ShaderNodeObjectInfo')
    combine = nt.nodes.new('ShaderNodeCombineColor')
    nt.links.new(info.outputs['Random'], combine.inputs[0])
    combine.inputs[1].default_value, combine.inputs[2].default_value = 0.5, 0.3
    nt.links.new(combine.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _instancer_material(name, attribute):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = 'INSTANCER', attribute
    nt.links.new(a.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _grid(n, size=4.0, z=0.0):
    k = int(np.ceil(np.sqrt(n)))
    return [((i % k) / k * size - size / 2, (i // k) / k * size - size / 2, z) for i in range(n)]


def _lit(scene):
    scenes.camera((0, 0, 12), kind='ORTHO', ortho_scale=7.0)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    scenes.world((0.1, 0.1, 0.1))


def _scatter_scene(scene):
    """Object and geometry instances with random rotation and scale, one source read by Object
    Info Random, another by an Instancer attribute."""
    _lit(scene)
    info_src = scenes.cube("InfoSrc", size=0.2, location=(0, 0, -40), materials=(_object_info_material("Info"),))
    attr_src = scenes.uv_sphere("AttrSrc", radius=0.12, segments=8, rings=4, location=(0, 0, -40),
                                materials=(_instancer_material("Attr", 'icol'),))
    _scatter("ObjectInstances", _grid(60), info_src, as_instance=True, seed=3, store='icol')
    _scatter("GeometryInstances", _grid(50, z=1.0), attr_src, as_instance=False, seed=7, store='icol')
    _scatter("InfoGeometry", _grid(30, z=-1.0), info_src, as_instance=False, seed=11)


def _nested_scene(scene):
    """Instances of instances (attributes at both levels), beside an instancer's own face."""
    _lit(scene)
    src = scenes.cube("Src", size=0.15, location=(0, 0, -40),
                      materials=(_instancer_material("Outer", 'outer'), _object_info_material("Info")))
    src.data.polygons.foreach_set('material_index', np.array([0, 1, 0, 1, 0, 1], np.int32))
    _scatter("Nested", _grid(12, size=1.5), src, as_instance=True, seed=5, store='icol',
             nested=_grid(6, size=5.0), own_face=True)
    _scatter("NestedGeometry", _grid(8, size=1.0), src, as_instance=False, seed=9, store='icol',
             nested=_grid(4, size=4.0, z=1.0))


def _particles_and_collections_scene(scene):
    """Particle instances, collection instances (a light among their members), a plain object."""
    _lit(scene)
    src = scenes.cube("PartSrc", size=0.1, location=(0, 0, -40), materials=(_object_info_material("Info"),))
    emitter = scenes.plane("Emitter", size=4.0, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    settings = emitter.modifiers.new("P", 'PARTICLE_SYSTEM').particle_system.settings
    settings.count, settings.frame_start, settings.frame_end, settings.lifetime = 80, 1, 1, 100
    settings.physics_type, settings.emit_from = 'NO', 'FACE'
    settings.render_type, settings.instance_object, settings.particle_size = 'OBJECT', src, 1.0
    settings.use_rotations = True
    coll = bpy.data.collections.new("Members")
    member = scenes.uv_sphere("Member", radius=0.2, segments=8, rings=4, scene=None)
    scene.collection.objects.unlink(member)
    coll.objects.link(member)
    lamp = bpy.data.objects.new("MemberLamp", bpy.data.lights.new("MemberLamp", 'POINT'))
    lamp.location = (0, 0, 1)
    coll.objects.link(lamp)
    for i, x in enumerate((-2.0, 0.0, 2.0)):
        e = bpy.data.objects.new(f"Empty{i}", None)
        e.instance_type, e.instance_collection, e.location = 'COLLECTION', coll, (x, 2.5, 0.5)
        e.rotation_euler = (0.2 * i, 0.5, 0.1)
        e.scale = (1.0, 1.0 + i, 0.5)
        scene.collection.objects.link(e)


def _same(a, b, where):
    """Assert two exported values are equal: arrays bit for bit, dataclasses field by field."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            if f.compare:   # (not a cache such as a light's made lamp, which is no part of its value)
                _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        assert a.shape == b.shape and a.dtype == b.dtype, (where, a.shape, b.shape, a.dtype, b.dtype)
        same = np.array_equal(a, b, equal_nan=True) if a.dtype.kind in 'fc' else np.array_equal(a, b)
        assert same, where
    elif isinstance(a, dict):
        assert list(a) == list(b), where
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), (where, len(a), len(b))
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        pass
    else:
        assert a == b, (where, a, b)


@pytest.mark.parametrize('build', [_scatter_scene, _nested_scene, _particles_and_collections_scene],
                         ids=['scatter', 'nested', 'particles_and_collections'])
def test_the_bulk_walk_exports_what_reading_each_instance_does(scene, exported, monkeypatch, build):
    build(scene)
    seen = _exporters(monkeypatch)
    monkeypatch.setattr(export_scene, 'BULK_WALK', True)
    bulk = exported()
    monkeypatch.setattr(export_scene, 'BULK_WALK', False)
    each = exported()
    a, b = seen
    assert a.object_info and b.object_info           # the random ids and attributes are read
    placed = sum(len(p) for p in a.placements.values())
    assert placed > 40, placed
    assert len(bulk.geometry.triangles) > 500
    # every placement the same: matrix (bit for bit), slots, visibility, object, name, terminator
    # (keyed by data pointers, another depsgraph's in each render: compared in their order)
    assert [k[0] for k in a.placements] == [k[0] for k in b.placements]
    for ours, theirs in zip(a.placements.values(), b.placements.values(), strict=True):
        for p, q in zip(ours, theirs, strict=True):
            assert np.array_equal(p.matrix, q.matrix) and p.matrix.dtype == q.matrix.dtype == np.float64
            assert (p.slots, p.visibility, p.object_index, p.name, p.terminator) == \
                   (q.slots, q.visibility, q.object_index, q.name, q.terminator)
            assert (p.info is None) == (q.info is None)
            if p.info is not None:
                assert p.info[:4] == q.info[:4]
    # and what the frame renders from
    for field in ('geometry', 'lights', 'object_names', 'object_keys', 'object_pass_index', 'object_assets',
                  'object_lightgroups', 'messages', 'skipped', 'light_links', 'shadow_links'):
        _same(getattr(bulk, field), getattr(each, field), field)
    assert [m.name for m in bulk.materials] == [m.name for m in each.materials]


def test_each_object_is_read_once_for_all_its_instances(scene, exported, monkeypatch):
    """300 instances of one object: its geometry key, material slots and object entry are
    worked out once (they had been for each instance, ~20 us of RNA reads each)."""
    _lit(scene)
    src = scenes.cube("Src", size=0.1, location=(0, 0, -40), materials=(scenes.diffuse("D", (0.5, 0.4, 0.3)),))
    _scatter("Scatter", _grid(300), src, as_instance=False, seed=1)
    calls = {'_read_geometry': 0, '_object_id': 0}
    for name in calls:
        real = getattr(export_scene.Exporter, name)

        def counted(self, *args, _real=real, _name=name):
            calls[_name] += 1
            return _real(self, *args)
        monkeypatch.setattr(export_scene.Exporter, name, counted)
    data = exported()
    assert len(data.geometry.triangles) == 12 * 301
    assert calls['_read_geometry'] <= 3 and calls['_object_id'] <= 3, calls


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
