"""An Attribute node of type Instancer agrees with Cycles per instance: Geometry Nodes instance
attributes (Store Named Attribute on the Instance domain: colours, numbers, integers, booleans,
vectors) on object and geometry instances, nested instances (the innermost instancer's), an
instancer's own mesh and a realized copy (the object's custom property, as Cycles: no
instance), collection and particle instances (the instancer's property, the particle
settings'), a name nowhere (0) and the nodes after it (a Color Ramp on a number). Small quads
under a straight-down sun, direct light only: each quad's centre pixel is exact per sample, and
both engines agree within 2e-3. Before, DACRT read the node's own colour (0.8) everywhere, said
'instancer attribute ... not read'."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_color_attributes import _render_both

pytestmark = pytest.mark.usefixtures('parity_addon')

W, H, SCALE = 48, 36, 4.0           # 12 pixels a unit


def instancer_material(name, attribute, output='Color', ramp=False):
    """A diffuse material coloured by the Attribute node (type Instancer) `attribute`'s output."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = 'INSTANCER', attribute
    s = a.outputs[output]
    if ramp:
        r = nt.nodes.new('ShaderNodeValToRGB')
        r.color_ramp.elements[0].color = (1, 0.1, 0, 1)
        r.color_ramp.elements[1].color = (0, 0.3, 1, 1)
        nt.links.new(s, r.inputs['Fac'])
        s = r.outputs['Color']
    nt.links.new(s, d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def quad(name, location=(0, 100, 0), materials=()):
    return scenes.plane(name, size=0.36, location=location, materials=materials)


def _store(ng, geometry, name, data_type, value_of_index):
    """Store Named Attribute `name` of `data_type` on the Instance domain, valued by
    value_of_index(ng, index socket) -> socket."""
    st = ng.nodes.new('GeometryNodeStoreNamedAttribute')
    st.data_type, st.domain = data_type, 'INSTANCE'
    st.inputs['Name'].default_value = name
    ng.links.new(geometry, st.inputs['Geometry'])
    ng.links.new(value_of_index(ng, ng.nodes.new('GeometryNodeInputIndex').outputs[0]), st.inputs['Value'])
    return st.outputs[0]


def colour_of(ng, index):
    """(0.15 + 0.3 i, 0.6, 0.8 - 0.3 i) as a colour."""
    m = ng.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = 0.3, 0.15
    ng.links.new(index, m.inputs[0])
    m2 = ng.nodes.new('ShaderNodeMath')
    m2.operation = 'MULTIPLY_ADD'
    m2.inputs[1].default_value, m2.inputs[2].default_value = -0.3, 0.8
    ng.links.new(index, m2.inputs[0])
    c = ng.nodes.new('FunctionNodeCombineColor')
    ng.links.new(m.outputs[0], c.inputs[0])
    c.inputs[1].default_value = 0.6
    ng.links.new(m2.outputs[0], c.inputs[2])
    return c.outputs[0]


def fraction_of(ng, index):
    """0.1 + 0.35 i"""
    m = ng.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = 0.35, 0.1
    ng.links.new(index, m.inputs[0])
    return m.outputs[0]


def vector_of(ng, index):
    """(0.2 + 0.3 i, 0.7, 0.25)"""
    v = ng.nodes.new('ShaderNodeCombineXYZ')
    ng.links.new(fraction_of(ng, index), v.inputs[0])
    v.inputs[1].default_value, v.inputs[2].default_value = 0.7, 0.25
    return v.outputs[0]


def odd_of(ng, index):
    """index % 2 (a boolean or an integer)"""
    m = ng.nodes.new('FunctionNodeIntegerMath')
    m.operation = 'MODULO'
    m.inputs[1].default_value = 2
    ng.links.new(index, m.inputs[0])
    return m.outputs[0]


def instancer(name, points, source, stores=(), join_own=False, as_instance=True, nested=None,
              location=(0, 0, 0)):
    """A mesh object of `points` whose Geometry Nodes put `source` (an object) on each of them
    (As Instance: object instances; off: geometry instances), then store `stores` ((name,
    type, value_of_index)...) on those instances; `nested` (points, stores): the instances put
    as one instance on each of those points in turn, storing these there; join_own: the
    object's own mesh (its faces) kept beside them."""
    me = bpy.data.meshes.new(name)
    faces = [(len(points), len(points) + 1, len(points) + 2, len(points) + 3)] if join_own else []
    verts = list(points) + ([(x + 1.0, y + points[0][1], 0) for x, y, _ in ((-.18, -.18, 0), (.18, -.18, 0), (.18, .18, 0),
                                                             (-.18, .18, 0))] if join_own else [])
    me.from_pydata(verts, [], faces)
    ob = bpy.data.objects.new(name, me)
    ob.location = location
    bpy.context.scene.collection.objects.link(ob)
    ng = bpy.data.node_groups.new(name, 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    pts = gi.outputs[0]
    if join_own:
        # the loose vertices carry the instances, the face stays
        sep = ng.nodes.new('GeometryNodeSeparateGeometry')
        sep.domain = 'POINT'
        idx = ng.nodes.new('GeometryNodeInputIndex')
        cmp = ng.nodes.new('FunctionNodeCompare')
        cmp.data_type, cmp.operation = 'INT', 'LESS_THAN'
        cmp.inputs[3].default_value = len(points)
        ng.links.new(idx.outputs[0], cmp.inputs[2])
        ng.links.new(gi.outputs[0], sep.inputs['Geometry'])
        ng.links.new(cmp.outputs[0], sep.inputs['Selection'])
        pts = sep.outputs['Selection']
        own = ng.nodes.new('GeometryNodeDeleteGeometry')
        own.domain = 'POINT'
        ng.links.new(gi.outputs[0], own.inputs['Geometry'])
        ng.links.new(cmp.outputs[0], own.inputs['Selection'])
    info = ng.nodes.new('GeometryNodeObjectInfo')
    info.inputs[0].default_value = source
    info.inputs['As Instance'].default_value = as_instance
    iop = ng.nodes.new('GeometryNodeInstanceOnPoints')
    ng.links.new(pts, iop.inputs['Points'])
    ng.links.new(info.outputs['Geometry'], iop.inputs['Instance'])
    out = iop.outputs[0]
    for st in stores:
        out = _store(ng, out, *st)
    if nested is not None:
        outer_points, outer_stores = nested
        # the outer points: a mesh object's vertices (not in the scene)
        om = bpy.data.meshes.new(name + "Outer")
        om.from_pydata(list(outer_points), [], [])
        oob = bpy.data.objects.new(name + "Outer", om)
        oi = ng.nodes.new('GeometryNodeObjectInfo')
        oi.inputs[0].default_value = oob
        iop2 = ng.nodes.new('GeometryNodeInstanceOnPoints')
        ng.links.new(oi.outputs['Geometry'], iop2.inputs['Points'])
        ng.links.new(out, iop2.inputs['Instance'])
        out = iop2.outputs[0]
        for st in outer_stores:
            out = _store(ng, out, *st)
    if join_own:
        j = ng.nodes.new('GeometryNodeJoinGeometry')
        ng.links.new(out, j.inputs[0])
        ng.links.new(own.outputs[0], j.inputs[0])
        out = j.outputs[0]
    ng.links.new(out, go.inputs[0])
    ob.modifiers.new("GN", 'NODES').node_group = ng
    return ob


def render_both(sc, tmp_path, samples=4):
    """Both engines' RGB (H, W, 3) under an orthographic view from above and a sun straight
    down, direct light only (test_color_attributes' set-up, at this file's size)."""
    sc.render.resolution_x, sc.render.resolution_y = W, H
    return _render_both(sc, tmp_path, SCALE, samples)


def at(img, x, y):
    """The pixel at world (x, y)."""
    return img[int(H / 2 + y * W / SCALE), int(W / 2 + x * W / SCALE)]      # (rows bottom up)


def fresh():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    return bpy.context.scene


XS = (-1.5, -1.0, -0.5)


def test_geometry_nodes_instance_attributes_match_cycles(tmp_path, said):
    """Rows of three instances each: a colour on object instances; a number through a Color
    Ramp on geometry instances (the instancer's own output); an integer, a boolean and a vector
    on object instances; nested instances (3 inner x 2 outer, both storing 'icol': the inner
    one's, as Cycles); and beside them an instancer's own face (its custom property) and a
    realized copy (a plain object with the property: Cycles reads no instance there)."""
    sc = fresh()
    col = instancer_material("Col", 'icol')
    src = quad("Src", materials=(col,))
    rows = {1.25: instancer("Colours", [(x, 1.25, 0) for x in XS], src, [('icol', 'FLOAT_COLOR', colour_of)],
                            join_own=True)}
    rows[1.25]['icol'] = (0.7, 0.3, 0.1)           # its own face reads this, the instances theirs
    rows[1.25].data.materials.append(col)
    fac_src = quad("FacSrc", materials=(instancer_material("Fac", 'ifac', 'Fac', ramp=True),))
    rows[0.75] = instancer("Numbers", [(x, 0.75, 0) for x in XS], fac_src, [('ifac', 'FLOAT', fraction_of)],
                           as_instance=False)
    int_src = quad("IntSrc", materials=(instancer_material("Int", 'iint', 'Fac'),))
    rows[0.25] = instancer("Ints", [(x, 0.25, 0) for x in XS], int_src, [('iint', 'INT', odd_of)])
    vec_src = quad("VecSrc", materials=(instancer_material("Vec", 'ivec'),))
    rows[-0.25] = instancer("Vectors", [(x, -0.25, 0) for x in XS], vec_src, [('ivec', 'FLOAT_VECTOR', vector_of)])
    # nested: inner instances along x at y=0, put on two outer points
    rows[-0.75] = instancer("Nested", [(x, 0, 0) for x in XS], src, [('icol', 'FLOAT_COLOR', colour_of)],
                            nested=([(0, -0.75, 0), (0, -1.25, 0)], [('icol', 'FLOAT_COLOR', vector_of),
                                                                     ('iouter', 'FLOAT', fraction_of)]))
    bool_src = quad("BoolSrc", materials=(instancer_material("Bool", 'ibool'),))
    instancer("Bools", [(x, 0, 0) for x in (0.5, 1.0)], bool_src, [('ibool', 'BOOLEAN', odd_of)],
              location=(0, -0.75, 0))
    outer_src = quad("OuterSrc", materials=(instancer_material("Outer", 'iouter', 'Fac', ramp=True),))
    instancer("OuterOnly", [(0, 0, 0)], outer_src, (),
              nested=([(x, -1.25, 0) for x in (0.5, 1.0, 1.5)], [('iouter', 'FLOAT', fraction_of)]))
    plain = quad("Realized", location=(1.0, 0.25, 0), materials=(col,))
    plain['icol'] = (0.2, 0.9, 0.4)
    quad("Nothing", location=(1.0, -0.25, 0), materials=(col,))      # no instance, no property: 0
    cells = [(x, y) for y in (1.25, 0.75, 0.25, -0.25, -0.75, -1.25) for x in XS]
    cells += [(1.0, 1.25), (1.0, 0.25), (1.0, -0.25), (0.5, -0.75), (1.0, -0.75), (0.5, -1.25), (1.0, -1.25), (1.5, -1.25)]
    imgs = render_both(sc, tmp_path)
    c = np.array([at(imgs['CYCLES'], x, y) for x, y in cells])
    d = np.array([at(imgs['DACRT'], x, y) for x, y in cells])
    assert len({tuple(np.round(v, 2)) for v in c}) >= 12, c.round(3).tolist()     # they differ
    assert np.abs(c - d).max() < 2e-3, (np.abs(c - d).max(axis=1).round(4).tolist(), c.round(3).tolist(),
                                        d.round(3).tolist())
    assert not [s for s in said if 'instancer attribute' in s and 'not read' in s], said


def ids_of(ng, index):
    """7 - 3 (index % 2): the ids 7, 4, 7 (the third collides: Blender gives it a random one)"""
    m = ng.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = -3.0, 7.0
    ng.links.new(odd_of(ng, index), m.inputs[0])
    return m.outputs[0]


def test_collection_particle_and_id_instances_match_cycles(tmp_path):
    """Collection instances read the instancer's property (an empty's 'icol'), else the
    member's own, else 0; particle instances the particle settings' property; Geometry Nodes
    instances with an 'id' attribute (7, 4, 7: the third collides) their own colours; the Alpha
    of a name nowhere (Cycles: 0, not 1) and of a stored colour (1); a Geometry Nodes instancer
    inside a collection instance (its attribute before the empty's property) and inside a
    Collection Info instance (the inner instancer's before the outer's)."""
    sc = fresh()
    col = instancer_material("Col", 'icol')
    members = []
    for i, (x, own) in enumerate(((-1.5, (0.1, 0.1, 0.1)), (-1.0, (0.9, 0.5, 0.2)), (-0.5, None))):
        coll = bpy.data.collections.new(f"C{i}")
        m = quad(f"Member{i}", location=(0, 0, 0), materials=(col,))
        sc.collection.objects.unlink(m)
        coll.objects.link(m)
        if own is not None:
            m['icol'] = own
        e = bpy.data.objects.new(f"Empty{i}", None)
        e.instance_type, e.instance_collection = 'COLLECTION', coll
        e.location = (x, 1.25, 0)
        sc.collection.objects.link(e)
        members.append(e)
    members[0]['icol'] = (0.3, 0.5, 0.9)              # the instancer's, before the member's
    # particles: one on each of three vertices, the instanced quad at size 1
    emitter = scenes.mesh("Emitter", [(x, 0.75, 0) for x in XS], [])
    ps = emitter.modifiers.new("P", 'PARTICLE_SYSTEM').particle_system.settings
    ps.count, ps.frame_start, ps.frame_end, ps.lifetime = 3, 1, 1, 100
    ps.emit_from, ps.use_emit_random, ps.physics_type = 'VERT', False, 'NO'
    ps.render_type, ps.instance_object, ps.particle_size = 'OBJECT', quad("PartSrc", materials=(col,)), 1.0
    ps['icol'] = (0.8, 0.4, 0.6)
    ps.normal_factor = 0.0
    emitter.show_instancer_for_render = False
    src = quad("Src", materials=(col,))
    instancer("Ids", [(x, 0.25, 0) for x in XS], src, [('id', 'INT', ids_of), ('icol', 'FLOAT_COLOR', colour_of)])
    alpha_src = quad("AlphaSrc", materials=(instancer_material("Missing", 'nowhere', 'Alpha'),))
    instancer("Alphas", [(-1.5, -0.25, 0)], alpha_src, [('icol', 'FLOAT_COLOR', colour_of)])
    present = quad("PresentSrc", materials=(instancer_material("Present", 'icol', 'Alpha'),))
    instancer("Present", [(-1.0, -0.25, 0)], present, [('icol', 'FLOAT_COLOR', colour_of)])
    # a Geometry Nodes instancer inside a collection instance (an empty with its own 'icol':
    # the inner instancer's attribute comes first)
    inner = instancer("InnerGN", [(x, 0, 0) for x in XS], src, [('icol', 'FLOAT_COLOR', colour_of)])
    sc.collection.objects.unlink(inner)
    held = bpy.data.collections.new("Held")
    held.objects.link(inner)
    e = bpy.data.objects.new("HeldEmpty", None)
    e.instance_type, e.instance_collection, e.location = 'COLLECTION', held, (0, -0.75, 0)
    e['icol'] = (0.5, 0.5, 0.5)
    sc.collection.objects.link(e)
    # ... and inside a collection a Geometry Nodes Collection Info instances (whose own
    # instances store another colour)
    deep = instancer("DeepGN", [(x, 0, 0) for x in (0.5, 1.0, 1.5)], src, [('icol', 'FLOAT_COLOR', colour_of)])
    sc.collection.objects.unlink(deep)
    deep_coll = bpy.data.collections.new("Deep")
    deep_coll.objects.link(deep)
    outer = instancer("ByCollection", [(0, -1.25, 0)], src, [('icol', 'FLOAT_COLOR', vector_of)])
    ng = outer.modifiers[0].node_group
    ci = ng.nodes.new('GeometryNodeCollectionInfo')
    ci.inputs['Collection'].default_value = deep_coll
    iop = next(n for n in ng.nodes if n.bl_idname == 'GeometryNodeInstanceOnPoints')
    ng.links.new(ci.outputs[0], iop.inputs['Instance'])
    cells = [(x, y) for y in (1.25, 0.75, 0.25) for x in XS] + [(-1.5, -0.25), (-1.0, -0.25)]
    cells += [(x, -0.75) for x in XS] + [(x, -1.25) for x in (0.5, 1.0, 1.5)]
    imgs = render_both(sc, tmp_path)
    c = np.array([at(imgs['CYCLES'], x, y) for x, y in cells])
    d = np.array([at(imgs['DACRT'], x, y) for x, y in cells])
    assert len({tuple(np.round(v, 2)) for v in c}) >= 8, c.round(3).tolist()
    assert np.abs(c - d).max() < 2e-3, (np.abs(c - d).max(axis=1).round(4).tolist(), c.round(3).tolist(),
                                        d.round(3).tolist())
