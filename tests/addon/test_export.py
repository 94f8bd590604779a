"""Export correctness on scenes built in bpy: what the engine hands the integrator.

Every test renders through the registered engine (render depsgraph, as F12 does) and checks
the SceneData it exported (see conftest.exported)."""
import math

import bpy
import numpy as np
import pytest
from mathutils import Euler, Vector

from addon import export, hair, pointcloud, specular
from addon import lights as ls
from addon import scenedata as sd
from addon.export.meshes import color_attribute_key
from addon.procedural import ProceduralTexels
from addon.texture import srgb_to_linear, stored_texels

from . import scenes


def tri_area(g, mask=None):
    v = g.vertices[g.triangles if mask is None else g.triangles[mask]].astype(np.float64)
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum()


def corners(g, mask=None):
    """All triangle corner positions (N*3, 3), float64."""
    return g.vertices[g.triangles if mask is None else g.triangles[mask]].reshape(-1, 3).astype(np.float64)


def of_object(data, name):
    return data.geometry.object_index == data.object_names.index(name)


def setup(scene):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))


# -- geometry ------------------------------------------------------------------------------

def test_array_modifier_world_positions(scene, exported):
    setup(scene)
    ob = scenes.cube("Cube")
    ob.modifiers.new("Array", 'ARRAY').count = 3        # relative offset 1: copies 2 apart in x
    ob.location = (1.0, 2.0, 3.0)
    ob.rotation_euler = (0.0, 0.0, math.pi / 2)
    data = exported()
    g = data.geometry
    assert len(g.triangles) == 3 * 12
    assert tri_area(g) == pytest.approx(3 * 24.0, rel=1e-5)
    M = np.array(ob.matrix_world)
    local = np.array([(x + 2 * k, y, z) for k in range(3) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    expected = local @ M[:3, :3].T + M[:3, 3]
    d = np.linalg.norm(corners(g)[:, None] - expected[None], axis=2).min(axis=1)
    assert d.max() < 1e-5, "every exported corner is a corner of one of the three cubes"
    # rotated by 90 degrees about z: the array runs along world +y from y=2-1 to y=2+5
    assert g.vertices[:, 1].min() == pytest.approx(1.0, abs=1e-5)
    assert g.vertices[:, 1].max() == pytest.approx(7.0, abs=1e-5)


def _instance(scene, ob, placements):
    """Move ob into a new collection (still rendered once where it is) and add an empty
    instancing that collection per (location, scale) of placements."""
    col = bpy.data.collections.new(ob.name + "Parts")
    scene.collection.children.link(col)
    scene.collection.objects.unlink(ob)
    col.objects.link(ob)
    for i, (loc, scale) in enumerate(placements):
        e = scenes.link(bpy.data.objects.new(f"{ob.name}Inst{i}", None))
        e.instance_type, e.instance_collection = 'COLLECTION', col
        e.location, e.scale = loc, scale


def test_collection_instances_read_mesh_once_and_transform_each(scene, exported):
    setup(scene)
    sphere = scenes.uv_sphere("Ball", radius=1.0, segments=8, rings=4, smooth=False)
    _instance(scene, sphere, [((10, 0, 0), (1.0, 1.0, 1.0)), ((20, 0, 0), (2.0, 2.0, 2.0))])
    data = exported()
    g = data.geometry
    per = len(sphere.data.polygons) + len([p for p in sphere.data.polygons if len(p.vertices) == 4])
    assert len(g.triangles) == 3 * per         # the original plus two instances
    c = corners(g)
    for x0, r in ((0, 1.0), (10, 1.0), (20, 2.0)):
        sel = np.abs(c[:, 0] - x0) < 3
        dist = np.linalg.norm(c[sel] - (x0, 0, 0), axis=1)
        assert np.allclose(dist, r, atol=1e-5), f"instance at x={x0} has radius {r}"


def test_emissive_instances_are_lights_of_their_own(scene, exported):
    """Each placement of a mesh (the object, every collection instance, every Geometry Nodes
    instance) has its own instance id, so the light tree holds each emissive instance as a
    light of its own (one object id for all of them made them one leaf, sampled by power
    wherever the shading point was)."""
    from addon.integrator import Integrator
    setup(scene)
    bulb = scenes.uv_sphere("Bulb", radius=0.2, segments=8, rings=4)
    bulb.data.materials.append(scenes.emission("Glow", (1.0, 0.9, 0.7), 20.0))
    _instance(scene, bulb, [((3.0 * i, 0.0, 2.0), (1.0, 1.0, 1.0)) for i in range(1, 5)])
    field = scenes.plane("Field")
    _gn_instances(field, 3, 2, 8.0)
    ng = field.modifiers["GN"].node_group                        # the cones made emissive
    setmat = ng.nodes.new('GeometryNodeSetMaterial')
    setmat.inputs['Material'].default_value = scenes.emission("Cones", (0.5, 0.5, 1.0), 5.0)
    ng.links.new(ng.nodes['Cone'].outputs['Mesh'], setmat.inputs['Geometry'])
    ng.links.new(setmat.outputs['Geometry'], ng.nodes['Instance on Points'].inputs['Instance'])
    field.location = (0, 0, -3)
    scenes.light('POINT', 100.0, (0, 0, 5))
    data = exported()
    g = data.geometry
    bulbs, cones = of_object(data, "Bulb"), ~of_object(data, "Bulb")
    assert len(np.unique(g.object_index[bulbs])) == 1            # one object ...
    ids = np.unique(g.instance[bulbs])
    assert len(ids) == 5                                         # ... placed five times
    for i in ids:                                                # each id one whole sphere
        c = corners(g, g.instance == i)
        assert np.ptp(c, axis=0).max() == pytest.approx(0.4, abs=1e-4)
    assert len(np.unique(g.instance[cones])) == 6 and not set(g.instance[cones]) & set(ids)
    integ = Integrator(data)
    try:
        lights = integ.lights
        assert lights.tree is not None and lights.tree.nodes == 2 * (1 + 5 + 6) - 1     # 12 leaves
        # half a metre under one bulb, looking up: the tree picks that bulb, not by power
        tris = lights.triangles
        inst = g.instance[tris.index]
        v0 = tris.geo[0:3].T                                     # (the integrator's frame)
        near, far = ids[1], ids[-1]
        P = (v0[inst == near].mean(axis=0) - (0.0, 0.0, 0.5)).astype(np.float32)
        key = lights.num_lamps + np.array([np.flatnonzero(inst == near)[0], np.flatnonzero(inst == far)[0]])
        pdf = lights.tree.pdf(np.repeat(P[:, None], 2, axis=1), key, np.tile(np.float32([[0], [0], [1]]), 2))
        assert pdf[0] > 10 * pdf[1], pdf
    finally:
        integ.close()


def test_many_smooth_instances_keep_outward_normals(scene, exported):
    """Six instances (the batched transform path) of a smooth sphere, scaled unevenly and one
    mirrored: every corner normal is the object's vertex normal by the inverse transpose, not
    normalized (Cycles transforms an instanced mesh's interpolated normal at each hit, so the
    renderer interpolates these and then normalizes: normalized first, a smooth cylinder
    scaled (4, 1, 1) as linked duplicates was 0.31-1.06x Cycles across its bands), and follows
    the ellipsoid's gradient."""
    setup(scene)
    ball = scenes.uv_sphere("Ball", radius=1.0, segments=16, rings=8, smooth=True)
    scales = [(1, 1, 1), (2, 1, 1), (1, 3, 1), (1, 1, 0.5), (-1, 1, 1), (2, 2, 2)]
    _instance(scene, ball, [((10.0 * (i + 1), 0.0, 0.0), s) for i, s in enumerate(scales)])
    g = exported().geometry
    vn = np.array([v.vector for v in ball.data.vertex_normals], np.float64)
    nv = len(vn)
    c = g.vertices[g.triangles].astype(np.float64)                 # (M, 3, 3) corners
    for i, s in enumerate(scales):
        sel = np.abs(c[:, 0, 0] - 10.0 * (i + 1)) < 5
        local = (c[sel] - (10.0 * (i + 1), 0, 0)) / np.abs(np.asarray(s, np.float64))
        grad = local / np.abs(np.asarray(s, np.float64))           # gradient of sum (x_k / s_k)^2
        grad /= np.linalg.norm(grad, axis=2, keepdims=True)
        n = g.normals[sel] / np.linalg.norm(g.normals[sel], axis=2, keepdims=True)
        cos = np.einsum('ijk,ijk->ij', n, grad)
        assert sel.sum() == 16 * 8 * 2 - 2 * 16 and cos.min() > 0.97, f"instance {i} (scale {s})"
        want = vn[g.triangles[sel] % nv] / np.asarray(s, np.float64)   # M^-T n, M = diag(s)
        np.testing.assert_allclose(g.normals[sel], want, atol=1e-5, err_msg=f"instance {i} (scale {s})")


def test_linked_duplicates_with_object_linked_materials_are_single_users(scene, exported):
    """Two objects sharing a smooth mesh, scaled (4, 1, 1), with their material slots linked to
    the object: Cycles gives each its own geometry, shaded as a single user (normals normalized
    per vertex after the transform), as a copy of the mesh is; they had been shaded as
    instances (0.80-1.11x Cycles across the bands). Data-linked slots stay instances."""
    setup(scene)
    ball = scenes.uv_sphere("A", radius=1.0, segments=8, rings=4, smooth=True)
    ball.scale = (4, 1, 1)
    twin = scenes.link(bpy.data.objects.new("B", ball.data))
    twin.location, twin.scale = (0, 5, 0), (4, 1, 1)
    copy = scenes.link(bpy.data.objects.new("C", ball.data.copy()))
    copy.location, copy.scale = (0, 10, 0), (4, 1, 1)
    paint = scenes.diffuse("Paint", (0.5, 0.5, 0.5))
    for ob in (ball, twin, copy):
        ob.data.materials.clear()
        ob.data.materials.append(paint)
    for ob in (ball, twin):
        ob.material_slots[0].link = 'OBJECT'
        ob.material_slots[0].material = paint
    g = exported().geometry
    c = g.vertices[g.triangles].astype(np.float64)
    by_y = lambda y: np.abs(c[:, 0, 1] - y) < 2.0
    for y in (0.0, 5.0):
        np.testing.assert_allclose(g.normals[by_y(y)], g.normals[by_y(10.0)], atol=1e-5, err_msg=str(y))
    for ob in (ball, twin):
        ob.material_slots[0].link = 'DATA'
    g = exported().geometry
    assert not np.allclose(g.normals[by_y(0.0)], g.normals[by_y(10.0)], atol=1e-3)


def _gn_instances(ob, points_x, points_y, size):
    ng = bpy.data.node_groups.new("Scatter", 'GeometryNodeTree')
    ng.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    out = ng.nodes.new('NodeGroupOutput')
    grid = ng.nodes.new('GeometryNodeMeshGrid')
    grid.inputs['Vertices X'].default_value = points_x
    grid.inputs['Vertices Y'].default_value = points_y
    grid.inputs['Size X'].default_value = size
    grid.inputs['Size Y'].default_value = size
    cone = ng.nodes.new('GeometryNodeMeshCone')
    cone.inputs['Vertices'].default_value = 8
    inst = ng.nodes.new('GeometryNodeInstanceOnPoints')
    ng.links.new(grid.outputs['Mesh'], inst.inputs['Points'])
    ng.links.new(cone.outputs['Mesh'], inst.inputs['Instance'])
    ng.links.new(inst.outputs['Instances'], out.inputs[0])
    mod = ob.modifiers.new("GN", 'NODES')
    mod.node_group = ng


def test_geometry_nodes_instances(scene, exported):
    setup(scene)
    ob = scenes.plane("Scatter")
    _gn_instances(ob, 3, 2, 8.0)
    ob.location = (0, 0, 1)
    data = exported()
    g = data.geometry
    # one cone with 8 vertices: 8 side triangles + an 8-gon cap (6 triangles) = 14
    assert len(g.triangles) == 6 * 14
    c = corners(g)
    # grid 3x2 of size 8: instance points at x in {-4, 0, 4}, y in {-4, 4}; cone radius 1
    centre = np.round(c[:, :2] / 4) * 4
    assert np.linalg.norm(c[:, :2] - centre, axis=1).max() <= 1 + 1e-5
    keys, counts = np.unique(centre, axis=0, return_counts=True)
    assert {tuple(k) for k in keys.tolist()} == {(x, y) for x in (-4.0, 0.0, 4.0) for y in (-4.0, 4.0)}
    assert np.all(counts == 14 * 3)
    assert c[:, 2].min() == pytest.approx(1.0, abs=1e-5)     # cone base on the points (z=1)
    assert c[:, 2].max() == pytest.approx(3.0, abs=1e-5)     # depth 2


def test_curve_text_and_metaball_become_triangles(scene, exported, monkeypatch):
    setup(scene)
    curve = bpy.data.curves.new("Tube", 'CURVE')
    curve.dimensions = '3D'
    curve.bevel_depth = 0.1
    spline = curve.splines.new('POLY')
    spline.points.add(1)
    spline.points[0].co = (-1, 0, 0, 1)
    spline.points[1].co = (1, 0, 0, 1)
    scenes.link(bpy.data.objects.new("Tube", curve))
    text = bpy.data.curves.new("Label", 'FONT')
    text.body = "DACRT"
    scenes.link(bpy.data.objects.new("Label", text)).location = (0, 0, 2)
    ball = bpy.data.metaballs.new("Blob")
    ball.elements.new().radius = 1.0
    scenes.link(bpy.data.objects.new("Blob", ball)).location = (0, 0, -3)
    # the render depsgraph lists such an object as itself and as an instance of its evaluated
    # mesh; Cycles renders that mesh alone, and so once (both read, an emissive text had
    # 1.06-1.17x Cycles' light)
    evaluated = {}
    real_init = export.scene.Exporter.__init__

    def init(self, depsgraph, *args):
        evaluated.update({i.parent.name: len(i.object.data.loop_triangles) for i in depsgraph.object_instances
                          if i.is_instance and i.object.type == 'MESH' and i.parent is not None})
        real_init(self, depsgraph, *args)
    monkeypatch.setattr(export.scene.Exporter, '__init__', init)
    data = exported()
    for name in ("Tube", "Label", "Blob"):
        assert name in data.object_names
        assert of_object(data, name).sum() > 8, f"{name} exported as triangles"
        n = evaluated[name]                           # (less the degenerate ones dropped)
        assert n - data.skipped['triangles_degenerate'] <= of_object(data, name).sum() <= n, name
    blob = corners(data.geometry, of_object(data, "Blob"))
    assert np.abs(blob.mean(axis=0) - (0, 0, -3)).max() < 0.1


def _instanced_in_a_grid(scene, ob, count):
    """Move ob into a collection of its own (not in the scene) and instance that collection
    `count` times, 20 to a row, 1 apart."""
    props = bpy.data.collections.new(ob.name + "Set")
    for c in list(ob.users_collection):
        c.objects.unlink(ob)
    props.objects.link(ob)
    for i in range(count):
        empty = bpy.data.objects.new(f"{ob.name}{i}", None)
        empty.instance_type, empty.instance_collection = 'COLLECTION', props
        empty.location = (i % 20, i // 20, 0)
        scene.collection.objects.link(empty)


def test_instanced_hair_emitters_share_the_frames_tube_budget(scene, exported):
    """An emitter with hair particles instanced 400 times: its strands are tessellated at the
    level for all the frame's hair points (each instance had taken the level of one emitter's
    strands), and each strand keeps its system's material slot."""
    setup(scene)
    emitter = scenes.plane("Emitter", size=1, materials=[scenes.diffuse("Skin", (0.2, 0.2, 0.2)),
                                                         scenes.diffuse("Fur", (0.9, 0.6, 0.3))])
    emitter.modifiers.new("hair", 'PARTICLE_SYSTEM')
    hs = emitter.particle_systems[0].settings
    hs.type, hs.count, hs.hair_length, hs.material = 'HAIR', 10, 0.5, 2
    _instanced_in_a_grid(scene, emitter, 400)
    data = exported()
    g = data.geometry
    names = np.array([m.name for m in data.materials])[g.material]
    fur = of_object(data, "Emitter") & (names == "Fur")
    sides, steps = hair.level_for(400 * 10 * 9)
    assert (sides, steps) != hair.level_for(10 * 9)
    per_strand = 8 * steps * sides * 2 - sides        # 2^3 + 1 points; the closed tip a cone
    assert fur.sum() == 400 * 10 * per_strand, (fur.sum(), 400 * 10 * per_strand)


def test_particle_instances_and_hair_strands(scene, exported):
    """Object particles are instances; hair particles are strands rendered as tubes, as Cycles
    reads them: co_hair's points (2^render_step + 1 a strand), children instead of the parents
    when there are children, the radius from the Hair Shape settings, tessellated in the
    emitter's object space, with the material slot the settings name."""
    setup(scene)
    emitter = scenes.plane("Emitter", size=4, materials=[scenes.diffuse("Skin", (0.2, 0.2, 0.2)),
                                                         scenes.diffuse("Fur", (0.9, 0.6, 0.3))])
    leaf = scenes.cube("Leaf", size=0.2, location=(50, 0, 0))
    emitter.modifiers.new("ps", 'PARTICLE_SYSTEM')
    ps = emitter.particle_systems[0].settings
    ps.count, ps.frame_start, ps.frame_end = 10, 1, 1
    ps.render_type, ps.instance_object = 'OBJECT', leaf
    ps.particle_size, ps.physics_type = 1.0, 'NO'
    emitter.modifiers.new("hair", 'PARTICLE_SYSTEM')
    hair_settings = emitter.particle_systems[1].settings
    hair_settings.type, hair_settings.count, hair_settings.hair_length = 'HAIR', 5, 1.0
    hair_settings.material, hair_settings.use_close_tip = 2, False
    hair_settings.root_radius, hair_settings.tip_radius, hair_settings.radius_scale = 1.0, 1.0, 0.02
    data = exported()
    leaves = of_object(data, "Leaf")
    assert leaves.sum() == 12 * 11       # the leaf object itself plus ten particle instances
    g = data.geometry
    em = of_object(data, "Emitter")
    names = np.array([m.name for m in data.materials])[g.material]
    plane, strands = em & (names == "Skin"), em & (names == "Fur")
    assert plane.sum() == 2
    sides, steps = hair.level_for(5 * 9)
    assert strands.sum() == 5 * 8 * steps * sides * 2       # 5 strands of 2^3 + 1 points
    c = corners(g, strands)
    assert c[:, 2].min() == pytest.approx(0.0, abs=1e-4) and c[:, 2].max() == pytest.approx(1.0, abs=1e-3)
    ring = np.pi / (sides * np.sin(np.pi / sides))
    # straight strands along +z, one after another: every corner at radius_scale / 2 (times
    # the ring's perimeter scale) from its strand's axis
    per = c.reshape(5, -1, 3)
    off_axis = np.linalg.norm(per[:, :, :2] - per[:, :, :2].mean(axis=1, keepdims=True), axis=2)
    assert np.allclose(off_axis, 0.5 * 0.02 * ring, rtol=1e-3)
    text = " | ".join(m for _, m in data.messages)
    assert "'Emitter': hair particles rendered as tubes" in text
    # children replace their parents
    hair_settings.child_type, hair_settings.rendered_child_count = 'INTERPOLATED', 3
    data = exported()
    names = np.array([m.name for m in data.materials])[data.geometry.material]
    assert (of_object(data, "Emitter") & (names == "Fur")).sum() == 15 * 8 * steps * sides * 2
    scene.view_layers[0].use_strand = False
    data = exported()
    assert "off in the view layer" in " | ".join(m for _, m in data.messages)
    assert of_object(data, "Emitter").sum() == 2


def test_instanced_hair_emitter_places_its_hair(scene, exported):
    """An emitter's hair is tessellated once, in its object space, and placed by the emitter
    and by each of its collection instances, as Cycles renders an instanced emitter's hair (it
    was skipped, reported: a tester's two instances rendered 18.5% off Cycles)."""
    setup(scene)
    em = scenes.plane("Furry", size=1)
    em.modifiers.new("hair", 'PARTICLE_SYSTEM')
    em.particle_systems[0].settings.type, em.particle_systems[0].settings.count = 'HAIR', 3
    _instance(scene, em, [((5, 0, 0), (1, 1, 1))])
    data = exported()
    text = " | ".join(m for _, m in data.messages)
    assert "not rendered" not in text
    assert "'Furry': hair particles rendered as tubes" in text
    g = data.geometry
    mine = np.flatnonzero(of_object(data, "Furry"))
    hair = mine[np.abs(g.vertices[g.triangles[mine]][..., 2]).max(axis=1) > 1e-6]   # off the planes
    assert len(hair) > 0 and len(hair) % 2 == 0
    c = g.vertices[g.triangles[hair]].reshape(2, -1, 3, 3)     # the emitter's strands, then the instance's
    assert np.allclose(np.abs(c[1] - c[0]), (5, 0, 0), atol=1e-5)


def test_point_cloud_becomes_spheres_with_its_material(scene, exported):
    """Geometry Nodes points (Mesh to Points) are spheres of their radius around each point,
    in world space, with the point cloud's material; the tessellation is reported."""
    setup(scene)
    mat = scenes.diffuse("Dots", (0.9, 0.2, 0.1))
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.5]], np.float64)
    ob = scenes.point_cloud("Scatter", pts, radius=0.1, material=mat)
    ob.location = (0, 0, 2)
    data = exported()
    g = data.geometry
    names = [data.object_names[i] for i in np.unique(g.object_index)]
    assert names == ["Scatter"]
    level = pointcloud.level_for(3)
    per = len(pointcloud.unit_sphere(level)[1])
    assert len(g.triangles) == 3 * per
    c = corners(g).reshape(3, per * 3, 3)                 # one sphere after another
    scale = pointcloud.unit_sphere(level)[2]
    for k in range(3):
        assert np.allclose(c[k].mean(axis=0), pts[k] + (0, 0, 2), atol=1e-4)
        assert np.allclose(np.linalg.norm(c[k] - pts[k] - (0, 0, 2), axis=1), 0.1 * scale, rtol=1e-4)
    assert {data.materials[m].name for m in np.unique(g.material)} == {"Dots"}
    assert tri_area(g) == pytest.approx(3 * 4 * np.pi * 0.01, rel=1e-4)
    text = " | ".join(m for _, m in data.messages)
    assert "'Scatter': point clouds rendered as spheres" in text and "not rendered" not in text


def test_point_cloud_default_radius_and_hair_curves(scene, exported):
    """Points without a radius attribute take Cycles' 0.01; a Curves object becomes one tube
    per curve of 2+ points with its radius (Cycles' 0.005 without the attribute); hair off in
    the view layer's filter skips the curves, as Cycles does."""
    setup(scene)
    scenes.point_cloud("Bare", np.zeros((1, 3)), radius=None)
    z = np.linspace(0, 1, 4)[:, None] * (0, 0, 1)
    scenes.hair_curves("Fur", [z, z + (1, 0, 0), [[5, 5, 5]]], radius=0.02)
    scenes.hair_curves("Fuzz", [z + (3, 0, 0)])
    data = exported()
    g = data.geometry
    bare = corners(g, of_object(data, "Bare"))
    scale = pointcloud.unit_sphere(pointcloud.level_for(1))[2]
    assert np.linalg.norm(bare, axis=1).max() == pytest.approx(pointcloud.DEFAULT_RADIUS * scale, rel=1e-4)
    sides, steps = hair.level_for(9)
    assert of_object(data, "Fur").sum() == 2 * 3 * steps * sides * 2
    fur = corners(g, of_object(data, "Fur"))
    ring = np.pi / (sides * np.sin(np.pi / sides))
    off_axis = np.linalg.norm((fur - np.round(fur[:, :1]) * (1, 0, 0))[:, :2], axis=1)
    assert np.allclose(off_axis.max(), 0.02 * ring, rtol=1e-4)
    fuzz = corners(g, of_object(data, "Fuzz"))
    assert np.linalg.norm(fuzz[:, :2] - (3, 0), axis=1).max() == pytest.approx(hair.DEFAULT_RADIUS * ring, rel=1e-4)
    text = " | ".join(m for _, m in data.messages)
    assert "hair curves rendered as tubes" in text and "'Fur': curves of fewer than 2 points" in text
    scene.view_layers[0].use_strand = False
    data = exported()
    assert "Fur" not in data.object_names and "Bare" in data.object_names
    assert "off in the view layer" in " | ".join(m for _, m in data.messages)


def test_poly_curves_are_straight_between_their_points(scene, exported):
    """Curves of type Poly (what Curve Line, Curve Circle, Mesh to Curve and Resample make) are
    straight between their points, as Cycles draws them: every tube vertex lies within the
    ring's radius of a segment of the zig-zag (a Catmull-Rom tube had rounded the corners off,
    in Cycles 24 strand pixels at the peaks, DACRT 15); Catmull-Rom curves stay smooth."""
    setup(scene)
    zig = np.array([[0, 0, 0], [1, 0, 1], [2, 0, 0], [3, 0, 1]], np.float64)
    poly = scenes.hair_curves("Poly", [zig], radius=0.01)
    poly.data.set_types(type='POLY')
    scenes.hair_curves("Smooth", [zig + (0, 5, 0)], radius=0.01)
    data = exported()
    sides, _ = hair.level_for(8)
    # one step a segment (with its round end caps and joints)
    assert of_object(data, "Poly").sum() == len(hair.tubes(zig, np.full(4, 0.01), [0, 4], (sides, 1), linear=True)[1])
    ring = 0.01 * np.pi / (sides * np.sin(np.pi / sides))

    def off_the_zigzag(name, shift):
        pts = corners(data.geometry, of_object(data, name)).reshape(-1, 3) - shift
        a, b = zig[:-1], zig[1:]
        u = np.clip(np.einsum('psk,sk->ps', pts[:, None] - a[None], b - a) / ((b - a) ** 2).sum(1), 0, 1)
        return np.linalg.norm(pts[:, None] - (a + u[..., None] * (b - a)), axis=2).min(axis=1).max()
    # a mitred joint's ring sits on the bisector: up to ring / cos(45 deg) from a segment
    assert off_the_zigzag("Poly", 0.0) <= ring / np.cos(np.pi / 4) * 1.001
    assert off_the_zigzag("Smooth", np.array([0, 5, 0])) > 0.05      # Catmull-Rom cuts inside
    assert "straight between their points" in " | ".join(m for _, m in data.messages)


def test_points_and_curves_generated_coordinates_are_object_space(scene):
    """Cycles' Generated coordinates of a point cloud's spheres and a Curves object's tubes are
    their object-space positions (a Gradient along x on three points at -1.2, 0, 1.2 reads 0,
    0.03, 1 there; mapping the tessellation's bounds to 0..1 had read 0.15, 0.49, 0.84)."""
    from addon import hair, pointcloud
    from addon.export import strands

    class Notes:
        def ignore(self, *a):
            pass
    cloud = scenes.point_cloud("Dots", np.array([[-1.2, 0, 0], [0, 0, 0], [1.2, 0, 0]]), radius=0.1)
    fur = scenes.hair_curves("Fur", [np.array([[-1.2, 0, 0], [1.2, 0, 0.5]])], radius=0.05)
    seen = []
    for inst in bpy.context.evaluated_depsgraph_get().object_instances:
        if inst.object.type in ('POINTCLOUD', 'CURVES'):     # the cloud: a GN output instance
            src = strands.read_strands(inst.object, Notes())
            level = (pointcloud if src.kind == 'POINTCLOUD' else hair).level_for(len(src.positions))
            coords = strands.tessellate(src, level, Notes()).corner_coordinates()
            assert np.allclose(coords[..., :3], coords[..., 3:6], atol=1e-6), inst.object.name
            seen.append(inst.object.type)
    assert sorted(seen) == ['CURVES', 'POINTCLOUD'] and cloud and fur


def test_instanced_curves_are_tessellated_for_the_frames_point_count(scene, exported):
    """The tessellation level follows the points the frame holds, instances included: a tuft of
    10 curves instanced 300 times is 24,000 points, tessellated as one object of that many
    would be (each instance had taken the finest level: 400 tufts made 10.75M triangles,
    3.4 GB, and 1600 failed to allocate; Cycles 282 MB)."""
    setup(scene)
    tuft = [np.array([[0.1 * i, 0, 0.1 * j] for j in range(8)]) for i in range(10)]
    _instanced_in_a_grid(scene, scenes.hair_curves("Tuft", tuft, radius=0.01), 300)
    data = exported()
    sides, steps = hair.level_for(300 * 80)
    assert (sides, steps) != hair.level_for(80)
    assert of_object(data, "Tuft").sum() == 300 * 10 * 7 * steps * sides * 2


def test_glass_roughness_and_the_transparent_glass_threshold_exported(scene, exported):
    """Each material's glass roughness (Glass, Refraction, transmitting Principled; the largest
    through Mix Shaders), which Film > Transparent Glass compares with its Roughness Threshold
    (read from Cycles' setting)."""
    setup(scene)
    made = {}
    for name, kind, rough in (("Frosted", 'ShaderNodeBsdfGlass', 0.5), ("Clear", 'ShaderNodeBsdfRefraction', 0.0),
                              ("Principled", 'ShaderNodeBsdfPrincipled', 0.3), ("Mixed", 'ShaderNodeBsdfGlass', 0.05)):
        mat, nt, out = _shader_material(name)
        node = nt.nodes.new(kind)
        node.inputs['Roughness'].default_value = rough
        if kind == 'ShaderNodeBsdfPrincipled':
            node.inputs['Transmission Weight'].default_value = 1.0
        src = node.outputs[0]
        if name == "Mixed":
            mix = nt.nodes.new('ShaderNodeMixShader')
            nt.links.new(src, mix.inputs[1])
            nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], mix.inputs[2])
            src = mix.outputs[0]
        nt.links.new(src, out.inputs['Surface'])
        made[name] = rough
        scenes.plane(name, location=(3 * len(made), 0, 0), materials=(mat,))
    scene.cycles.film_transparent_roughness = 0.25
    data = exported()
    got = {m.name: m.glass_roughness for m in data.materials}
    for name, rough in made.items():
        assert got[name] == pytest.approx(rough, abs=1e-6), (name, got)
    assert data.settings.film_transparent_roughness == pytest.approx(0.25)


def test_light_path_ray_type_mix_hides_the_material(scene, exported):
    """A Mix Shader by Light Path Is Camera Ray / Is Shadow Ray with a white Transparent BSDF on
    one side: the triangles lose the ray kinds that see through it and keep the other shader,
    and a clear twin of them those kinds alone see stands for the Transparent side (a pass that
    counts against Transparent Max Bounces, as Cycles counts it); a non-white transparent side
    is built per ray kind instead (rayvariants.py: a copy of the triangles for the camera's)."""
    setup(scene)
    # (the originals' visibility, the clear twins' (None: no twin))
    cases = {"NoCam": ('Is Camera Ray', 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent', (1, 1, 1),
                       sd.VIS_DIFFUSE | sd.VIS_SHADOW, sd.VIS_CAMERA | sd.NO_TRANSMISSION),
             # (rays past glass, Cycles' transmission rays, see it as bounce rays do: its clear side)
             "CamOnly": ('Is Camera Ray', 'ShaderNodeBsdfTransparent', 'ShaderNodeEmission', (1, 1, 1),
                         sd.VIS_CAMERA | sd.NO_TRANSMISSION, sd.VIS_DIFFUSE | sd.VIS_SHADOW),
             "NoShadow": ('Is Shadow Ray', 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent', (1, 1, 1),
                          sd.VIS_CAMERA | sd.VIS_DIFFUSE, sd.VIS_SHADOW | sd.NO_TRANSMISSION),
             "Tinted": ('Is Camera Ray', 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent', (0.5, 1, 1),
                        sd.VIS_DIFFUSE | sd.VIS_SHADOW, None)}
    for i, (name, (output, first, second, clear, *_)) in enumerate(cases.items()):
        mat, nt, mix, a, b = scenes.mix_shader_material(name, first, second)
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
        for node in (a, b):
            if node.type == 'BSDF_TRANSPARENT':
                node.inputs['Color'].default_value = (*clear, 1)
        scenes.plane(name, location=(3 * i, 0, 0), materials=(mat,))
    data = exported()
    twin = np.array([m.clear_twin for m in data.materials])[data.geometry.material]
    # (the camera's build of a material built per ray kind: the second of its name)
    variant = np.zeros(len(data.materials), bool)
    names = [m.name for m in data.materials]
    variant[[k for k, n in enumerate(names) if n in names[:k] and not data.materials[k].clear_twin]] = True
    variant = variant[data.geometry.material]
    for name, (*_, want, want_twin) in cases.items():
        rows = of_object(data, name)
        vis = np.unique(data.geometry.visibility[rows & ~twin & ~variant])
        assert vis.tolist() == [want], name
        assert np.unique(data.geometry.visibility[rows & twin]).tolist() == ([] if want_twin is None else [want_twin])
        assert np.count_nonzero(rows & twin) == (0 if want_twin is None else np.count_nonzero(rows & ~twin))
    by_name = {m.name: m for m in data.materials if not m.clear_twin}
    assert np.allclose(by_name["NoCam"].emission, 1.0) and by_name["NoCam"].transparency is None
    for m in data.materials:
        if m.clear_twin:        # a white Transparent BSDF: no light, no albedo
            assert np.allclose(m.transparency, 1.0) and not m.emission.any() and not m.base_color.any()
    # the tinted one: its emission for bounce rays, its tinted transparency for the camera's on
    # a copy of each triangle (it had been the own-value mix, factor 0.5, for all)
    tinted = [k for k, m in enumerate(data.materials) if m.name == "Tinted"]
    assert [data.materials[k].visibility for k in tinted] == [sd.VIS_DIFFUSE | sd.VIS_SHADOW, sd.VIS_CAMERA]
    bounce, camera = (data.materials[k] for k in tinted)
    assert np.allclose(bounce.emission, 1.0) and bounce.transparency is None
    assert not camera.emission.any() and np.allclose(camera.transparency, (0.5, 1, 1))
    rows = of_object(data, "Tinted")
    assert np.unique(data.geometry.visibility[rows & variant]).tolist() == [sd.VIS_CAMERA | sd.NO_TRANSMISSION]
    assert np.count_nonzero(rows & variant) == np.count_nonzero(rows & ~variant)


def test_material_slot_per_triangle(scene, exported):
    setup(scene)
    red, blue = scenes.diffuse("Red", (1, 0, 0)), scenes.diffuse("Blue", (0, 0, 1))
    ob = scenes.cube("Cube", materials=(red, blue))
    for p in ob.data.polygons:
        p.material_index = 1 if p.normal.z > 0.5 else 0
    data = exported()
    names = [m.name for m in data.materials]
    assert names[0] == '(default)'
    g = data.geometry
    nz = g.normals[:, 0, 2]
    assert np.all(np.array(names)[g.material[nz > 0.5]] == "Blue")
    assert np.all(np.array(names)[g.material[nz <= 0.5]] == "Red")
    assert (nz > 0.5).sum() == 2


def test_object_linked_slot_and_material_override(scene, exported):
    setup(scene)
    red, green = scenes.diffuse("Red", (1, 0, 0)), scenes.diffuse("Green", (0, 1, 0))
    a = scenes.plane("A", materials=(red,))
    b = scenes.link(bpy.data.objects.new("B", a.data))      # same mesh, object-linked material
    b.location = (3, 0, 0)
    b.material_slots[0].link = 'OBJECT'
    b.material_slots[0].material = green
    data = exported()
    name_of = lambda obj: {data.materials[i].name for i in data.geometry.material[of_object(data, obj)]}
    assert name_of("A") == {"Red"} and name_of("B") == {"Green"}
    override = scenes.diffuse("Clay", (0.5, 0.5, 0.5))
    bpy.context.view_layer.material_override = override
    data = exported()
    assert {data.materials[i].name for i in data.geometry.material} == {"Clay"}


def test_missing_slot_material_uses_default(scene, exported):
    setup(scene)
    ob = scenes.plane("P")
    ob.data.materials.append(None)
    data = exported()
    assert np.all(data.geometry.material == 0)
    assert np.allclose(data.materials[0].base_color, export.materials.DEFAULT_SURFACE_ALBEDO)


# -- normals -----------------------------------------------------------------------------

def test_flat_normals_are_outward_face_normals_even_mirrored(scene, exported):
    setup(scene)
    ob = scenes.cube("Cube")
    assert ob.data.normals_domain == 'FACE'
    ob.scale = (-1.0, 2.0, 1.0)          # mirrored: outside must stay outside
    data = exported()
    g = data.geometry
    centroid = g.vertices[g.triangles].mean(axis=1)
    n = g.normals
    assert np.allclose(n[:, 0], n[:, 1]) and np.allclose(n[:, 0], n[:, 2])
    assert np.allclose(np.abs(n[:, 0]).max(axis=1), 1.0, atol=1e-6)      # axis aligned
    assert np.all(np.einsum('ij,ij->i', n[:, 0], centroid) > 0), "normals point outwards"



def test_mirrored_instances_wind_outwards_with_their_corner_data(scene, exported):
    """A negative scale reverses the winding; the renderer orients shading normals by the winding
    normal, so a mirrored instance must wind outwards and keep each corner's normal and UV with
    its vertex (mirrored objects rendered black while only the normals were flipped)."""
    setup(scene)
    mat = bpy.data.materials.new("Textured")           # UVs are exported when a texture reads them
    nt = mat.node_tree
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.new("Px", 2, 2)
    bsdf = next(n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED')
    nt.links.new(tex.outputs['Color'], bsdf.inputs['Base Color'])
    ob = scenes.uv_sphere("S", segments=12, rings=6, location=(1.0, 2.0, 3.0), materials=(mat,))
    uv = ob.data.uv_layers.new(name="UV")
    for loop in ob.data.loops:          # u, v = the vertex's local x, y: a known corner -> UV map
        co = ob.data.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (co.x, co.y)
    ob.scale = (1.0, -2.0, 1.0)
    data = exported()
    g = data.geometry
    V = np.asarray(g.vertices)[g.triangles]                       # (M, 3 corners, 3)
    wind = np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0])
    centre = np.array([1.0, 2.0, 3.0])
    assert np.all(np.einsum('ij,ij->i', wind, V.mean(axis=1) - centre) > 0), "winding faces the outside"
    assert np.all(np.einsum('ij,ikj->ik', wind, g.normals) > 0), "corner normals on the winding side"
    local = (V - centre) / np.array([1.0, -2.0, 1.0])
    assert np.allclose(g.uvs, local[..., :2], atol=1e-5), "each corner keeps its vertex's UV"

def test_smooth_normals_follow_inverse_transpose(scene, exported):
    setup(scene)
    ob = scenes.uv_sphere("Ball", radius=1.0, segments=48, rings=24, smooth=True)
    assert ob.data.normals_domain == 'POINT'
    ob.scale = (1.0, 1.0, 3.0)
    data = exported()
    g = data.geometry
    p = g.vertices[g.triangles].astype(np.float64)            # (M,3,3) on the ellipsoid
    expect = p / np.array([1.0, 1.0, 9.0])                    # gradient of x^2 + y^2 + z^2/9
    expect /= np.linalg.norm(expect, axis=2, keepdims=True)
    cos = np.einsum('ijk,ijk->ij', g.normals, expect)
    assert np.all(np.abs(np.linalg.norm(g.normals, axis=2) - 1) < 1e-5)
    assert cos.min() > 0.995
    # smooth: corners of a triangle differ (unlike flat shading)
    assert np.mean(np.abs(g.normals[:, 0] - g.normals[:, 1]).max(axis=1) > 1e-3) > 0.9


def test_custom_normals_corner_domain(scene, exported):
    setup(scene)
    ob = scenes.plane("P")
    custom = Vector((0.0, 0.6, 0.8))
    ob.data.normals_split_custom_set([custom[:]] * len(ob.data.loops))
    assert ob.data.normals_domain == 'CORNER'
    ob.rotation_euler = (0.0, 0.0, math.pi / 2)
    data = exported()
    expected = Euler((0.0, 0.0, math.pi / 2)).to_matrix() @ custom
    assert np.allclose(data.geometry.normals.reshape(-1, 3), expected, atol=1e-4)


def test_shadow_terminator_offsets_per_triangle(scene, exported):
    """Cycles' shadow terminator settings, per triangle of each object: the geometry offset on
    smooth meshes only (Blender's default 0.1; Cycles lifts shadow rays off smooth triangles
    alone), the shading offset on all; none at all when every object has zero offsets."""
    setup(scene)
    ball = scenes.uv_sphere("Ball", segments=8, rings=4, smooth=True)
    soft = scenes.uv_sphere("Soft", segments=8, rings=4, smooth=True, location=(3, 0, 0))
    soft.shadow_terminator_geometry_offset, soft.shadow_terminator_shading_offset = 0.4, 0.7
    box = scenes.cube("Box", location=(-3, 0, 0))
    box.shadow_terminator_shading_offset = 0.25
    data = exported()
    t = data.geometry.terminator
    assert t.dtype == np.float32 and t.shape == (len(data.geometry.triangles), 2)
    assert ball.shadow_terminator_geometry_offset == pytest.approx(0.1)
    assert np.allclose(t[of_object(data, "Ball")], (0.1, 0.0))
    assert np.allclose(t[of_object(data, "Soft")], (0.4, 0.7))
    assert np.allclose(t[of_object(data, "Box")], (0.0, 0.25))        # flat: no geometry offset
    for ob in (ball, soft, box):
        ob.shadow_terminator_geometry_offset = ob.shadow_terminator_shading_offset = 0.0
    assert exported().geometry.terminator is None


def test_sharp_edges_mixed_normals(scene, exported):
    setup(scene)
    ob = scenes.uv_sphere("Ball", segments=16, rings=8, smooth=True)
    sharp = ob.data.attributes.new("sharp_face", 'BOOLEAN', 'FACE')
    values = [p.center.z > 0 for p in ob.data.polygons]
    sharp.data.foreach_set('value', values)
    ob.data.update()
    assert ob.data.normals_domain == 'CORNER'
    data = exported()
    g = data.geometry
    centroid = g.vertices[g.triangles].mean(axis=1)
    flat = np.all(np.isclose(g.normals[:, 0], g.normals[:, 1], atol=1e-6), axis=1) & \
        np.all(np.isclose(g.normals[:, 0], g.normals[:, 2], atol=1e-6), axis=1)
    assert flat[centroid[:, 2] > 0.05].all() and not flat[centroid[:, 2] < -0.05].any()
    # flat faces are all that is sharp: the smooth faces take the vertex normals, averaged over
    # every face around a vertex (Cycles' normals_domain(true), POINT), not corner normals that
    # split at the flat faces (a roof's smooth half had shaded flat, 0.68x Cycles); flat ones
    # their own geometric normal
    vn = np.array([v.vector for v in ob.data.vertex_normals])
    smooth = centroid[:, 2] < -0.05
    assert len(g.vertices) == len(vn)
    np.testing.assert_allclose(g.normals[smooth], vn[g.triangles[smooth]], atol=1e-5)
    e1, e2 = (g.vertices[g.triangles[:, k]] - g.vertices[g.triangles[:, 0]] for k in (1, 2))
    n = np.cross(e1, e2)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    top = centroid[:, 2] > 0.05
    np.testing.assert_allclose(g.normals[top], np.repeat(n[top][:, None], 3, axis=1), atol=1e-5)
    # a sharp edge as well: Blender's corner normals, as Cycles (CORNER either way)
    ob.data.attributes.new("sharp_edge", 'BOOLEAN', 'EDGE').data[0].value = True
    ob.data.update()
    corner = np.array([[ob.data.corner_normals[c].vector for c in t.loops] for t in ob.data.loop_triangles])
    np.testing.assert_allclose(exported().geometry.normals, corner, atol=1e-5)


def _reference_corners(ob, uv_map=None):
    """Per triangle corner, read the slow independent way (loop_triangles one by one) from the
    object's own mesh (no modifiers: the evaluated mesh has the same topology): world
    position, face corner normal, UV (of the active map, or the one named) and material slot."""
    me, m = ob.data, np.array(ob.matrix_world)
    uv = (me.uv_layers.active if uv_map is None else me.uv_layers[uv_map]).uv
    pos, nrm, uvs, slot = [], [], [], []
    for t in me.loop_triangles:
        pos.append([m[:3, :3] @ np.array(me.vertices[v].co) + m[:3, 3] for v in t.vertices])
        nrm.append([np.array(me.corner_normals[c].vector) for c in t.loops])
        uvs.append([np.array(uv[c].vector) for c in t.loops])
        slot.append(me.polygons[t.polygon_index].material_index)
    return np.array(pos), np.array(nrm), np.array(uvs), np.array(slot)


@pytest.mark.parametrize("faces", ["triangles", "mixed"])
def test_face_corners_match_loop_triangles(scene, exported, faces):
    """A mesh of triangles only takes the fast path (triangle i is face i, corners 3i..3i+2, no
    per-triangle read); a mesh with quads and an n-gon reads loop_triangles. Either way every
    triangle's positions, corner normals, UVs and material slot are those of its face corners,
    in loop_triangles order (faces start at different corners, normals are custom per corner)."""
    setup(scene)
    rng = np.random.default_rng(3)
    verts = [(x, y, 0.3 * rng.random()) for x in range(4) for y in range(3)]
    if faces == "triangles":
        polys = [(0, 3, 4), (4, 1, 0), (5, 2, 1), (1, 4, 5), (6, 7, 4), (3, 6, 4), (8, 5, 4), (7, 8, 4),
                 (10, 7, 6), (9, 10, 6), (11, 8, 7), (10, 11, 7)]
    else:
        polys = [(0, 3, 4), (4, 1, 0), (1, 4, 5, 2), (3, 6, 7, 4), (4, 7, 10, 11, 8, 5), (6, 9, 10, 7)]
    mats = [scenes.diffuse(n, c) for n, c in (("Red", (1, 0, 0)), ("Blue", (0, 0, 1)))]
    img = bpy.data.images.new("Grey", 2, 2)
    mats.append(_image_material("Tex", img))
    ob = scenes.mesh("M", verts, polys, materials=mats)
    ob.location, ob.rotation_euler = (0.5, -1.0, 2.0), (0.3, 0.0, 0.7)
    me = ob.data
    for p in me.polygons:
        p.material_index = p.index % 3
    me.uv_layers.new(name="UVMap").uv.foreach_set(
        'vector', rng.random(2 * len(me.loops)).astype(np.float32))
    custom = rng.normal(size=(len(me.loops), 3)) + (0, 0, 3)
    me.normals_split_custom_set((custom / np.linalg.norm(custom, axis=1, keepdims=True)).tolist())
    assert me.normals_domain == 'CORNER'
    assert (len(me.loop_triangles) == len(me.polygons)) == (faces == "triangles")
    data = exported()
    g = data.geometry
    bpy.context.view_layer.update()                      # ob.matrix_world from its transform
    pos, nrm, uvs, slot = _reference_corners(ob)
    assert len(g.triangles) == len(pos)
    assert np.allclose(g.vertices[g.triangles], pos, atol=1e-5)
    rot = np.array(ob.matrix_world)[:3, :3]              # rotation only: normals turn with it
    assert np.allclose(g.normals, nrm @ rot.T, atol=1e-5)
    assert g.uvs is not None and np.array_equal(g.uvs, uvs.astype(np.float32))
    names = np.array([m.name for m in data.materials])[g.material]
    assert list(names) == [mats[s].name for s in slot]


def _uv_map_material(name, image, *uv_maps):
    """A diffuse whose colour is the sum (Mix Add) of one image per UV map name given, each read
    through a UV Map node of that name ('' : the node with no map chosen)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    last = None
    for uv_map in uv_maps:
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = image
        node = nt.nodes.new('ShaderNodeUVMap')
        node.uv_map = uv_map
        nt.links.new(node.outputs['UV'], tex.inputs['Vector'])
        if last is None:
            last = tex.outputs['Color']
            continue
        add = nt.nodes.new('ShaderNodeMix')
        add.data_type, add.blend_type = 'RGBA', 'ADD'
        add.inputs['Factor'].default_value = 1.0
        nt.links.new(last, add.inputs['A'])
        nt.links.new(tex.outputs['Color'], add.inputs['B'])
        last = add.outputs['Result']
    nt.links.new(last, d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def test_uv_map_node_reads_its_map_by_name(scene, exported):
    """An image read through a UV Map node uses that map (Cycles: the attribute of that name)
    on the triangles of its material, the active render map elsewhere; a mesh without the map
    reads (0, 0), as in Cycles; a material whose images ask for two maps is reported. Before,
    every image read the active render map (reported)."""
    setup(scene)
    rng = np.random.default_rng(5)
    img = bpy.data.images.new("Grey", 2, 2)
    mats = [_image_material("Active", img), _uv_map_material("Detail", img, "Detail"),
            _uv_map_material("Unnamed", img, "")]
    verts = [(x, y, 0.3 * rng.random()) for x in range(4) for y in range(3)]
    polys = [(0, 3, 4), (4, 1, 0), (1, 4, 5, 2), (3, 6, 7, 4), (4, 7, 10, 11, 8, 5), (6, 9, 10, 7)]
    ob = scenes.mesh("M", verts, polys, materials=mats)
    ob.scale.x = -1.0                                    # mirrored: corners 1 and 2 swap
    me = ob.data
    for p in me.polygons:
        p.material_index = p.index % 3
    for layer in ("UVMap", "Detail"):
        me.uv_layers.new(name=layer).uv.foreach_set('vector', rng.random(2 * len(me.loops)).astype(np.float32))
    me.uv_layers["UVMap"].active_render = True
    lone = scenes.plane("NoDetail", location=(5, 0, 0), materials=(mats[1],))
    lone.data.uv_layers.new(name="UVMap")
    both = scenes.plane("Both", location=(9, 0, 0), materials=(_uv_map_material("Two", img, "UVMap", "Detail"),))
    both.data.uv_layers.new(name="UVMap")
    data = exported()
    g = data.geometry
    bpy.context.view_layer.update()
    _, _, active, slot = _reference_corners(ob)
    _, _, detail, _ = _reference_corners(ob, "Detail")
    sel = of_object(data, "M")
    expect = np.where((slot == 1)[:, None, None], detail, active)[:, [0, 2, 1]]    # rewound
    assert np.array_equal(g.uvs[sel], expect.astype(np.float32))
    assert np.all(g.uvs[of_object(data, "NoDetail")] == 0.0)
    table = {m.name: m for m in data.materials}
    assert table["Detail"].uv_map == "Detail" and table["Unnamed"].uv_map == "" and not table["Detail"].approximated
    assert "textures on several UV maps ('UVMap', 'Detail')" in table["Two"].approximated


@pytest.mark.parametrize("domain", ["POINT", "FACE"])
def test_uv_map_node_reads_a_2d_vector_attribute_on_points_or_faces(scene, exported, domain):
    """A UV Map node naming a 2D vector attribute on points or faces (Geometry Nodes' Store
    Named Attribute writes Points by default) reads it per corner, as Cycles reads an attribute
    of that name on any domain; it had read (0, 0), silently."""
    setup(scene)
    img = bpy.data.images.new("Grey", 2, 2)
    rng = np.random.default_rng(8)
    verts = [(x, y, 0.0) for x in range(3) for y in range(3)]
    polys = [(0, 3, 4, 1), (1, 4, 5, 2), (3, 6, 7, 4), (4, 7, 8, 5)]
    ob = scenes.mesh("G", verts, polys, materials=(_uv_map_material("ByName", img, "gnuv"),))
    me = ob.data
    attr = me.attributes.new("gnuv", 'FLOAT2', domain)
    values = rng.random((len(attr.data), 2)).astype(np.float32)
    attr.data.foreach_set('vector', values.ravel())
    data = exported()
    want = np.array([[values[me.loops[c].vertex_index if domain == 'POINT' else t.polygon_index]
                      for c in t.loops] for t in me.loop_triangles], np.float32)
    np.testing.assert_array_equal(data.geometry.uvs[of_object(data, "G")], want)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_quad_tessellation_is_blenders(scene, seed):
    """Meshes of triangles and quads are tessellated here as Blender does (reading its
    loop_triangles goes through RNA item by item, ~90 ms per million triangles): on random
    quads, many of them concave, folded or degenerate, every triangle's corners equal
    loop_triangles'; a mesh with an n-gon is left to Blender."""
    rng = np.random.default_rng(seed)
    n = 3000
    quads = rng.normal(size=(n, 4, 3)).astype(np.float32)
    quads[: n // 3, :, 2] = 0.0                               # planar ones, convex or not
    quads[n // 3: n // 3 + 50, 3] = quads[n // 3: n // 3 + 50, 1]   # degenerate: v3 = v1
    tris = rng.normal(size=(n // 2, 3, 3)).astype(np.float32)
    verts, faces = [], []
    for q in quads:
        faces.append(tuple(range(len(verts), len(verts) + 4)))
        verts += q.tolist()
    for t in tris:                                            # triangles between the quads
        faces.insert(int(rng.integers(len(faces) + 1)), tuple(range(len(verts), len(verts) + 3)))
        verts += t.tolist()
    me = bpy.data.meshes.new("Quads")
    me.from_pydata(verts, [], faces)
    nt, nl = len(me.loop_triangles), len(me.loops)
    expect = np.empty(3 * nt, np.int32)
    me.loop_triangles.foreach_get('loops', expect)
    positions = np.empty(3 * len(me.vertices), np.float32)
    me.attributes['position'].data.foreach_get('vector', positions)
    corner_vert = np.empty(nl, np.int32)
    me.attributes['.corner_vert'].data.foreach_get('value', corner_vert)
    tri_poly = np.empty(nt, np.int32)
    me.loop_triangle_polygons.foreach_get('value', tri_poly)
    got = export.meshes._quad_corner_tris(positions.reshape(-1, 3), corner_vert, tri_poly, nl)
    assert got is not None and np.array_equal(got, expect.reshape(-1, 3))
    flipped = np.count_nonzero(np.diff(got[:, 0]) == 1)        # (0 1 3) then (1 2 3)
    assert flipped > 100, "the sample has folded quads for the flip rule to decide"
    ngon = bpy.data.meshes.new("Ngon")
    ngon.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0.5, 1.5, 0), (0, 1, 0)], [], [(0, 1, 2, 3, 4)])
    tp = np.empty(3, np.int32)
    ngon.loop_triangle_polygons.foreach_get('value', tp)
    assert export.meshes._quad_corner_tris(np.zeros((5, 3), np.float32), np.arange(5, dtype=np.int32), tp, 5) is None


def test_dropped_triangles_keep_later_objects_aligned(scene, exported):
    """Triangles dropped from one mesh (NaN vertex, zero area) are removed from every
    per-triangle array alike, so the meshes after it keep their own materials, objects and
    normals."""
    setup(scene)
    red, blue = scenes.diffuse("Red", (1, 0, 0)), scenes.diffuse("Blue", (0, 0, 1))
    scenes.plane("First", location=(-5, 0, 0), materials=(red,))
    scenes.mesh("Broken", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (float('nan'), 0, 0), (2, 2, 2),
                           (3, 3, 3), (4, 4, 4)],
                [(0, 1, 2), (0, 3, 1), (4, 5, 6)], materials=(red,))
    ball = scenes.uv_sphere("Ball", segments=12, rings=6, location=(5, 0, 0), smooth=True,
                            materials=(blue,))
    data = exported()
    g = data.geometry
    assert [of_object(data, n).sum() for n in ("First", "Broken", "Ball")] == [2, 1, 12 * 6 * 2 - 2 * 12]
    assert data.skipped['triangles_degenerate'] == 1 and data.skipped['triangles_nonfinite'] == 1
    sel = of_object(data, "Ball")
    assert {data.materials[i].name for i in g.material[sel]} == {"Blue"}
    assert {data.materials[i].name for i in g.material[~sel]} == {"Red"}
    out = g.vertices[g.triangles[sel]] - np.array(ball.location)
    out /= np.linalg.norm(out, axis=2, keepdims=True)
    assert np.einsum('ijk,ijk->ij', g.normals[sel], out).min() > 0.99


# -- visibility --------------------------------------------------------------------------------

@pytest.mark.parametrize("pattern", ["first", "last", "runs", "scattered", "all", "none"])
def test_compact_rows_equals_boolean_indexing(pattern):
    """The in-place removal of dropped triangles gives exactly a[keep] for every array shape the
    export uses, whatever the drop pattern (consecutive drops, the first and last rows, all)."""
    rng = np.random.default_rng(len(pattern))
    m = 5000
    keep = np.ones(m, bool)
    if pattern == "first":
        keep[0] = False
    elif pattern == "last":
        keep[-1] = False
    elif pattern == "runs":
        keep[10:20] = keep[100:101] = keep[4990:] = False
    elif pattern == "scattered":
        keep[rng.choice(m, 300, replace=False)] = False
    elif pattern == "all":
        keep[:] = False
    for shape, dtype in (((m, 3), np.int32), ((m, 3, 3), np.float32), ((m,), np.uint8), ((m, 3, 2), np.float32)):
        a = rng.integers(0, 1000, shape).astype(dtype)
        expect = a[keep]
        got = export.assembly._compact_rows(a, keep)
        assert got.dtype == dtype and got.shape == expect.shape
        np.testing.assert_array_equal(got, expect)


def test_animated_hide_render_counts_the_rendered_frame(scene, exported, tmp_path):
    """Disable in Renders keyframed off by frame 4: an animation render of frame 4 (the file
    at frame 1, hidden there) exports the plane and counts nothing hidden."""
    setup(scene)
    ob = scenes.plane("Blink")
    scenes.keyed(ob, 'hide_render', {1: True, 4: False})
    scenes.animation_of_one_frame(scene, 4, tmp_path)
    data = exported(animation=True)
    assert "Blink" in data.object_names and data.skipped['objects_hidden'] == 0


def test_hidden_and_ray_visibility(scene, exported):
    setup(scene)
    scenes.plane("Shown")
    scenes.plane("Hidden", location=(3, 0, 0)).hide_render = True
    scenes.plane("NoCamera", location=(6, 0, 0)).visible_camera = False
    no_shadow = scenes.plane("NoShadow", location=(9, 0, 0))
    no_shadow.visible_shadow = False
    held = scenes.plane("Held", location=(12, 0, 0))
    held.is_holdout = True
    gone = scenes.plane("Gone", location=(15, 0, 0))
    gone.visible_camera = gone.visible_diffuse = gone.visible_shadow = gone.visible_transmission = False
    scenes.plane("NoTransmission", location=(18, 0, 0)).visible_transmission = False
    past_glass = scenes.plane("PastGlassOnly", location=(21, 0, 0))
    past_glass.visible_camera = past_glass.visible_diffuse = past_glass.visible_shadow = False
    data = exported()
    assert "Hidden" not in data.object_names and "Gone" not in data.object_names
    assert data.skipped['objects_hidden'] == 1 and data.skipped['objects_invisible'] == 1
    vis = {n: set(data.geometry.visibility[of_object(data, n)].tolist()) for n in data.object_names}
    full = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
    assert vis["Shown"] == {full}
    assert vis["NoCamera"] == {sd.VIS_DIFFUSE | sd.VIS_SHADOW}
    assert vis["NoShadow"] == {sd.VIS_CAMERA | sd.VIS_DIFFUSE}
    assert vis["Held"] == {full | sd.HOLDOUT}
    assert vis["NoTransmission"] == {full | sd.NO_TRANSMISSION}    # seen past glass no more
    assert vis["PastGlassOnly"] == {sd.VIS_TRANSMISSION}           # seen past glass alone


def test_holdout_and_excluded_collections(scene, exported):
    setup(scene)
    held, excluded = bpy.data.collections.new("Held"), bpy.data.collections.new("Excluded")
    for c in (held, excluded):
        scene.collection.children.link(c)
    a = scenes.plane("InHeld")
    scene.collection.objects.unlink(a)
    held.objects.link(a)
    b = scenes.plane("InExcluded", location=(3, 0, 0))
    scene.collection.objects.unlink(b)
    excluded.objects.link(b)
    layer = bpy.context.view_layer
    layer.layer_collection.children["Held"].holdout = True
    layer.layer_collection.children["Excluded"].exclude = True
    data = exported()
    assert data.object_names == ["InHeld"]
    assert np.all(data.geometry.visibility & sd.HOLDOUT)


def test_holdout_follows_the_rendered_frame_and_parent_collections(scene, exported, tmp_path):
    """Object > Visibility > Holdout keyed off at frame 3 (the file at frame 1, held out): an
    animation render of frame 3 does not hold it out (Object.holdout_get ORs in the original's
    stale flag: a hunt's wall was held out on every frame, alpha 0.833 where Cycles gives 1);
    a collection under a held-out one is not (Blender's bases take Holdout from the collection
    itself: a child had been held out where Cycles renders it, alpha 0.54 vs 1), an excluded
    held-out one holds nothing."""
    setup(scene)
    wall = scenes.plane("Wall")
    scenes.keyed(wall, 'is_holdout', {1: True, 3: False})
    outer, inner = bpy.data.collections.new("Outer"), bpy.data.collections.new("Inner")
    scene.collection.children.link(outer)
    outer.children.link(inner)
    nested = scenes.plane("Nested", location=(3, 0, 0))
    scene.collection.objects.unlink(nested)
    inner.objects.link(nested)
    outside = scenes.plane("Outside", location=(6, 0, 0))
    scene.collection.objects.unlink(outside)
    outer.objects.link(outside)
    gone = bpy.data.collections.new("Gone")
    scene.collection.children.link(gone)
    gone.objects.link(bpy.data.objects["Wall"])       # (also in an excluded held-out one)
    layer = bpy.context.view_layer
    layer.layer_collection.children["Outer"].holdout = True
    layer.layer_collection.children["Gone"].holdout = True
    layer.layer_collection.children["Gone"].exclude = True
    scenes.animation_of_one_frame(scene, 3, tmp_path)
    assert wall.is_holdout
    data = exported(animation=True)
    vis = {n: set(data.geometry.visibility[of_object(data, n)].tolist()) for n in data.object_names}
    assert not any(v & sd.HOLDOUT for v in vis["Wall"]), vis
    assert not any(v & sd.HOLDOUT for v in vis["Nested"]), vis
    assert all(v & sd.HOLDOUT for v in vis["Outside"]), vis
    scenes.animation_of_one_frame(scene, 1, tmp_path)
    data = exported(animation=True)
    assert np.all(data.geometry.visibility[of_object(data, "Wall")] & sd.HOLDOUT)


def test_indirect_only_collection_is_hidden_from_camera_rays_only(scene, exported):
    """Cycles clears camera visibility for an Indirect Only collection (unless held out): its
    objects still cast shadows and light others by bounces."""
    setup(scene)
    side = bpy.data.collections.new("Side")
    scene.collection.children.link(side)
    a = scenes.plane("Indirect")
    scene.collection.objects.unlink(a)
    side.objects.link(a)
    scenes.plane("Direct", location=(3, 0, 0))
    bpy.context.view_layer.layer_collection.children["Side"].indirect_only = True
    data = exported()
    vis = {name: data.geometry.visibility[data.geometry.object_index == i] for i, name in enumerate(data.object_names)}
    assert np.all(vis["Indirect"] == sd.VIS_DIFFUSE | sd.VIS_SHADOW)
    assert np.all(vis["Direct"] == sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW)


def test_see_through_hair_and_points_are_reported(scene, exported):
    """Points and hair curves are tessellated spheres and tubes: light through a translucent or
    see-through one crosses two surfaces where Cycles' curve or point is one; said, naming the
    object, only where the material lets light through."""
    setup(scene)
    leaf = _mixed("Leafy", 'ShaderNodeBsdfDiffuse', (0.2, 0.4, 0.1), 'ShaderNodeBsdfTranslucent', (0.6, 0.8, 0.2),
                  0.5)
    scenes.point_cloud("Seeds", np.array([(0.0, 0.0, 0.5)]), 0.2, leaf)
    scenes.hair_curves("Fur", [np.array([(1.0, 0.0, 0.0), (1.0, 0.0, 1.0)])], 0.05, scenes.diffuse("Fur", (0.5,) * 3))
    said = [m for _, m in exported().messages if "crosses two surfaces" in m]
    assert len(said) == 1 and said[0].startswith("'Seeds':") and "'Fur'" not in said[0]


def test_features_rendered_without_are_reported(scene, exported):
    """Shadow catchers and motion blur are Cycles features DACRT does not render: the objects
    render as ordinary ones and the render says so. Light and shadow linking (receiver and
    blocker collections) are rendered and exported, not reported."""
    setup(scene)
    catcher = scenes.plane("Catcher")
    catcher.is_shadow_catcher = True
    lamp = scenes.light('POINT', 100.0, (0, 0, 3), name="Linked")
    lamp.light_linking.blocker_collection = bpy.data.collections.new("Blockers")
    scene.render.use_motion_blur = True
    # (said only of what Cycles would blur: something that may move, tests/addon/test_motion_blur_messages.py)
    scenes.keyed(catcher, 'location', {1: (0, 0, 0), 10: (0, 0, 1)})
    s = exported()
    text = " | ".join(m for _, m in s.messages)
    assert "'Catcher': shadow catcher is not supported" in text
    assert "motion blur is not rendered" in text
    scene.view_layers[0].use_motion_blur = False    # the layer's own switch: Cycles blurs nothing
    assert "motion blur" not in " | ".join(m for _, m in exported().messages)
    assert "linking" not in text and s.shadow_links == {"Linked": (frozenset(), frozenset())}
    scene.render.use_motion_blur = False
    catcher.is_shadow_catcher = False
    lamp.light_linking.blocker_collection = None
    text = " | ".join(m for _, m in exported().messages)
    assert "shadow catcher" not in text and "linking" not in text and "motion blur" not in text
    assert "working colour space" not in text
    # Blender 5.0's file working space other than Rec.709: image and blackbody colours differ
    bpy.ops.wm.set_working_color_space(working_space='ACEScg', convert_colors=False)
    try:
        text = " | ".join(m for _, m in exported().messages)
        assert "working colour space 'ACEScg'" in text
    finally:
        bpy.ops.wm.set_working_color_space(working_space='Linear Rec.709', convert_colors=False)


def test_light_linking_tells_library_objects_from_local_ones_of_the_same_name(scene, tmp_path):
    """Light linking matches objects, not names: a library plane named as a local one ('Plane'
    and 'Plane [lib.blend]') is not lit by a lamp whose receiver collection holds the local
    one (it was: 0.110 where Cycles renders 0), and a library lamp named as a local, linked one
    lights everything (it had taken the local lamp's linking: black where Cycles gives 0.4)."""
    setup(scene)
    plane = scenes.plane("Plane", size=2.0)
    lamp = scenes.light('POINT', 200.0, (0, 0, 2), name="Lamp")
    lib = tmp_path / "lib.blend"
    bpy.data.libraries.write(str(lib), {plane, lamp})
    with bpy.data.libraries.load(str(lib), link=True) as (_, linked):
        linked.objects = ["Plane", "Lamp"]
    far_plane, far_lamp = linked.objects
    plane.location.x, lamp.location.x = -3.0, -3.0    # the library's stay at x = 0
    recv = bpy.data.collections.new("Receivers")
    recv.objects.link(plane)
    lamp.light_linking.receiver_collection = recv
    scene.collection.objects.link(far_plane)
    scenes.camera(location=(-1.5, 0, 8), kind='ORTHO', ortho_scale=6.0)
    scene.render.resolution_x, scene.render.resolution_y = 24, 8
    scene.render.engine = 'DACRT'
    scene.dacrt.samples, scene.dacrt.max_bounces = 4, 0
    scenes.black_world()
    img = scenes.read_exr(scenes.render_exr(tmp_path / "a.exr"))["R"]
    left, right = img[:, 4:8].mean(), img[:, 16:20].mean()
    assert left > 0.02 and right == 0.0, (left, right)
    # the library lamp over the library plane lights it: the local lamp's linking is its own
    scene.collection.objects.link(far_lamp)
    img = scenes.read_exr(scenes.render_exr(tmp_path / "b.exr"))["R"]
    assert img[:, 16:20].mean() > 0.02, img[:, 16:20].mean()


def test_light_linking_receivers_exported(scene, exported):
    """An emitter's receiver collection as (included, excluded) names: objects by their own
    state, a child collection's objects (all levels) by the child's state."""
    setup(scene)
    for name in ("A", "B", "C", "D"):
        scenes.plane(name)
    lamp = scenes.light('POINT', 100.0, (0, 0, 3), name="Key")
    recv = bpy.data.collections.new("Receivers")
    recv.objects.link(bpy.data.objects["A"])
    recv.objects.link(bpy.data.objects["B"])
    recv.collection_objects[1].light_linking.link_state = 'EXCLUDE'
    child, grandchild = bpy.data.collections.new("Child"), bpy.data.collections.new("Grandchild")
    recv.children.link(child)
    child.children.link(grandchild)
    child.objects.link(bpy.data.objects["C"])
    grandchild.objects.link(bpy.data.objects["D"])
    recv.collection_children[0].light_linking.link_state = 'EXCLUDE'
    lamp.light_linking.receiver_collection = recv
    s = exported()
    assert s.light_links == {"Key": (frozenset({"A"}), frozenset({"B", "C", "D"}))}
    assert not any("linking" in m or "instancer" in m for _, m in s.messages)
    # a collection instance in it: its instances are not linked through it, and the render says so
    # (Cycles lights them; silently unlit before)
    src = bpy.data.collections.new("Source")
    src.objects.link(scenes.plane("Instanced", location=(5, 0, 0)))
    empty = bpy.data.objects.new("Instancer", None)
    empty.instance_type, empty.instance_collection = 'COLLECTION', src
    scene.collection.objects.link(empty)
    recv.objects.link(empty)
    text = " | ".join(m for _, m in exported().messages)
    assert "instancer 'Instancer' in its receiver collection" in text and "'Key'" in text


def test_passes_dacrt_does_not_write_are_reported(scene, exported):
    """A view layer asking for passes Cycles renders and DACRT does not (Glossy, AO...) is told which are missing from the result; the passes DACRT writes
    (data and diffuse light passes, Emission, Environment) are not named, and nothing is said
    when only those are on."""
    setup(scene)
    vl = bpy.context.view_layer
    vl.use_pass_z = vl.use_pass_normal = vl.use_pass_diffuse_color = vl.use_pass_mist = True
    vl.use_pass_diffuse_direct = vl.use_pass_diffuse_indirect = True
    vl.use_pass_emit = vl.use_pass_environment = True
    vl.use_pass_position = vl.use_pass_uv = vl.use_pass_object_index = vl.use_pass_material_index = True
    s = exported()
    assert not any("not in the result" in m for _, m in s.messages)
    assert set(s.settings.passes) == {'Depth', 'Normal', 'DiffCol', 'Mist', 'DiffDir', 'DiffInd', 'Emit', 'Env',
                                      'Position', 'UV', 'IndexOB', 'IndexMA'}
    vl.use_pass_glossy_direct = vl.use_pass_ambient_occlusion = vl.use_pass_cryptomatte_object = True
    vl.cycles.denoising_store_passes = True
    vl.aovs.add().name = "Wetness"
    notes = [m for _, m in exported().messages if "not in the result" in m]
    assert len(notes) == 1, notes
    for label in ("Glossy Direct", "Ambient Occlusion"):
        assert label in notes[0], (label, notes[0])
    assert "Wetness" not in notes[0] and exported().settings.aovs == (("Wetness", 'COLOR'),)   # written
    assert "Denoising Data" not in notes[0] and "DenoiseNormal" in exported().settings.passes
    assert "Cryptomatte Object" not in notes[0]               # written since it has been
    assert exported().settings.cryptomatte == ('CryptoObject',)
    written = notes[0].split("not in the result")[1]
    assert "Depth," in notes[0] and "Depth" not in written and "Mist" not in written
    assert "Emission" not in written and "Diffuse Direct" not in written
    assert "Position" not in written and "Object Index" not in written and "UV" not in written


def test_nan_vertices_dropped_with_message(scene, exported):
    setup(scene)
    ob = scenes.mesh("Broken", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (float('nan'), 0, 0),
                                (2, 0, float('inf'))],
                     [(0, 1, 2), (0, 2, 3), (1, 4, 2), (1, 5, 2)])
    scenes.plane("Fine", location=(5, 0, 0))
    data = exported()
    g = data.geometry
    assert of_object(data, "Broken").sum() == 2 and of_object(data, "Fine").sum() == 2
    assert np.isfinite(g.vertices[g.triangles]).all()
    msgs = [t for lvl, t in data.messages if 'Broken' in t]
    assert len(msgs) == 1 and "2 vertices" in msgs[0] and "2 triangles" in msgs[0]


# -- UVs, materials, world ------------------------------------------------------------------

def _image_material(name, image, interpolation='Closest'):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    bsdf = nt.nodes.new('ShaderNodeBsdfPrincipled')
    bsdf.inputs['Specular IOR Level'].default_value = 0.0
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation, tex.extension = image, interpolation, 'EXTEND'
    nt.links.new(tex.outputs['Color'], bsdf.inputs['Base Color'])
    nt.links.new(bsdf.outputs[0], out.inputs['Surface'])
    return mat


def test_image_texture_uvs_and_linear_pixels(scene, exported, tmp_path):
    setup(scene)
    img = bpy.data.images.new("Checker", 2, 2)
    values = [0.5, 0.25, 1.0, 1.0,  0.0, 0.0, 0.0, 1.0,  1.0, 1.0, 1.0, 1.0,  0.2, 0.4, 0.6, 1.0]
    img.pixels[:] = values
    path = tmp_path / "checker.png"
    img.filepath_raw, img.file_format = str(path), 'PNG'
    img.save()
    loaded = bpy.data.images.load(str(path))          # an sRGB 8-bit image on disk
    ob = scenes.plane("P", materials=(_image_material("Tex", loaded),))
    uv = ob.data.uv_layers.new(name="UVMap")
    uv_values = np.array([[0.1, 0.2], [0.9, 0.2], [0.9, 0.8], [0.1, 0.8]], np.float32)
    uv.uv.foreach_set('vector', uv_values.ravel())
    data = exported()
    mat = data.materials[data.geometry.material[0]]
    assert mat.name == "Tex" and mat.texture is not None and mat.texture_extension == 'EXTEND'
    assert mat.texture_interpolation == 'Closest' and not mat.approximated
    srgb = np.round(np.array(values, np.float32).reshape(2, 2, 4) * 255) / 255
    lin = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    assert np.allclose(mat.texture[..., :3], lin[..., :3], atol=1e-4)
    assert np.allclose(mat.texture[..., 3], 1.0)
    corners_uv = data.geometry.uvs.reshape(-1, 2)
    loops_uv = uv_values[np.array([l for t in ob.data.loop_triangles for l in t.loops])]
    assert np.allclose(np.sort(corners_uv, axis=0), np.sort(loops_uv, axis=0))



def _mixed(name, a_type, a_color, b_type, b_color, fac):
    """A material: Mix Shader (factor fac) of a node a_type of colour a_color and one of b."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    a, b = nt.nodes.new(a_type), nt.nodes.new(b_type)
    a.inputs['Color'].default_value = (*a_color, 1)
    b.inputs['Color'].default_value = (*b_color, 1)
    m = nt.nodes.new('ShaderNodeMixShader')
    m.inputs['Fac'].default_value = fac
    nt.links.new(a.outputs[0], m.inputs[1])
    nt.links.new(b.outputs[0], m.inputs[2])
    nt.links.new(m.outputs[0], nt.nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    return mat

def test_material_table(scene, exported):
    setup(scene)
    mats = [scenes.diffuse("Diffuse", (0.2, 0.4, 0.6)),
            scenes.principled("Principled", (0.1, 0.2, 0.3), (1.0, 0.5, 0.0), 4.0),
            scenes.emission("Emission", (0.3, 0.3, 0.3), 5.0)]
    mats.append(_mixed("Mix", 'ShaderNodeBsdfDiffuse', (1, 0, 0), 'ShaderNodeBsdfDiffuse', (0, 0, 1), 0.25))
    mats.append(scenes.emissive_diffuse("Furnace", 0.5, 1.0))
    glass = bpy.data.materials.new("Glass")
    g = glass.node_tree
    g.nodes.clear()
    gout = g.nodes.new('ShaderNodeOutputMaterial')
    gnode = g.nodes.new('ShaderNodeBsdfGlass')
    gnode.inputs['Color'].default_value = (0.9, 0.8, 0.7, 1)
    g.links.new(gnode.outputs[0], gout.inputs['Surface'])
    mats.append(glass)
    refraction = bpy.data.materials.new("Refraction")
    r = refraction.node_tree
    r.nodes.clear()
    rnode = r.nodes.new('ShaderNodeBsdfRefraction')
    rnode.inputs['Color'].default_value = (0.9, 0.5, 0.2, 1)
    r.links.new(rnode.outputs[0], r.nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    mats.append(refraction)
    bottle = scenes.principled("Bottle", (0.3, 0.8, 0.4), specular=0.5)
    bnode = next(n for n in bottle.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    bnode.inputs['Transmission Weight'].default_value = 1.0
    bnode.inputs['Roughness'].default_value = 0.0
    mats.append(bottle)
    mats.append(_mixed("Leaf", 'ShaderNodeBsdfDiffuse', (0.2, 0.4, 0.1), 'ShaderNodeBsdfTranslucent',
                       (0.6, 0.8, 0.2), 0.25))
    mats.append(scenes.principled("Shiny", (0.5, 0.5, 0.5), specular=0.5, metallic=1.0))
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    data = exported()
    table = {m.name: m for m in data.materials}
    expect = {"Diffuse": ((0.2, 0.4, 0.6), (0, 0, 0)),
              "Principled": ((0.1, 0.2, 0.3), (4.0, 2.0, 0.0)),
              "Emission": ((0, 0, 0), (1.5, 1.5, 1.5)),
              "Mix": ((0.75, 0, 0.25), (0, 0, 0)),
              "Furnace": ((0.5, 0.5, 0.5), (1, 1, 1)),
              "Shiny": (tuple(specular.metal_albedo(0.5, (0.5, 0.5, 0.5), (1, 1, 1))), (0, 0, 0))}
    for name, (base, emit) in expect.items():
        assert np.allclose(table[name].base_color, base, atol=1e-6), name
        assert np.allclose(table[name].emission, emit, atol=1e-6), name
    assert {n for n, m in table.items() if m.approximated} == {"Glass", "Refraction", "Bottle", "Shiny"}
    # Principled transmission: the Glass BSDF's reflection (the same roughness and IOR), the rest
    # let through tinted by sqrt(base) as Cycles' glass (it was an opaque diffuse of its base)
    np.testing.assert_allclose(table["Bottle"].base_color, table["Glass"].base_color / (0.9, 0.8, 0.7), rtol=1e-6)
    np.testing.assert_allclose(table["Bottle"].transparency,
                               np.sqrt([0.3, 0.8, 0.4]) * (1 - table["Glass"].base_color[0] / 0.9), rtol=1e-5)
    assert "Principled transmission as a transparent surface" in table["Bottle"].approximated
    # a Translucent BSDF is diffuse transmission, rendered as such (it was a diffuse reflector)
    np.testing.assert_allclose(table["Leaf"].base_color, np.array([0.2, 0.4, 0.1]) * 0.75, rtol=1e-6)
    np.testing.assert_allclose(table["Leaf"].translucency, np.array([0.6, 0.8, 0.2]) * 0.25, rtol=1e-6)
    assert table["Diffuse"].translucency is None
    # refraction: all of its colour let through, unbent, nothing reflected (it was an opaque
    # diffuse surface of its colour)
    assert not table["Refraction"].base_color.any()
    np.testing.assert_allclose(table["Refraction"].transparency, (0.9, 0.5, 0.2), rtol=1e-6)
    assert "Refraction BSDF as a transparent surface" in table["Refraction"].approximated
    # glass: its reflection as a diffuse albedo (a few percent at IOR 1.5), the rest let through,
    # unbent, both times its colour (it was an opaque surface of its colour)
    reflect = table["Glass"].base_color / (0.9, 0.8, 0.7)
    assert np.ptp(reflect) < 1e-6 and 0.03 < reflect[0] < 0.12
    np.testing.assert_allclose(table["Glass"].transparency, np.array([0.9, 0.8, 0.7]) * (1 - reflect[0]), rtol=1e-5)
    assert "Glass BSDF as a transparent surface" in table["Glass"].approximated
    # fully metallic: the metal (its albedo as diffuse, 0.48 for base 0.5 at roughness 0.5)
    # replaces the dielectric specular layer
    assert 0.47 < table["Shiny"].base_color[0] < 0.49
    assert "metal as diffuse" in table["Shiny"].approximated and "specular" not in table["Shiny"].approximated
    approx = [t for _, t in data.messages if "approximated" in t]
    assert len(approx) == 1 and all(f"'{n}'" in approx[0] for n in ("Glass", "Refraction", "Bottle", "Shiny"))


def _shader_material(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new('ShaderNodeOutputMaterial')


def _alpha_image(alphas):
    img = bpy.data.images.new("Alpha", len(alphas), 1, float_buffer=True, alpha=True)
    img.pixels.foreach_set([c for a in alphas for c in (0.5, 0.5, 0.5, a)])
    img.pack()
    return img


def test_transparent_materials(scene, exported):
    """Transparent BSDF (its colour, mixed by constants), Principled Alpha (constant: the rest
    scaled by alpha; an image's Alpha output: an opacity texture) and a Mix Shader whose factor
    is an image's alpha between a Transparent BSDF and a Diffuse (either input order)."""
    setup(scene)
    built = []
    pane, nt, out = _shader_material("Pane")
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.25
    clear, dif = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    clear.inputs['Color'].default_value = (0.8, 0.4, 0.2, 1.0)
    dif.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1.0)
    nt.links.new(clear.outputs[0], mix.inputs[1])
    nt.links.new(dif.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    built.append(pane)
    ghost = scenes.principled("Ghost", (0.4, 0.2, 0.8), (1.0, 1.0, 1.0), 2.0)
    ghost.node_tree.nodes['Principled BSDF'].inputs['Alpha'].default_value = 0.25
    built.append(ghost)
    leaf = scenes.principled("Leaf", (0.2, 0.6, 0.1))
    tex = leaf.node_tree.nodes.new('ShaderNodeTexImage')
    tex.image = _alpha_image([0.0, 0.25, 1.0])
    leaf.node_tree.links.new(tex.outputs['Alpha'], leaf.node_tree.nodes['Principled BSDF'].inputs['Alpha'])
    built.append(leaf)
    for name, transparent_first in (("CardA", True), ("CardB", False)):
        card, nt, out = _shader_material(name)
        mix = nt.nodes.new('ShaderNodeMixShader')
        clear, dif = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeBsdfDiffuse')
        dif.inputs['Color'].default_value = (0.7, 0.3, 0.3, 1.0)
        t = nt.nodes.new('ShaderNodeTexImage')
        t.image = _alpha_image([0.0, 0.25, 1.0])
        nt.links.new(t.outputs['Alpha'], mix.inputs['Fac'])
        nt.links.new(clear.outputs[0], mix.inputs[1 if transparent_first else 2])
        nt.links.new(dif.outputs[0], mix.inputs[2 if transparent_first else 1])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
        built.append(card)
    for i, mat in enumerate(built):
        ob = scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
        ob.data.uv_layers.new(name="UVMap")
    table = {m.name: m for m in exported().materials}
    assert np.allclose(table["Pane"].transparency, [0.6, 0.3, 0.15]) and table["Pane"].opacity is None
    assert np.allclose(table["Pane"].base_color, 0.25)
    g = table["Ghost"]
    assert np.allclose(g.transparency, 0.75) and np.allclose(g.base_color, [0.1, 0.05, 0.2])
    assert np.allclose(g.emission, 0.5) and g.opacity is None          # emission x alpha, as Cycles
    leaf = table["Leaf"]
    assert np.allclose(leaf.transparency, 1.0) and np.allclose(leaf.base_color, [0.2, 0.6, 0.1])
    assert np.allclose(leaf.opacity[0, :, 0], [0.0, 0.25, 1.0]) and not leaf.approximated
    # Mix = (1 - fac) first + fac second: the opacity is fac when the Transparent BSDF is first
    assert np.allclose(table["CardA"].opacity[0, :, 0], [0.0, 0.25, 1.0])
    assert np.allclose(table["CardB"].opacity[0, :, 0], [1.0, 0.75, 0.0])
    for name in ("CardA", "CardB"):
        assert np.allclose(table[name].base_color, [0.7, 0.3, 0.3]) and np.allclose(table[name].transparency, 1)
    assert all(table[n].transparency is None for n in table if n not in {"Pane", "Ghost", "Leaf", "CardA", "CardB"})


def test_world_background(scene, exported):
    setup(scene)
    scenes.world((0.5, 0.25, 1.0), 2.0)
    assert np.allclose(exported().world, (1.0, 0.5, 2.0))
    scene.world.node_tree.links.clear()                 # nothing on the Surface: black
    assert np.allclose(exported().world, 0.0)
    scene.world = None
    assert np.allclose(exported().world, 0.0)


def test_world_emission_add_and_mix_shaders(scene, exported):
    """For the world, Emission is Background's twin in Cycles; Add and Mix Shader (constant
    factor) of them combine linearly; a BSDF in the tree emits nothing, as in Cycles (the world
    colour had stood in for it), and is said."""
    setup(scene)
    w = scenes.world((0.5, 0.25, 1.0), 2.0)
    nt = w.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_WORLD')
    emit = nt.nodes.new('ShaderNodeEmission')
    emit.inputs['Color'].default_value, emit.inputs['Strength'].default_value = (1.0, 1.0, 0.0, 1.0), 4.0
    nt.links.new(emit.outputs[0], out.inputs['Surface'])
    assert np.allclose(exported().world, (4.0, 4.0, 0.0))
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.25
    nt.links.new(bg.outputs[0], mix.inputs[1])
    nt.links.new(emit.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    assert np.allclose(exported().world, 0.75 * np.array([1.0, 0.5, 2.0]) + 0.25 * np.array([4.0, 4.0, 0.0]))
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(mix.outputs[0], add.inputs[0])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    w.color = (0.1, 0.2, 0.3)
    data = exported()
    assert np.allclose(data.world, np.array([1.75, 1.375, 1.5]))
    assert any("world surface has Diffuse BSDF" in t for lvl, t in data.messages if lvl == 'WARNING')


def test_world_light_path_camera_ray_splits_the_world(scene, exported):
    """The artist's backdrop trick: a world Mix Shader whose factor is a Light Path's Is Camera
    Ray. The world lighting the scene is the mix at 0 (its first shader), what camera rays see
    (camera_world) the mix at 1; nothing reported. Without the trick there is no camera_world."""
    setup(scene)
    w = scenes.world((0.5, 0.25, 1.0), 2.0)
    nt = w.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_WORLD')
    assert exported().camera_world is None
    backdrop = nt.nodes.new('ShaderNodeBackground')
    backdrop.inputs['Color'].default_value, backdrop.inputs['Strength'].default_value = (0.9, 0.9, 0.1, 1.0), 0.5
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    nt.links.new(bg.outputs[0], mix.inputs[1])
    nt.links.new(backdrop.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    data = exported()
    assert np.allclose(data.world, (1.0, 0.5, 2.0))
    uniform, env = data.camera_world
    assert np.allclose(uniform, (0.45, 0.45, 0.05)) and env is None
    assert not any("Mix Shader" in t or "Light Path" in t for _, t in data.messages), data.messages
    # a black lighting world beside a camera backdrop, no lights: the backdrop is drawn, so the
    # image is not black (it had said it would be)
    for ob in [o for o in scene.objects if o.type == 'LIGHT']:
        bpy.data.objects.remove(ob)
    bg.inputs['Strength'].default_value = 0.0
    data = exported()
    assert not data.world.any() and data.camera_world[0].any()
    assert not any("will be black" in t for _, t in data.messages), data.messages


def test_world_ray_visibility(scene, exported):
    """World > Ray Visibility's camera, diffuse and transmission toggles reach SceneData as bits."""
    setup(scene)
    scenes.world((0.5, 0.25, 1.0), 2.0)
    assert exported().world_visibility == sd.VIS_CAMERA | sd.VIS_DIFFUSE
    vis = scene.world.cycles_visibility
    for camera, diffuse in ((False, True), (True, False), (False, False)):
        vis.camera, vis.diffuse = camera, diffuse
        assert exported().world_visibility == (sd.VIS_CAMERA if camera else 0) | (sd.VIS_DIFFUSE if diffuse else 0)
    vis.camera, vis.diffuse, vis.transmission = True, True, False
    assert exported().world_visibility == sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.NO_TRANSMISSION
    scene.world = None
    assert exported().world_visibility == sd.VIS_CAMERA | sd.VIS_DIFFUSE


def _sky_pixels(h=8, w=16):
    rng = np.random.default_rng(7)
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = rng.random((h, w, 3), np.float32) * 2.0
    return px


def test_world_environment_texture(scene, exported):
    """An Environment Texture on the Background is exported as its image (linear RGB, row 0 at
    the bottom) with the strength and the Mapping node's rotation: Point and Vector rotate the
    direction (a mirroring scale keeps its signs), Texture is the inverse."""
    setup(scene)
    px = _sky_pixels()
    img = scenes.float_image("Sky", px)
    scenes.environment_world(img, 2.0)
    data = exported()
    env = data.environment
    assert env is not None and np.array_equal(data.world, np.zeros(3, np.float32))
    assert np.allclose(env.pixels[..., :3], px[..., :3]) and np.allclose(env.strength, 2.0)
    assert np.allclose(env.to_map, np.eye(3)) and env.interpolation == 'Linear'
    assert not any("world approximated" in t for _, t in data.messages)
    rot = (0.3, -0.2, 1.2)
    R = np.array(Euler(rot, 'XYZ').to_matrix())
    for kind, scale, expect in (('POINT', (1, -1, 1), R @ np.diag([1, -1, 1])),
                                ('VECTOR', (-2, -2, -2), -R),
                                ('TEXTURE', (1, 1, 1), R.T)):
        scenes.environment_world(img, 1.0, rotation=rot, scale=scale, vector_type=kind, interpolation='Closest')
        data = exported()
        assert np.allclose(data.environment.to_map, expect, atol=1e-6), kind
        assert data.environment.interpolation == 'Closest'
        assert not any("world approximated" in t for _, t in data.messages), kind


def test_world_normal_coordinates_are_minus_the_view_direction(scene, exported):
    """Texture Coordinate > Normal in a world shader is -D (Cycles' shader_setup_from_background:
    N = -ray D), straight into the map or through a Mapping node: the map's other side (it had
    been read as D: red where Cycles shows blue, silently)."""
    setup(scene)
    img = scenes.float_image("Sky", _sky_pixels())
    rot = (0.3, -0.2, 1.2)
    R = np.array(Euler(rot, 'XYZ').to_matrix())
    w = scenes.environment_world(img, 1.0, rotation=rot)
    nt = w.node_tree
    coords = next(n for n in nt.nodes if n.type == 'TEX_COORD')
    mapping = next(n for n in nt.nodes if n.type == 'MAPPING')
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    nt.links.new(coords.outputs['Normal'], mapping.inputs['Vector'])
    data = exported()
    assert np.allclose(data.environment.to_map, -R, atol=1e-6)
    for out in ('Normal', 'Reflection'):        # (Reflection is I = -D where there is no object)
        nt.links.new(coords.outputs[out], env.inputs['Vector'])
        data = exported()
        assert np.allclose(data.environment.to_map, -np.eye(3), atol=1e-6), out
        assert not any("world approximated" in t for _, t in data.messages), out
    nt.links.new(coords.outputs['Generated'], env.inputs['Vector'])
    assert np.allclose(exported().environment.to_map, np.eye(3), atol=1e-6)


def test_world_environment_found_by_its_links(scene, exported):
    """The map a world's colour comes from is found by following the links back (Cycles
    compiles only what reaches the output): linked straight into the World Output's Surface
    (Cycles: an emission of it, strength 1), tinted inside a node group, or tinted beside a
    stray, unconnected second Environment Texture; each is the tinted map, not a constant."""
    setup(scene)
    px = _sky_pixels()
    img = scenes.float_image("Sky", px)
    tint = (0.5, 0.25, 1.0)

    def tinted(nt, env):
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
        mix.inputs['Factor'].default_value = 1.0
        mix.inputs['B'].default_value = (*tint, 1.0)
        nt.links.new(env.outputs['Color'], mix.inputs['A'])
        return mix.outputs['Result']

    w, nt, out = scenes.world_tree()
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = img
    nt.links.new(env.outputs['Color'], out.inputs['Surface'])
    data = exported()
    assert data.environment is not None and np.allclose(data.environment.pixels[..., :3], px[..., :3])
    assert np.allclose(data.environment.strength, 1.0) and not data.world.any()

    w = scenes.environment_world(img, 2.0)
    nt = w.node_tree
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    nt.links.new(tinted(nt, env), bg.inputs['Color'])
    nt.nodes.new('ShaderNodeTexEnvironment').image = img          # stray, linked to nothing
    data = exported()
    assert data.environment is not None
    assert np.allclose(data.environment.pixels, px[..., :3] * tint, rtol=1e-5)
    assert not any("not evaluated" in t for _, t in data.messages)

    g = bpy.data.node_groups.new("Tint", 'ShaderNodeTree')
    g.interface.new_socket("Color", in_out='INPUT', socket_type='NodeSocketColor')
    g.interface.new_socket("Color", in_out='OUTPUT', socket_type='NodeSocketColor')
    gin, gout = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    mix = g.nodes.new('ShaderNodeMix')
    mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
    mix.inputs['Factor'].default_value = 1.0
    mix.inputs['B'].default_value = (*tint, 1.0)
    g.links.new(gin.outputs[0], mix.inputs['A'])
    g.links.new(mix.outputs['Result'], gout.inputs[0])
    w = scenes.environment_world(img, 1.0)
    nt = w.node_tree
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    group = nt.nodes.new('ShaderNodeGroup')
    group.node_tree = g
    nt.links.new(env.outputs['Color'], group.inputs[0])
    nt.links.new(group.outputs[0], bg.inputs['Color'])
    data = exported()
    assert data.environment is not None
    assert np.allclose(data.environment.pixels, px[..., :3] * tint, rtol=1e-5)


def test_nonlinear_colour_nodes_after_a_float_environment_are_reported(scene, exported):
    """Colour nodes after a float environment map are applied to its texels, before the blend:
    exact for a tint (a scale per channel), not for a Gamma, which is now said (it was not: a
    Gamma 2.2 on 0/1 columns read 0.50 where Cycles gives 0.32); 'Closest' reads one texel, exact."""
    setup(scene)
    img = scenes.float_image("Sky", _sky_pixels())
    w = scenes.environment_world(img, 1.0)
    nt = w.node_tree
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    said = lambda: [t for _, t in exported().messages if "applied to its texels before the blend" in t]
    for kind, nonlinear in (('ShaderNodeGamma', True), ('ShaderNodeInvert', False)):
        node = nt.nodes.new(kind)
        if kind == 'ShaderNodeGamma':
            node.inputs['Gamma'].default_value = 2.2
        nt.links.new(env.outputs['Color'], node.inputs['Color'])
        nt.links.new(node.outputs['Color'], bg.inputs['Color'])
        assert bool(said()) == nonlinear, kind
        env.interpolation = 'Closest'
        assert not said(), kind
        env.interpolation = 'Linear'


def test_world_environment_approximations_are_reported(scene, exported):
    setup(scene)
    px = _sky_pixels()
    px[2, 3, 1] = np.nan
    img = scenes.float_image("Sky", px)
    scenes.environment_world(img, 1.0, rotation=(0, 0, 0.5), scale=(1, 2, 1))
    data = exported()
    # the NaN channel kept as NaN, which the native lookups blending it in read as 0 (as Cycles)
    assert data.environment is not None and (~np.isfinite(data.environment.pixels)).sum() == 1
    assert np.isnan(data.environment.pixels[2, 3, 1])
    msg = " ".join(t for _, t in data.messages if "world approximated" in t)
    assert "not finite" in msg and "only its signs" in msg
    w = scenes.environment_world(None, 3.0)                     # no image: magenta, as Cycles
    data = exported()
    assert data.environment is None and np.allclose(data.world, (3.0, 0.0, 3.0))
    assert any("without an image" in t for _, t in data.messages)
    env = next(n for n in w.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    env.image, env.projection = img, 'MIRROR_BALL'    # (resampled into a map: its NaN texel read as 0)
    data = exported()
    assert data.environment is not None and np.isfinite(data.environment.pixels).all()
    assert np.allclose(data.environment.strength, 3.0) and not data.world.any()
    assert any("mirror ball image 'Sky' resampled" in t for _, t in data.messages)
    scenes.environment_world(img, -1.0)
    data = exported()
    assert data.environment is None and not data.world.any()
    assert any("negative" in t for _, t in data.messages)


# -- lights ------------------------------------------------------------------------------------

def test_light_values_in_cycles_units(scene, exported):
    setup(scene)
    point = scenes.light('POINT', 1000.0, (1, 2, 3), color=(1.0, 0.5, 0.25), exposure=1.0,
                         shadow_soft_size=0.5, use_soft_falloff=False)
    spot = scenes.light('SPOT', 200.0, (0, 0, 4), spot_size=math.radians(45), spot_blend=0.5,
                        shadow_soft_size=0.0)
    spot.scale = (1.0, 2.0, 1.0)
    sun = scenes.light('SUN', 3.0, rotation=(0.3, 0, 0), angle=math.radians(20), use_shadow=False)
    warm = scenes.light('POINT', 10.0, name="Warm", use_temperature=True, temperature=3000.0)
    rect = scenes.light('AREA', 100.0, (0, 0, 2), shape='RECTANGLE', size=2.0, size_y=0.5)
    rect.scale = (3.0, 1.0, 1.0)
    disk = scenes.light('AREA', 50.0, (0, 0, 3), name="Disk", shape='DISK', size=1.5, spread=1.0)
    unseen = scenes.light('POINT', 10.0, name="Unseen")
    unseen.visible_diffuse = unseen.visible_transmission = False    # (camera: off by default)
    data = exported()
    L = {l.name: l for l in data.lights}
    # (kept, lighting nothing: Cycles keeps it in its light choice, lights/choiceonly.py)
    assert set(L) == {"Point", "Spot", "Sun", "Warm", "Area", "Disk", "Unseen"}
    assert not (L["Unseen"].visible_camera or L["Unseen"].visible_diffuse or L["Unseen"].visible_transmission)
    assert np.allclose(L["Point"].strength, (2000, 1000, 500))
    assert L["Point"].kind == 'POINT' and L["Point"].radius == 0.5 and not L["Point"].soft_falloff
    assert np.allclose(L["Point"].matrix[:3, 3], (1, 2, 3))
    assert L["Spot"].spot_size == pytest.approx(math.radians(45)) and L["Spot"].spot_blend == 0.5
    assert np.allclose(L["Spot"].matrix, np.array(spot.matrix_world))      # scale kept (cone shape)
    assert np.allclose(L["Sun"].strength, 3.0) and L["Sun"].angle == pytest.approx(math.radians(20))
    assert not L["Sun"].cast_shadow
    assert np.allclose(L["Warm"].strength, 10.0 * np.array(warm.data.temperature_color)[:3])
    assert L["Warm"].strength[0] > L["Warm"].strength[2]                   # 3000 K is reddish
    assert (L["Area"].shape, L["Area"].size_x, L["Area"].size_y) == ('RECTANGLE', 2.0, 0.5)
    assert np.allclose(np.linalg.norm(L["Area"].matrix[:3, 0]), 3.0)
    assert (L["Disk"].shape, L["Disk"].size_x, L["Disk"].size_y) == ('DISK', 1.5, 1.5)
    assert L["Disk"].spread == pytest.approx(1.0)



def test_degenerate_and_negative_lights_skipped_with_a_message(scene, exported):
    """Lights Blender allows but Cycles gets no (positive) light from: an area light of zero
    size or at a zero object scale emits nothing; a negative strength, which Cycles subtracts,
    is not supported. Each is left out with a message naming it; the rest export as usual."""
    setup(scene)
    scenes.light('AREA', 100.0, (0, 0, 2), name="NoSize", size=0.0)
    flat = scenes.light('AREA', 100.0, (0, 0, 2), name="Squashed", shape='RECTANGLE', size=1.0, size_y=1.0)
    flat.scale = (1.0, 0.0, 1.0)
    scenes.light('POINT', -500.0, (0, 0, 2), name="Negative")
    scenes.light('POINT', float('inf'), (0, 0, 2), name="Infinite")
    scenes.light('AREA', 100.0, (0, 0, 2), name="Beam", spread=0.0)
    cone = scenes.light('SPOT', 100.0, (0, 0, 2), name="NoCone")
    cone.scale = (1.0, 0.0, 1.0)
    scenes.light('AREA', 100.0, (0, 0, 3), name="Fine", size=0.5)
    scenes.light('SUN', 3.0, name="WideSun", angle=math.pi)     # 180 degrees: float32 pi > pi
    # a zero Z scale: a sun and an area light face no direction (no light in Cycles; the sun
    # failed the whole render)
    scenes.light('SUN', 3.0, name="FlatSun").scale = (1.0, 1.0, 0.0)
    scenes.light('AREA', 100.0, (0, 0, 2), name="FlatArea", size=0.5).scale = (1.0, 1.0, 0.0)
    # a NaN location or rotation: skipped, not a failed render (it was)
    scenes.light('POINT', 100.0, (float('nan'), 0, 2), name="Lost")
    scenes.light('AREA', 100.0, (0, 0, 2), name="Spun").rotation_euler = (float('nan'), 0.0, 0.0)
    # a NaN size, angle or radius set from Python (Blender's ranges let it through): skipped,
    # where it failed the whole render
    nan = float('nan')
    scenes.light('SPOT', 100.0, (0, 0, 2), name="NanCone", spot_size=nan)
    scenes.light('SPOT', 100.0, (0, 0, 2), name="NanBlend", spot_blend=nan)
    scenes.light('POINT', 100.0, (0, 0, 2), name="NanRadius", shadow_soft_size=nan)
    # (a NaN sun angle or area spread renders as 0, as in Cycles: test_bad_input_lights.py)
    data = exported()
    assert [l.name for l in data.lights] == ["Beam", "Fine", "WideSun"]
    assert data.lights[0].spread == export.lights.MIN_SPREAD            # Cycles: a beam, not nothing
    assert data.lights[2].angle > math.pi                       # as Blender stores it
    warnings = [t for lvl, t in data.messages if lvl == 'WARNING']
    for name, why in (("NoSize", "zero area"), ("Squashed", "zero area"), ("Negative", "negative strength"),
                      ("Infinite", "non-finite strength"), ("NoCone", "zero object scale"),
                      ("Lost", "non-finite transform"), ("Spun", "non-finite transform"),
                      ("NanCone", "non-finite spot_size"), ("NanBlend", "non-finite spot_blend"),
                      ("NanRadius", "non-finite radius"), ("FlatSun", "zero object scale along Z"),
                      ("FlatArea", "zero object scale along Z")):
        assert any(f"'{name}'" in t and why in t for t in warnings), (name, warnings)
    lamps = [ls.make_lamp(l) for l in data.lights]              # the integrator takes them
    assert ls.LightSet(lamps, None, 0).num_lamps == 3
    assert lamps[2].omc == 1.0                                   # the lights layer: a hemisphere


def test_light_edge_cases_as_cycles_renders_them(scene, exported):
    """A spot of zero Z scale is Cycles' limit of a tiny one (the cone stretched to the half-space
    in front; it was skipped); a Background shader in a light's node tree or on a surface emits
    (it lit nothing, or was rendered as diffuse); a light in an Indirect Only collection is not
    seen by the camera; a negative strength from the node tree is reported as the strength the
    light has, and the 'no lights' message counts the lights skipped."""
    setup(scene)
    flat = scenes.light('SPOT', 100.0, (0, 0, 2), name="FlatSpot", spot_size=math.radians(40.0))
    flat.scale = (1.0, 1.0, 0.0)
    thin = scenes.light('SPOT', 100.0, (0, 0, 2), name="ThinSpot", spot_size=math.radians(40.0))
    thin.scale = (1.0, 1.0, 1e-6)
    scaled = bpy.data.objects.new("Scaled", None)        # a rotated child of a scaled parent
    scene.collection.objects.link(scaled)
    scaled.scale = (3.0, 1.0, 0.3)
    leaning = scenes.light('SPOT', 100.0, (0, 0, 2), name="Leaning")
    leaning.parent, leaning.rotation_euler = scaled, (0.3, 0.25, 0.0)
    bg = scenes.light('AREA', 10.0, (0, 0, 3), name="BgLight", size=1.0)
    bg.data.use_nodes = True
    nt = bg.data.node_tree
    back = nt.nodes.new('ShaderNodeBackground')
    back.inputs['Color'].default_value = (0.2, 0.5, 1.0, 1.0)
    back.inputs['Strength'].default_value = 2.0
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')
    nt.links.new(back.outputs[0], out.inputs['Surface'])
    hidden = bpy.data.collections.new("Bounce")
    scene.collection.children.link(hidden)
    lamp = scenes.light('POINT', 100.0, (0, 0, 2), name="InBounce")
    lamp.visible_camera = True
    for c in lamp.users_collection:
        c.objects.unlink(lamp)
    hidden.objects.link(lamp)
    scene.view_layers[0].layer_collection.children["Bounce"].indirect_only = True
    mat, nt, out = scenes._material("Backdrop")
    back = nt.nodes.new('ShaderNodeBackground')
    back.inputs['Color'].default_value = (0.1, 0.2, 0.3, 1.0)
    back.inputs['Strength'].default_value = 3.0
    nt.links.new(back.outputs[0], out.inputs['Surface'])
    scenes.plane("Wall", materials=(mat,))
    data = exported()
    lights = {l.name: l for l in data.lights}
    assert set(lights) == {"FlatSpot", "ThinSpot", "BgLight", "InBounce", "Leaning"}
    text = " | ".join(t for _, t in data.messages)
    assert "spot light 'Leaning' has a sheared transform" in text and "'ThinSpot' has a sheared" not in text
    np.testing.assert_allclose(lights["BgLight"].strength, 10.0 * 2.0 * np.array([0.2, 0.5, 1.0]), rtol=1e-6)
    assert not lights["InBounce"].visible_camera and lights["InBounce"].visible_diffuse
    backdrop = next(m for m in data.materials if m.name == "Backdrop")
    np.testing.assert_allclose(backdrop.emission, [0.3, 0.6, 0.9], rtol=1e-6)
    assert "as diffuse" not in backdrop.approximated
    # the zero-scale spot lights as the 1e-6 one does, the whole half-space below it
    rng = np.random.default_rng(3)
    P = np.stack([rng.uniform(-20, 20, 400), rng.uniform(-20, 20, 400), np.full(400, -1.0)]).astype(np.float32)
    u = rng.random((2, 400)).astype(np.float32)
    flat_s, thin_s = (ls.make_lamp(lights[n]).sample(P, u[0], u[1]) for n in ("FlatSpot", "ThinSpot"))
    np.testing.assert_allclose(flat_s.value, thin_s.value, rtol=1e-3, atol=1e-9)
    assert (flat_s.value > 0).all()                  # no cone left: every point below is lit

    bpy.data.objects.remove(flat)
    bpy.data.objects.remove(thin)
    bpy.data.objects.remove(lamp)
    bpy.data.objects.remove(leaning)
    bg.data.node_tree.nodes['Background'].inputs['Strength'].default_value = -1.0
    data = exported()
    text = " | ".join(t for _, t in data.messages)
    assert "'BgLight' has a negative strength (-2, -5, -10 W per channel" in text, text
    assert "no light objects (1 light object(s) give none)" in text, text


def test_portal_area_lights_emit_nothing(scene, exported):
    """A portal only guides Cycles' world sampling and adds no light of its own."""
    setup(scene)
    portal = scenes.light('AREA', 500.0, (0, 0, 2), name="Window", size=1.0)
    portal.data.cycles.is_portal = True
    scenes.light('AREA', 100.0, (0, 0, 3), name="Lamp", size=0.5)
    assert [l.name for l in exported().lights] == ["Lamp"]


def test_sheared_area_light_is_reported(scene, exported):
    """An area light turned under a non-uniformly scaled parent has a sheared matrix, which
    Cycles renders as if its axes were orthogonal: the render says so, naming the light; a
    light scaled non-uniformly on its own axes is not sheared and says nothing."""
    setup(scene)
    parent = scenes.link(bpy.data.objects.new("Rig", None))
    parent.scale = (2.0, 0.5, 1.0)
    sheared = scenes.light('AREA', 100.0, (0, 0, 3), rotation=(0.3, 0.0, 0.6), name="Tilted", size=0.5)
    sheared.parent = parent
    plain = scenes.light('AREA', 100.0, (2, 0, 3), name="Stretched", size=0.5)
    plain.scale = (3.0, 0.5, 1.0)
    s = exported()
    assert {l.name for l in s.lights} == {"Tilted", "Stretched"}
    said = [t for _, t in s.messages if "sheared" in t]
    assert len(said) == 1 and "'Tilted'" in said[0], said


def test_light_max_bounces_exported(scene, exported):
    """Cycles' Light > Max Bounces reaches the render (light sampling skips the light deeper),
    with nothing reported."""
    setup(scene)
    scene.dacrt.max_bounces = 4
    scenes.light('SUN', 3.0, name="Direct").data.cycles.max_bounces = 0
    scenes.light('SUN', 3.0, name="Enough").data.cycles.max_bounces = 4
    s = exported()
    assert {l.name: l.max_bounces for l in s.lights} == {"Direct": 0, "Enough": 4}
    assert not any("Max Bounces" in t for _, t in s.messages)


def test_negative_or_non_finite_material_values_become_zero_with_a_reason(scene, exported):
    """Blender takes a negative emission strength or a NaN colour from a script or driver; the
    export sets a NaN colour's channel to 0 and says so, instead of failing the render. A
    negative emission is Cycles' too (it emits it): kept signed, per point, unsaid
    (tests/addon/test_message_truth.py)."""
    setup(scene)
    scenes.plane("Dark", materials=(scenes.emission("NegEmit", (1.0, 0.5, 0.25), -2.0),))
    scenes.plane("Odd", location=(3, 0, 0), materials=(scenes.diffuse("NanColour", (float('nan'), 0.5, 0.5)),))
    data = exported()
    m = {m.name: m for m in data.materials}
    np.testing.assert_allclose(m["NegEmit"].emission, [2.0, 1.0, 0.5])     # (its magnitude: the light's weight)
    assert m["NegEmit"].emission_texture is not None and not m["NegEmit"].approximated
    assert np.array_equal(m["NanColour"].base_color, np.float32([0.0, 0.5, 0.5]))
    assert "non-finite colour" in m["NanColour"].approximated


def test_negative_world_rendered_black_with_a_message(scene, exported):
    setup(scene)
    scenes.world((0.5, 0.5, 0.5), strength=-1.0)
    data = exported()
    assert np.array_equal(data.world, np.zeros(3, np.float32))
    assert any("world approximated" in t and "negative" in t for _, t in data.messages)


def test_material_without_output_node_is_black(scene, exported):
    """A node tree with no Material Output renders black in Cycles (no surface shader); it used
    to stop the export with an AttributeError."""
    setup(scene)
    mat = bpy.data.materials.new("NoOutput")
    mat.node_tree.nodes.clear()
    mat.node_tree.nodes.new('ShaderNodeBsdfDiffuse')
    scenes.plane("P", materials=(mat,))
    data = exported()
    idx = next(i for i, m in enumerate(data.materials) if m.name == "NoOutput")
    m = data.materials[idx]
    assert np.all(m.base_color == 0) and np.all(m.emission == 0) and not m.approximated
    assert np.all(data.geometry.material == idx)


def test_muted_nodes_pass_through_as_in_cycles(scene, exported):
    """Blender and Cycles pass a muted node through its internal links: a muted Invert or Math
    gives its linked input, a muted Mix Shader its linked shader, a muted Diffuse BSDF no
    closure (black), and a muted node whose passed-through input is unlinked leaves the input
    it feeds at that input's own value (checked against Cycles: a Diffuse's 0.8). Before, muted
    colour nodes were evaluated as if unmuted and muted shaders became a grey diffuse."""
    setup(scene)
    mats = {}

    def new(name):
        mat, nt, out = scenes._material(name)
        mats[name] = mat
        return nt, out

    nt, out = new("Invert")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.9, 0.1, 0.1, 1)
    inv = nt.nodes.new('ShaderNodeInvert')
    inv.mute = True
    nt.links.new(rgb.outputs[0], inv.inputs['Color'])
    nt.links.new(inv.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])

    nt, out = new("Math")
    e = nt.nodes.new('ShaderNodeEmission')
    v = nt.nodes.new('ShaderNodeValue')
    v.outputs[0].default_value = 0.5
    mt = nt.nodes.new('ShaderNodeMath')
    mt.operation, mt.mute = 'MULTIPLY', True
    mt.inputs[1].default_value = 10.0
    nt.links.new(v.outputs[0], mt.inputs[0])
    nt.links.new(mt.outputs[0], e.inputs['Strength'])
    nt.links.new(e.outputs[0], out.inputs['Surface'])

    nt, out = new("MixShader")
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.mute = True
    red = nt.nodes.new('ShaderNodeBsdfDiffuse')
    red.inputs['Color'].default_value = (0.8, 0.1, 0.1, 1)
    nt.links.new(red.outputs[0], mix.inputs[2])          # the only linked shader input
    nt.links.new(mix.outputs[0], out.inputs['Surface'])

    nt, out = new("Diffuse")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.1, 0.2, 0.9, 1)
    d.mute = True
    nt.links.new(d.outputs[0], out.inputs['Surface'])

    nt, out = new("Unlinked")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.3, 0.6, 0.2, 1)
    inv = nt.nodes.new('ShaderNodeInvert')
    inv.mute = True
    inv.inputs['Color'].default_value = (0.9, 0.1, 0.1, 1)
    nt.links.new(inv.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])

    for i, mat in enumerate(mats.values()):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    table = {m.name: m for m in exported().materials}
    assert np.allclose(table["Invert"].base_color, (0.9, 0.1, 0.1))
    assert np.allclose(table["Math"].emission, 0.5)
    assert np.allclose(table["MixShader"].base_color, (0.8, 0.1, 0.1))
    assert np.all(table["Diffuse"].base_color == 0) and np.all(table["Diffuse"].emission == 0)
    assert np.allclose(table["Unlinked"].base_color, (0.3, 0.6, 0.2))
    assert not any(table[n].approximated for n in mats)


def test_a_colour_or_value_into_a_shader_input_is_its_emission(scene, exported):
    """Cycles turns a colour, vector or float output linked into a shader input into an
    Emission of that value (strength 1; ShaderGraph::connect), in materials and the world.
    Before, the material became the default grey diffuse and the world its viewport colour."""
    setup(scene)
    mat, nt, out = scenes._material("ColorSurface")
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.9, 0.2, 0.1, 1)
    nt.links.new(rgb.outputs[0], out.inputs['Surface'])
    val, vnt, vout = scenes._material("ValueSurface")
    v = vnt.nodes.new('ShaderNodeValue')
    v.outputs[0].default_value = 0.75
    add = vnt.nodes.new('ShaderNodeAddShader')           # one level down, beside a diffuse
    vnt.links.new(v.outputs[0], add.inputs[0])
    vnt.links.new(vnt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], add.inputs[1])
    vnt.links.new(add.outputs[0], vout.inputs['Surface'])
    scenes.plane("A", materials=(mat,))
    scenes.plane("B", location=(3, 0, 0), materials=(val,))
    w = scenes.world((0.5, 0.5, 0.5), 1.0)
    sky = w.node_tree.nodes.new('ShaderNodeRGB')
    sky.outputs[0].default_value = (0.2, 0.4, 0.6, 1)
    w.node_tree.links.new(sky.outputs[0], next(n for n in w.node_tree.nodes if n.type == 'OUTPUT_WORLD').inputs['Surface'])
    data = exported()
    table = {m.name: m for m in data.materials}
    assert np.allclose(table["ColorSurface"].emission, (0.9, 0.2, 0.1))
    assert np.all(table["ColorSurface"].base_color == 0) and not table["ColorSurface"].approximated
    assert np.allclose(table["ValueSurface"].emission, 0.75)
    assert np.allclose(table["ValueSurface"].base_color, 0.8)
    assert np.allclose(data.world, (0.2, 0.4, 0.6))
    assert not any("world approximated" in t for _, t in data.messages)


def _image_emission(name, img, strength):
    """A material whose Emission (of `strength`) takes its colour from an Image Texture of img."""
    mat, nt, out = scenes._material(name)
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Strength'].default_value = strength
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    nt.links.new(tex.outputs['Color'], e.inputs['Color'])
    nt.links.new(e.outputs[0], out.inputs['Surface'])
    return mat


def test_image_driven_emission_is_the_image(scene, exported):
    """An Emission (or Principled emission) colour from an image (a screen, a sign) emits the
    image x strength, looked up per hit and per light sample (tests/parity/test_emission_texture.py),
    and `emission` holds its average, which weighs the light choice; an image into the strength
    bakes colour x strength per texel. Before, the socket's own value (the Emission node's
    default white) was emitted."""
    setup(scene)
    img = bpy.data.images.new("Screen", 2, 2, float_buffer=True)
    px = np.array([[0.2, 0.4, 0.6, 1], [1.0, 0.0, 0.0, 1], [0.0, 1.0, 0.0, 1], [0.6, 0.6, 0.2, 1]])
    img.pixels[:] = px.ravel()
    mat = _image_emission("Screen", img, 3.0)
    pmat = scenes.principled("Sign", (0.5, 0.5, 0.5), (1.0, 0.5, 1.0), 1.0)
    p = next(n for n in pmat.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    ptex = pmat.node_tree.nodes.new('ShaderNodeTexImage')
    ptex.image = img
    pmat.node_tree.links.new(ptex.outputs['Color'], p.inputs['Emission Strength'])   # as its grey
    scenes.plane("A", materials=(mat,))
    scenes.plane("B", location=(3, 0, 0), materials=(pmat,))
    table = {m.name: m for m in exported().materials}
    screen, sign = table["Screen"], table["Sign"]
    assert np.allclose(screen.emission, 3.0 * px[:, :3].mean(axis=0), rtol=1e-6) and not screen.approximated
    assert np.allclose(np.asarray(screen.emission_texture)[..., :3].reshape(-1, 3), 3.0 * px[:, :3], rtol=1e-6)
    grey = px[:, :3] @ np.array([0.2126729, 0.7151522, 0.0721750])                    # Rec.709 luminance
    texels = np.asarray(sign.emission_texture)[..., :3].reshape(-1, 3)
    assert np.allclose(texels, grey[:, None] * np.array([1.0, 0.5, 1.0]), rtol=1e-4)
    assert np.allclose(sign.emission, texels.mean(axis=0), rtol=1e-6)


def test_emission_image_with_a_nan_texel_keeps_its_channel(scene, exported):
    """One NaN texel of 4 in an emission image: that texel emits 0 (noted, naming the image)
    and the rest as usual; the average had been NaN and the emitter lost the whole channel."""
    setup(scene)
    img = bpy.data.images.new("Glitch", 2, 2, float_buffer=True)
    px = np.ones((4, 4))
    px[1, 0] = np.nan
    img.pixels[:] = px.ravel()
    mat = _image_emission("Lamp", img, 2.0)
    scenes.plane("A", materials=(mat,))
    m = {m.name: m for m in exported().materials}["Lamp"]
    assert np.allclose(m.emission, [1.5, 2.0, 2.0])
    texels = np.asarray(m.emission_texture)[..., :3].reshape(-1, 3)
    assert np.isfinite(texels).all() and texels[:, 0].tolist().count(0.0) == 1
    assert "image 'Glitch'" in m.approximated


def test_world_volume_is_reported(scene, exported):
    """A world's Volume (fog, haze) is not rendered, and the render says so, as it does for a
    material's; the world's Surface is rendered as before."""
    setup(scene)
    w = scenes.world((0.5, 0.5, 0.5), 1.0)
    out = next(n for n in w.node_tree.nodes if n.type == 'OUTPUT_WORLD')
    fog = w.node_tree.nodes.new('ShaderNodeVolumeScatter')
    w.node_tree.links.new(fog.outputs[0], out.inputs['Volume'])
    data = exported()
    assert np.allclose(data.world, 0.5)
    assert any(lvl == 'WARNING' and "world volume ignored" in t for lvl, t in data.messages)
    w.node_tree.links.remove(out.inputs['Surface'].links[0])      # a volume alone: still said
    data = exported()
    assert np.allclose(data.world, 0.0)
    assert any("world volume ignored" in t for _, t in data.messages)


def test_default_surface_reported_only_when_used(scene, exported):
    """Cycles renders an object without a material with Blender's default surface, a Principled
    BSDF whose specular layer is rendered as diffuse over the 0.8 base: said in the
    approximation message, and only when some triangle uses it."""
    setup(scene)
    scenes.plane("Bare")
    scenes.plane("Painted", location=(3, 0, 0), materials=(scenes.diffuse("Paint", (0.5, 0.5, 0.5)),))
    data = exported()
    assert np.allclose(data.materials[0].base_color, export.materials.DEFAULT_SURFACE_ALBEDO)
    assert 0.805 < export.materials.DEFAULT_SURFACE_ALBEDO[0] < 0.82      # 0.8 (1 - layer) + layer
    assert any("default surface" in t for _, t in data.messages)
    bpy.data.objects.remove(bpy.data.objects["Bare"])
    data = exported()
    assert not any("default surface" in t for _, t in data.messages)

def test_light_ray_visibility(scene, exported):
    """A light's Object > Visibility > Ray Visibility reaches SceneData.Light: Camera (off on a
    new light object in Blender 5.0) and Diffuse; an instancer's visibility is inherited; a
    light no ray kind can see (Transmission and Glossy off too) is kept with its flags (it had
    been skipped): Cycles keeps it in its light choice (lights/choiceonly.py)."""
    setup(scene)
    scenes.plane("Floor")       # Blender's default surface: a glossy layer rendered as diffuse
    default = scenes.light('AREA', 10.0, (0, 0, 2), name="Default")
    seen = scenes.light('AREA', 10.0, (0, 0, 3), name="Seen")
    seen.visible_camera = True
    camera_only = scenes.light('AREA', 10.0, (0, 0, 4), name="CameraOnly")
    camera_only.visible_camera, camera_only.visible_diffuse = True, False
    ghost = scenes.light('POINT', 10.0, (0, 0, 5), name="Ghost")
    ghost.visible_camera = ghost.visible_diffuse = ghost.visible_transmission = ghost.visible_glossy = False
    # a camera-visible light instanced by an empty whose diffuse visibility is off
    col = bpy.data.collections.new("Lamps")
    scene.collection.children.link(col)
    inst = bpy.data.objects.new("Inst", bpy.data.lights.new("Inst", 'AREA'))
    inst.data.energy = 10.0
    inst.visible_camera = True
    col.objects.link(inst)
    scene.collection.children.unlink(col)
    empty = scenes.link(bpy.data.objects.new("Instancer", None))
    empty.instance_type, empty.instance_collection, empty.location = 'COLLECTION', col, (5, 0, 0)
    empty.visible_diffuse = False
    assert not default.visible_camera and default.visible_diffuse          # Blender's defaults
    data = exported()
    L = {l.name: l for l in data.lights}
    assert set(L) == {"Default", "Seen", "CameraOnly", "Inst", "Ghost"}
    assert not (L["Ghost"].visible_camera or L["Ghost"].visible_diffuse or L["Ghost"].visible_transmission)
    assert (L["Default"].visible_camera, L["Default"].visible_diffuse) == (False, True)
    assert (L["Seen"].visible_camera, L["Seen"].visible_diffuse) == (True, True)
    assert (L["CameraOnly"].visible_camera, L["CameraOnly"].visible_diffuse) == (True, False)
    assert (L["Inst"].visible_camera, L["Inst"].visible_diffuse) == (True, False)
    assert L["Inst"].matrix[0, 3] == pytest.approx(5.0)
    # Glossy visibility apart from Diffuse: glossy layers (rendered as diffuse) follow Diffuse,
    # said per light (Cycles: a metallic floor under a Glossy-off light 0.0, DACRT 1.02, silent)
    glossy = [t for _, t in data.messages if "ray visibility Glossy" in t]
    # (the instancer's flag: named)
    assert len(glossy) == 1 and "'CameraOnly', 'Inst' (instanced by 'Instancer')" in glossy[0] \
        and "Glossy on with Diffuse off" in glossy[0], glossy
    seen.visible_glossy = False
    text = " | ".join(t for _, t in exported().messages)
    assert "Glossy off with Diffuse on" in text and "'Seen'" in text


def test_instanced_lights(scene, exported):
    setup(scene)
    col = bpy.data.collections.new("Lamps")
    scene.collection.children.link(col)
    lamp = scenes.light('POINT', 100.0, (0, 0, 1))
    scene.collection.objects.unlink(lamp)
    col.objects.link(lamp)
    for x in (5, 10):
        e = scenes.link(bpy.data.objects.new(f"E{x}", None))
        e.instance_type, e.instance_collection, e.location = 'COLLECTION', col, (x, 0, 0)
    data = exported()
    xs = sorted(l.matrix[0, 3] for l in data.lights)
    assert xs == [0, 5, 10]


# -- settings ------------------------------------------------------------------------------------

def test_settings_follow_scene_dacrt_and_blender(scene, exported):
    setup(scene)
    d = scene.dacrt
    d.samples, d.max_bounces, d.filter_type, d.filter_width, d.seed, d.partition = \
        17, 2, 'GAUSSIAN', 2.5, 99, 'SAH'
    scene.render.threads_mode, scene.render.threads = 'FIXED', 1
    scene.render.film_transparent = True
    layer = bpy.context.view_layer
    layer.use_pass_z = layer.use_pass_diffuse_color = True
    s = exported().settings
    assert (s.samples, s.max_bounces, s.filter_type, s.filter_width, s.seed, s.partition) == \
        (17, 2, 'GAUSSIAN', 2.5, 99, 'sah')
    assert s.threads == 1 and s.film_transparent and s.passes == ('Depth', 'DiffCol')
    scene.render.threads_mode = 'AUTO'
    assert exported().settings.threads == 0
    assert not exported().settings.use_adaptive_sampling
    d.use_adaptive_sampling, d.adaptive_threshold, d.adaptive_min_samples = True, 0.02, 12
    s = exported().settings
    assert s.use_adaptive_sampling and s.adaptive_threshold == pytest.approx(0.02) and s.adaptive_min_samples == 12
    # Light Paths > Clamping with Cycles' defaults (direct off, indirect 10)
    assert (s.sample_clamp_direct, s.sample_clamp_indirect) == (0.0, pytest.approx(10.0))
    scene.cycles.sample_clamp_indirect = 3.0                  # Cycles' own settings do not leak in
    d.sample_clamp_direct, d.sample_clamp_indirect = 4.0, 0.0
    s = exported().settings
    assert (s.sample_clamp_direct, s.sample_clamp_indirect) == (4.0, 0.0)
    # the Mist pass's settings: the world's (falloff as Cycles' exponent), Cycles' film defaults without one
    layer.use_pass_mist = True
    scene.world = None
    s = exported().settings
    assert s.passes == ('Depth', 'Mist', 'DiffCol') and s.mist == (0.0, 100.0, 1.0)
    scene.world = bpy.data.worlds.new("W")
    for falloff, power in (('QUADRATIC', 2.0), ('LINEAR', 1.0), ('INVERSE_QUADRATIC', 0.5)):
        m = scene.world.mist_settings
        m.start, m.depth, m.falloff = 1.5, 7.0, falloff
        assert exported().settings.mist == pytest.approx((1.5, 7.0, power))


def test_materials_no_triangle_uses_are_never_evaluated(scene, exported, monkeypatch):
    setup(scene)
    used, unused = scenes.diffuse("Used", (0.5, 0.5, 0.5)), scenes.diffuse("OnlyInAnUnusedSlot", (0.1, 0.9, 0.1))
    scenes.plane("Plane", materials=(used, unused))              # every face uses slot 0
    built = []
    real = export.materials.MaterialBuilder._build
    monkeypatch.setattr(export.materials.MaterialBuilder, '_build', lambda self, m: built.append(m.name) or real(self, m))
    data = exported()
    assert built == ["Used"] and [m.name for m in data.materials][1:] == ["Used"]
    assert data.skipped['materials_unused'] == 1
    # the same material used on a face of another object is evaluated once
    scenes.plane("Other", location=(3, 0, 0), materials=(unused,))
    built.clear()
    data = exported()
    assert sorted(built) == ["OnlyInAnUnusedSlot", "Used"] and data.skipped['materials_unused'] == 0


def test_empty_scene_exports_and_says_so(scene, exported):
    setup(scene)
    data = exported()
    assert len(data.geometry.triangles) == 0 and data.lights == []
    text = " ".join(t for _, t in data.messages)
    assert "no renderable geometry" in text and "no lights" in text


def test_sky_texture_vector_not_reproduced_is_reported(scene, exported):
    """A Sky Texture's Vector from nodes other than a Mapping rotation: the view direction,
    reported naming the sky and the node; every sky type gives a map."""
    setup(scene)
    w = scenes.world((0.2, 0.2, 0.2), 1.0)
    nt = w.node_tree
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sun_disc = False                         # (with the disc on, Blender hides the Vector input)
    nt.links.new(sky.outputs[0], next(n for n in nt.nodes if n.type == 'BACKGROUND').inputs['Color'])
    add = nt.nodes.new('ShaderNodeVectorMath')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Generated'], add.inputs[0])
    nt.links.new(add.outputs[0], sky.inputs[0])
    for kind in ('MULTIPLE_SCATTERING', 'SINGLE_SCATTERING', 'PREETHAM', 'HOSEK_WILKIE'):
        sky.sky_type = kind
        data = exported()
        assert data.environment is not None and data.environment.pixels[..., :3].max() > 0
        assert any("Sky Texture 'Sky Texture'" in t and "'Vector Math'" in t for _, t in data.messages), kind


def test_light_node_tree_and_world_approximation_reported(scene, exported):
    setup(scene)
    lamp = scenes.light('POINT', 100.0)
    lamp.data.use_nodes = True
    emit = next(n for n in lamp.data.node_tree.nodes if n.type == 'EMISSION')
    emit.inputs['Strength'].default_value = 2.0
    emit.inputs['Color'].default_value = (1.0, 0.5, 1.0, 1.0)
    w = scenes.world((0.2, 0.2, 0.2), 3.0)
    sky = w.node_tree.nodes.new('ShaderNodeTexSky')
    bg = next(n for n in w.node_tree.nodes if n.type == 'BACKGROUND')
    w.node_tree.links.new(sky.outputs[0], bg.inputs['Color'])
    data = exported()                             # a Sky Texture straight in: its map, not reported
    assert data.environment is not None and np.allclose(data.environment.strength, 3.0)
    assert not any("world approximated" in t for _, t in data.messages)
    other = w.node_tree.nodes.new('ShaderNodeTexSky')    # two skies mixed: not evaluated
    mix = scenes.mix_node(w.node_tree, 'MIX', sky.outputs[0], other.outputs[0])
    w.node_tree.links.new(mix.outputs['Result'], bg.inputs['Color'])
    data = exported()
    assert np.allclose(data.lights[0].strength, (200.0, 100.0, 200.0))
    assert np.allclose(data.world, 0.6) and data.environment is None    # the Background's own colour x strength
    assert any(lvl == 'WARNING' and "world approximated" in t and "Sky Texture" in t for lvl, t in data.messages)
    # nothing reaching the output's Surface: Cycles' light emits nothing (exact, not reported)
    emit.mute = True
    data = exported()
    assert np.allclose(data.lights[0].strength, 0.0)
    assert not any("light 'Point'" in t or "Light'" in t for _, t in data.messages if "node tree" in t)
    emit.mute = False
    out = next(n for n in lamp.data.node_tree.nodes if n.type == 'OUTPUT_LIGHT')
    lamp.data.node_tree.links.remove(out.inputs['Surface'].links[0])
    assert np.allclose(exported().lights[0].strength, 0.0)


def test_light_node_trees_as_cycles_evaluates_them(scene, exported):
    """A light's shader is its emission, as Cycles evaluates it: a Mix or Add of Emissions, a
    colour linked into Surface (an emission of it), a Light Falloff's Quadratic (its own
    Strength); a BSDF emits nothing. They had rendered at the light's colour and power alone
    (Mix 0.5x, Add 0.25x, an RGB node 1.1-5x, Light Falloff 0.02x, a Diffuse BSDF full power)."""
    setup(scene)
    lamp = scenes.light('POINT', 100.0)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')
    a = next(n for n in nt.nodes if n.type == 'EMISSION')
    a.inputs['Color'].default_value, a.inputs['Strength'].default_value = (1.0, 0.5, 0.25, 1.0), 2.0
    b = nt.nodes.new('ShaderNodeEmission')
    b.inputs['Color'].default_value, b.inputs['Strength'].default_value = (0.0, 1.0, 1.0, 1.0), 4.0
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.25
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])

    def strength():
        data = exported()
        warned = [t for _, t in data.messages if "light 'Point'" in t]
        return data.lights[0].strength / 100.0, warned
    s, warned = strength()
    assert np.allclose(s, 0.75 * np.array([2.0, 1.0, 0.5]) + 0.25 * np.array([0.0, 4.0, 4.0])) and not warned
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(a.outputs[0], add.inputs[0])
    nt.links.new(b.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    assert np.allclose(strength()[0], [2.0, 5.0, 4.5])
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.2, 0.4, 0.8, 1.0)
    nt.links.new(rgb.outputs[0], out.inputs['Surface'])
    assert np.allclose(strength()[0], [0.2, 0.4, 0.8])
    falloff = nt.nodes.new('ShaderNodeLightFalloff')
    falloff.inputs['Strength'].default_value = 7.0
    nt.links.new(falloff.outputs['Quadratic'], a.inputs['Strength'])
    nt.links.new(a.outputs[0], out.inputs['Surface'])
    s, warned = strength()
    assert np.allclose(s, [7.0, 3.5, 1.75]) and not warned
    nt.links.new(falloff.outputs['Linear'], a.inputs['Strength'])
    s, warned = strength()
    # (the Linear output's distance the lamp applies per ray: its falloff, nothing said)
    assert np.allclose(s, [7.0, 3.5, 1.75]) and not warned and exported().lights[0].falloff == (1, 0.0)
    # into the Colour: grey of its Strength (had stood at the socket's own colour: Cycles 0.320
    # where DACRT gave 0.107 for a Strength of 3)
    nt.links.new(falloff.outputs['Quadratic'], a.inputs['Color'])
    s, warned = strength()
    assert np.allclose(s, [49.0, 49.0, 49.0]) and not warned and exported().lights[0].falloff == (1, 0.0)
    nt.links.remove(a.inputs['Color'].links[0])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], out.inputs['Surface'])
    s, warned = strength()
    # (exact, as Cycles' light shader emits nothing from a BSDF: the lamp is skipped as dark
    # with that cause, not warned of as approximated)
    assert np.allclose(s, 0.0) and not warned and "emits no light" in exported().lights[0].no_emission
    # a Principled BSDF lights by its emission layer (measured in Cycles: Emission Color
    # (1, 0.5, 0.2) x Strength 2 gave 2.08, 1.04, 0.42 of the 1.04 of a plain area light; DACRT
    # had rendered 0 with "emits no light")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Emission Color'].default_value = (1.0, 0.5, 0.2, 1.0)
    p.inputs['Emission Strength'].default_value = 2.0
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    s, warned = strength()
    assert np.allclose(s, [2.0, 1.0, 0.4]) and not warned
    p.inputs['Alpha'].default_value = 0.5
    nt.links.new(p.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    assert np.allclose(strength()[0], [7.0, 3.5, 1.75] + 0.5 * np.array([2.0, 1.0, 0.4]))


def test_missing_image_is_magenta_like_cycles(scene, exported):
    setup(scene)
    empty_node = _image_material("NoImage", None)
    broken = bpy.data.images.new("Gone", 4, 4)
    broken.source, broken.filepath = 'FILE', "//does/not/exist.png"
    scenes.plane("A", materials=(empty_node,))
    scenes.plane("B", location=(3, 0, 0), materials=(_image_material("Broken", broken),))
    data = exported()
    table = {m.name: m for m in data.materials}
    for name in ("NoImage", "Broken"):
        assert table[name].texture is None and np.allclose(table[name].base_color, (1, 0, 1)), name
        assert table[name].approximated, name


def test_light_groups_exported(scene, exported):
    """The view layer's Light Groups and each emitter's group: lights, objects, the world."""
    setup(scene)
    vl = bpy.context.view_layer
    vl.lightgroups.add(name="key")
    vl.lightgroups.add(name="sky")
    lamp = scenes.light('POINT', 100.0, (0, 0, 3), name="Key")
    lamp.lightgroup = "key"
    glow = scenes.plane("Glow", materials=[scenes.emission("Glow", (1, 1, 1), 2.0)])
    glow.lightgroup = "key"
    scenes.world((0.1, 0.1, 0.1), 1.0)
    scene.world.lightgroup = "sky"
    s = exported()
    assert s.settings.lightgroups == ("key", "sky") and s.world_lightgroup == "sky"
    assert [l.lightgroup for l in s.lights if l.name == "Key"] == ["key"]
    assert s.object_lightgroups[s.object_names.index("Glow")] == "key"
    assert not any("light group" in m for _, m in s.messages)


def test_instances_take_their_instancers_light_group(scene, exported):
    """An instanced light or emitter without a light group of its own is in its instancer's
    (Cycles' sync); instances of one object under instancers of two groups are in both. Both
    had stayed in no group (Cycles: Combined_Key 0.329 = Combined, DACRT 0.0)."""
    setup(scene)
    vl = bpy.context.view_layer
    vl.lightgroups.add(name="key")
    vl.lightgroups.add(name="own")
    props = bpy.data.collections.new("Props")          # not linked to the scene: instanced only
    lamp = scenes.light('POINT', 100.0, (0, 0, 3), name="Bulb")
    panel = scenes.plane("Panel", materials=[scenes.emission("Glow", (1, 1, 1), 2.0)])
    tagged = scenes.plane("Tagged", location=(3, 0, 0), materials=[scenes.emission("Glow2", (1, 1, 1), 2.0)])
    tagged.lightgroup = "own"                           # its own group wins
    for ob in (lamp, panel, tagged):
        for c in list(ob.users_collection):
            c.objects.unlink(ob)
        props.objects.link(ob)
    for i, group in enumerate(("key", "")):
        empty = bpy.data.objects.new(f"Instancer{i}", None)
        empty.instance_type, empty.instance_collection = 'COLLECTION', props
        empty.location = (0, 10 * i, 0)
        empty.lightgroup = group
        scene.collection.objects.link(empty)
    s = exported()
    assert sorted(l.lightgroup for l in s.lights if l.name == "Bulb") == ["", "key"]
    groups = sorted(g for n, g in zip(s.object_names, s.object_lightgroups) if n == "Panel")
    assert groups == ["", "key"]
    assert [g for n, g in zip(s.object_names, s.object_lightgroups) if n == "Tagged"] == ["own"]
    # each instance's triangles point at the entry of its own group (instancer 0 at y = 0)
    geo = s.geometry
    y = geo.vertices[geo.triangles][:, :, 1].mean(axis=1)
    names = np.array(s.object_names)[geo.object_index]
    groups = np.array(s.object_lightgroups)[geo.object_index]
    panel = names == "Panel"
    assert panel.sum() == 4 and set(groups[panel & (y < 5)]) == {"key"} and set(groups[panel & (y > 5)]) == {""}


def test_shader_aovs_exported(scene, exported):
    """The view layer's AOVs (name, type) and what each material's AOV Output nodes write:
    constants, through a Math node and a node group, nodes of one name adding up, an image
    (as a texture); the world's AOV Output nodes."""
    setup(scene)
    vl = bpy.context.view_layer
    a, b = vl.aovs.add(), vl.aovs.add()
    a.name, a.type, b.name, b.type = "tint", 'COLOR', "mask", 'VALUE'
    mat = scenes.diffuse("Tagged", (0.5, 0.5, 0.5))
    nt = mat.node_tree
    out = nt.nodes.new('ShaderNodeOutputAOV')
    out.aov_name = "tint"
    out.inputs['Color'].default_value = (0.1, 0.2, 0.3, 1.0)
    math = nt.nodes.new('ShaderNodeMath')
    math.operation, math.inputs[0].default_value, math.inputs[1].default_value = 'ADD', 0.25, 0.5
    nt.links.new(math.outputs[0], out.inputs['Value'])
    group = bpy.data.node_groups.new("AOVGroup", 'ShaderNodeTree')
    inner = group.nodes.new('ShaderNodeOutputAOV')
    inner.aov_name, inner.inputs['Value'].default_value = "mask", 0.5
    nt.nodes.new('ShaderNodeGroup').node_tree = group
    twice = nt.nodes.new('ShaderNodeOutputAOV')
    twice.aov_name, twice.inputs['Value'].default_value = "mask", 0.25
    imaged = scenes.diffuse("Imaged", (0.5, 0.5, 0.5))
    node = imaged.node_tree.nodes.new('ShaderNodeOutputAOV')
    node.aov_name = "tint"
    tex = imaged.node_tree.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("AOVImage", np.full((2, 2, 4), 0.5, np.float32))
    imaged.node_tree.links.new(tex.outputs['Color'], node.inputs['Color'])
    scenes.plane("A", materials=[mat])
    scenes.plane("B", location=(3, 0, 0), materials=[imaged])
    scenes.world((0.1, 0.1, 0.1), 1.0)
    sky = scene.world.node_tree.nodes.new('ShaderNodeOutputAOV')
    sky.aov_name, sky.inputs['Value'].default_value = "mask", 0.125
    s = exported()
    assert s.settings.aovs == (("tint", 'COLOR'), ("mask", 'VALUE'))
    table = {m.name: m for m in s.materials}
    color, value = table["Tagged"].aovs["tint"]
    assert np.allclose(color, (0.1, 0.2, 0.3)) and value == pytest.approx(0.75)
    assert table["Tagged"].aovs["mask"][1] == pytest.approx(0.75) and not table["Tagged"].approximated
    assert not table["Imaged"].approximated and "tint" in table["Imaged"].aovs
    texels, interp, ext, _ = table["Imaged"].aov_textures["tint", 'color']
    assert np.allclose(texels[..., :3], 0.5) and interp == 'Linear' and ext == 'REPEAT'
    assert ("tint", 'value') not in table["Imaged"].aov_textures
    assert s.world_aovs["mask"][1] == pytest.approx(0.125) and "tint" not in s.world_aovs


def test_emission_sampling_follows_cycles(scene, exported):
    """Each material's Emission Sampling as Cycles resolves it (scene/shader.cpp): the setting,
    or for Auto the shader's emission estimate (colour x strength; a linked colour counts 1, a
    colour plugged into Surface 0.1; Add sums, Mix mixes by a constant factor and sums by a
    linked one) above 0.5 in some channel: both sides, else none."""
    setup(scene)
    made = {}

    def emitter(name, color=(1.0, 1.0, 1.0), strength=1.0, method='AUTO'):
        made[name] = mat = scenes.emission(name, color, strength)
        mat.cycles.emission_sampling = method
        return mat

    emitter("Bright")
    emitter("Dim", strength=0.3)
    emitter("DarkColour", color=(0.2, 0.1, 0.1), strength=3.0)              # 0.6 in red
    emitter("Forced", strength=0.3, method='FRONT_BACK')
    emitter("Front", method='FRONT')
    emitter("Off", strength=50.0, method='NONE')
    made["PrincipledDim"] = scenes.principled("PrincipledDim", (0.5, 0.5, 0.5), (1.0, 1.0, 1.0), 0.4)
    made["PrincipledBright"] = scenes.principled("PrincipledBright", (0.5, 0.5, 0.5), (1.0, 0.5, 0.5), 2.0)
    for name, strength in (("ImageDim", 0.4), ("ImageBright", 0.6)):     # a linked colour counts 1
        mat = emitter(name, strength=strength)
        img = bpy.data.images.new(name + "Texels", 2, 2)
        img.pixels = [0.1, 0.1, 0.1, 1.0] * 4
        tex = mat.node_tree.nodes.new('ShaderNodeTexImage')
        tex.image = img
        mat.node_tree.links.new(tex.outputs['Color'], mat.node_tree.nodes['Emission'].inputs['Color'])
    for name, fac, linked in (("MixHalf", 0.5, False), ("MixLinked", 0.5, True)):
        mat, nt, mix, e, d = scenes.mix_shader_material(name, 'ShaderNodeEmission', 'ShaderNodeBsdfDiffuse', fac)
        e.inputs['Strength'].default_value = 0.8                    # 0.4 mixed in, 0.8 summed
        if linked:
            nt.links.new(nt.nodes.new('ShaderNodeValue').outputs[0], mix.inputs['Fac'])
        made[name] = mat
    mat, nt, out = scenes._material("ColourToSurface")               # Cycles' auto-converted emission
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (4.0, 4.0, 4.0, 1.0)
    nt.links.new(rgb.outputs[0], out.inputs['Surface'])
    made["ColourToSurface"] = mat
    for i, (name, mat) in enumerate(made.items()):
        scenes.plane(name + "Plane", location=(3.0 * i, 0, 0), materials=[mat])
    table = {m.name: m.emission_sampling for m in exported().materials if m.name in made}
    both, none = 'FRONT_BACK', 'NONE'
    assert table == {"Bright": both, "Dim": none, "DarkColour": both, "Forced": both, "Front": 'FRONT',
                     "Off": none, "PrincipledDim": none, "PrincipledBright": both, "ImageDim": none,
                     "ImageBright": both, "MixHalf": none, "MixLinked": both, "ColourToSurface": none}, table


def test_normal_map_material_and_object_tangents(scene, exported):
    """A BSDF's Normal fed by a tangent-space Normal Map node of an image: the material carries
    the image and the strength, and its triangles get Blender's object-space mikktspace tangents
    and bitangent signs (as Cycles keeps them) with the object's linear map (tangent_xf), a
    mirroring one included; other triangles keep zeros; a bump node is a bump per point
    (export/bump.py), no tangents."""
    setup(scene)
    img = bpy.data.images.new("Normals", 2, 2)
    img.colorspace_settings.name = 'Non-Color'
    mat = scenes.normal_map_material("Mapped", img, 0.7)
    bumped, bnt, bout = scenes._material("Bumped")
    bd = bnt.nodes.new('ShaderNodeBsdfDiffuse')
    bump = bnt.nodes.new('ShaderNodeBump')
    bnt.links.new(bnt.nodes.new('ShaderNodeTexNoise').outputs['Fac'], bump.inputs['Height'])
    bnt.links.new(bump.outputs['Normal'], bd.inputs['Normal'])
    bnt.links.new(bd.outputs[0], bout.inputs['Surface'])
    for name, x, sx in (("Plain", 0.0, 1.0), ("Mirrored", 3.0, -1.0)):
        bpy.ops.mesh.primitive_plane_add(size=2.0, location=(x, 0, 0), rotation=(0, 0, math.pi / 2))
        ob = bpy.context.active_object
        ob.name, ob.scale.x = name, sx
        ob.data.materials.append(mat)
    scenes.plane("Other", location=(6, 0, 0), materials=(bumped,))
    data = exported()
    table = {m.name: m for m in data.materials}
    assert table["Mapped"].normal_texture is not None and table["Mapped"].normal_strength == pytest.approx(0.7)
    assert not table["Mapped"].approximated
    assert len(table["Bumped"].bumps) == 1 and not table["Bumped"].approximated
    g = data.geometry
    plain, mirrored, other = (g.tangents[of_object(data, n)] for n in ("Plain", "Mirrored", "Other"))
    # the plane's UV u runs along its local +x, in object space for both
    np.testing.assert_allclose(plain[..., :3], np.broadcast_to([1.0, 0.0, 0.0], plain[..., :3].shape), atol=1e-6)
    np.testing.assert_allclose(mirrored[..., :3], plain[..., :3], atol=1e-6)
    assert np.all(plain[..., 3] == 1.0) and np.all(mirrored[..., 3] == 1.0)
    assert not other.any()
    # the objects' linear maps: a quarter turn about z, after mirroring x for the second
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    xf_plain, xf_mirrored = (g.tangent_xf[g.instance[of_object(data, n)]] for n in ("Plain", "Mirrored"))
    np.testing.assert_allclose(xf_plain, np.broadcast_to(turn, xf_plain.shape), atol=1e-6)
    np.testing.assert_allclose(xf_mirrored, np.broadcast_to(turn @ np.diag([-1.0, 1.0, 1.0]), xf_mirrored.shape),
                               atol=1e-6)


# -- view layer overrides and filters (as Cycles syncs them) ---------------------------------

def test_view_layer_world_override_samples_and_filters(scene, exported):
    setup(scene)
    scenes.cube("Cube")
    scenes.world((0.5, 0.25, 1.0), 2.0)
    green = bpy.data.worlds.new("Green")
    next(n for n in green.node_tree.nodes if n.type == 'BACKGROUND').inputs['Color'].default_value = (0, 1, 0, 1)
    vl = scene.view_layers[0]
    scene.dacrt.samples = 64
    data = exported()
    assert np.allclose(data.world, (1.0, 0.5, 2.0)) and data.settings.samples == 64
    assert len(data.geometry.triangles) == 12
    scene.dacrt.film_exposure = 1.5
    assert exported().settings.film_exposure == 1.5
    assert scene.dacrt.use_light_tree and exported().settings.use_light_tree      # on, as Cycles'
    scene.dacrt.use_light_tree = False
    assert not exported().settings.use_light_tree
    scene.world.mist_settings.start, scene.world.mist_settings.depth = 1.0, 20.0
    green.mist_settings.start, green.mist_settings.depth = 4.0, 5.0
    vl.world_override = green                 # the layer's world, lights and background alike
    vl.samples = 3                            # Cycles' default 'Use' layer samples: overrides
    data = exported()
    assert np.allclose(data.world, (0.0, 1.0, 0.0)) and data.settings.samples == 3
    assert data.settings.mist[:2] == (1.0, 20.0)      # but Cycles' mist stays the scene world's
    scene.cycles.use_layer_samples = 'IGNORE'         # Cycles then renders the scene's samples
    assert exported().settings.samples == 64
    scene.cycles.use_layer_samples = 'BOUNDED'        # ... or the layer's, at most the scene's
    assert exported().settings.samples == 3
    vl.samples = 100
    assert exported().settings.samples == 64
    scene.cycles.use_layer_samples, vl.samples = 'USE', 3
    vl.use_sky = False                        # Environment filter off: no world at all
    assert np.allclose(exported().world, 0.0)
    vl.use_sky, vl.samples = True, 0
    vl.use_solid = False                      # Surfaces filter off: no mesh is synced
    data = exported()
    assert len(data.geometry.triangles) == 0 and data.settings.samples == 64
    assert any("surfaces are off in the view layer's filter" in text for _, text in data.messages)


def test_camera_override_renders_through_that_camera(scene):
    """RenderEngine.camera_override (a sequencer strip's camera) replaces the scene camera."""
    main = scenes.camera((0, -10, 0), (math.pi / 2, 0, 0), name="Main")
    other = scenes.camera((0, 0, 8), (0, 0, 0), lens=35.0, name="Other")
    scene.camera = main
    depsgraph = bpy.context.evaluated_depsgraph_get()
    scenes.cube("Cube")
    default = export.export_camera(scene)
    chosen = export.export_camera(scene, camera=other)
    assert np.allclose(default.matrix, np.array(main.matrix_world))
    assert np.allclose(chosen.matrix, np.array(other.matrix_world))
    assert not np.allclose(chosen.tan_half_fov, default.tan_half_fov)
    data = export.export_scene(depsgraph, camera=other)
    assert np.allclose(data.camera.matrix, np.array(other.matrix_world))


def test_a_volume_made_by_geometry_nodes_is_reported_as_that(scene, exported):
    """Geometry Nodes joining an object's mesh with a Mesh to Volume: the mesh renders and the
    message says the volume part is left out (it had said the object was skipped); a volume
    object of its own is skipped as such."""
    setup(scene)
    ob = scenes.mesh("Cube", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [(0, 1, 2, 3)])
    ng = bpy.data.node_groups.new("Vol", 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gin, gout = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    to_volume, join = ng.nodes.new('GeometryNodeMeshToVolume'), ng.nodes.new('GeometryNodeJoinGeometry')
    ng.links.new(gin.outputs[0], to_volume.inputs[0])
    ng.links.new(gin.outputs[0], join.inputs[0])
    ng.links.new(to_volume.outputs[0], join.inputs[0])
    ng.links.new(join.outputs[0], gout.inputs[0])
    ob.modifiers.new("GN", 'NODES').node_group = ng
    scenes.link(bpy.data.objects.new("Fog", bpy.data.volumes.new("Fog")))
    data = exported()
    text = " | ".join(t for _, t in data.messages)
    assert of_object(data, "Cube").sum() == 2
    assert "'Cube': volume geometry its Geometry Nodes make is not rendered (the rest of the object is)" in text
    assert "'Fog': volume objects are not rendered" in text


def test_volume_only_material_has_a_clear_surface(scene, exported):
    """Cycles: a material with only a Volume output (a fog box) has a surface every ray passes
    (SD_HAS_ONLY_VOLUME); with neither output linked it is black. The volume is reported."""
    setup(scene)
    fog, nt, out = _shader_material("Fog")
    vol = nt.nodes.new('ShaderNodeVolumePrincipled')
    nt.links.new(vol.outputs[0], out.inputs['Volume'])
    black, _, _ = _shader_material("Nothing")
    scenes.cube("Box", materials=(fog,))
    scenes.cube("Other", location=(3, 0, 0), materials=(black,))
    table = {m.name: m for m in exported().materials}
    assert np.allclose(table["Fog"].transparency, 1.0) and np.allclose(table["Fog"].base_color, 0.0)
    assert table["Fog"].visibility == 0      # no ray sees it (its faces are dropped: test_volume_clear)
    assert "volume ignored" in table["Fog"].approximated
    assert table["Nothing"].transparency is None and np.allclose(table["Nothing"].base_color, 0.0)


def test_normal_setups_that_leave_the_normal_are_not_approximations(scene, exported):
    """A Bump without a height or of strength 0, a Normal Map of its default flat colour or of
    strength 0, Geometry > Normal: Cycles shades with the normal as it is, so these are exact;
    a Bump driven by a texture is still reported."""
    setup(scene)

    def bsdf_normal(name, build):
        mat = scenes.diffuse(name, (0.5, 0.4, 0.3))
        nt = mat.node_tree
        bsdf = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
        nt.links.new(build(nt), bsdf.inputs['Normal'])
        return mat

    def bump(nt, strength=1.0, height=False):
        b = nt.nodes.new('ShaderNodeBump')
        b.inputs['Strength'].default_value = strength
        if height:
            nt.links.new(nt.nodes.new('ShaderNodeTexNoise').outputs['Fac'], b.inputs['Height'])
        return b.outputs['Normal']

    def normal_map(nt, strength=1.0):
        m = nt.nodes.new('ShaderNodeNormalMap')
        m.inputs['Strength'].default_value = strength
        return m.outputs['Normal']

    exact = {
        "BumpNoHeight": lambda nt: bump(nt),
        "BumpZero": lambda nt: bump(nt, 0.0, height=True),
        "FlatMap": lambda nt: normal_map(nt),
        "GeometryNormal": lambda nt: nt.nodes.new('ShaderNodeNewGeometry').outputs['Normal'],
    }
    for i, (name, build) in enumerate(exact.items()):
        scenes.plane(name, location=(3 * i, 0, 0), materials=(bsdf_normal(name, build),))
    scenes.plane("Bumpy", location=(-3, 0, 0), materials=(bsdf_normal("Bumpy", lambda nt: bump(nt, height=True)),))

    def object_map(nt):                       # its default colour is a fixed direction there
        out = normal_map(nt)
        out.node.space = 'OBJECT'
        return out
    scenes.plane("ObjectMap", location=(-6, 0, 0), materials=(bsdf_normal("ObjectMap", object_map),))
    table = {m.name: m for m in exported().materials}
    for name in exact:
        assert table[name].approximated == '', (name, table[name].approximated)
    assert len(table["Bumpy"].bumps) == 1 and table["Bumpy"].approximated == ''    # (tests/parity/test_bump.py)
    # (rendered: tests/parity/test_normal_map_spaces.py)
    assert table["ObjectMap"].approximated == '' and table["ObjectMap"].normal_space == 'OBJECT'
    assert table["ObjectMap"].normal_texture is not None


def test_colour_nodes_after_an_8bit_image(scene, exported, tmp_path):
    """After an image Cycles blends encoded (8-bit sRGB), an affine chain (a Mix Multiply tint)
    stays weight x lookup (the image itself, looked up as stored); a non-affine one (Gamma) runs
    after the image's lookup as stored (EncodedTexels.then), as Cycles runs it after the blend:
    exact, not reported."""
    setup(scene)
    px = (np.arange(4 * 4 * 3).reshape(4, 4, 3) * 5).astype(np.uint8)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "bytes.png", px))
    for i, kind in enumerate(("Tint", "Gamma")):
        mat = scenes.diffuse(kind, (1, 1, 1))
        nt = mat.node_tree
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = img
        if kind == "Tint":
            out = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], (0.5, 0.25, 1.0), 1.0).outputs['Result']
        else:
            g = nt.nodes.new('ShaderNodeGamma')
            g.inputs['Gamma'].default_value = 2.0
            nt.links.new(tex.outputs['Color'], g.inputs['Color'])
            out = g.outputs['Color']
        nt.links.new(out, next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE').inputs['Color'])
        scenes.plane(kind, location=(3 * i, 0, 0), materials=(mat,))
    table = {m.name: m for m in exported().materials}
    tint, gamma = table["Tint"], table["Gamma"]
    assert tint.approximated == '' and np.allclose(tint.base_color, (0.5, 0.25, 1.0))
    assert stored_texels(tint.texture) is not None              # the image as Cycles stores it
    assert gamma.approximated == ''
    stored = stored_texels(gamma.texture)
    assert stored is not None and stored.then is not None
    u = np.array([0.25], np.float32)        # halfway between texels (0, 0) and (1, 0) of row 0
    v = np.array([0.125], np.float32)
    want = srgb_to_linear((px[0, 0] / 255.0 + px[0, 1] / 255.0) / 2) ** 2
    assert np.allclose(stored.lookup(u, v, 'Linear', 'REPEAT')[:, 0], want, rtol=1e-5, atol=1e-7)


def _attribute_material(name, node_type='ShaderNodeVertexColor', attribute='Col', chain=None):
    mat, nt, out = _shader_material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    node = nt.nodes.new(node_type)
    if node_type == 'ShaderNodeVertexColor':
        node.layer_name = attribute
    else:
        node.attribute_name = attribute
    s = node.outputs['Color']
    if chain is not None:
        s = chain(nt, s)
    nt.links.new(s, d.inputs['Color'])
    return mat


def test_attribute_factor_is_the_colours_average(scene, exported):
    """An Attribute node's Factor output (so named since Blender 4; identifier Fac) is the
    colour's average, as Cycles' svm_node_attr, not its first channel: on a quad of one colour
    per point, every corner's albedo is its point's mean."""
    setup(scene)
    mat, nt, out = _shader_material("Factor")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    attr = nt.nodes.new('ShaderNodeAttribute')
    attr.attribute_name = 'Col'
    nt.links.new(attr.outputs['Factor'], d.inputs['Color'])
    ob = scenes.mesh("Quad", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [(0, 1, 2, 3)], materials=(mat,))
    values = np.array([[0.9, 0.1, 0.2, 1], [0.1, 0.8, 0.3, 1], [0.2, 0.3, 0.9, 1], [0.7, 0.7, 0.1, 1]], np.float32)
    ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT').data.foreach_set('color', values.ravel())
    data = exported()
    g = data.geometry
    corners = np.asarray(g.triangles)[of_object(data, "Quad")]
    means = values[:, :3].mean(axis=1)
    np.testing.assert_allclose(g.colors[of_object(data, "Quad")], np.repeat(means[corners][..., None], 3, -1),
                               atol=1e-6)


def test_a_tint_of_byte_corner_colours_is_applied_per_point(scene, exported):
    """A tint (1, 0.5, 0.8) of a byte corner attribute is a scale of its colour: applied per
    point, nothing reported (float32 rounding had left its fitted offset a few 1e-9 below 0,
    and the tint was evaluated at the corners with a note)."""
    setup(scene)
    ob = scenes.mesh("Tinted", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [(0, 1, 2, 3)],
                     materials=(_attribute_material("MTint", chain=lambda nt, s: scenes.mix_node(
                         nt, 'MULTIPLY', s, (1.0, 0.5, 0.8), 1.0).outputs['Result']),))
    attr = ob.data.color_attributes.new('Col', 'BYTE_COLOR', 'CORNER')
    attr.data.foreach_set('color', np.random.default_rng(5).random(len(attr.data) * 4).astype(np.float32))
    m = {m.name: m for m in exported().materials}["MTint"]
    assert m.color_attribute == color_attribute_key('Col') and m.approximated == '', m.approximated


def test_curves_attributes_are_read_per_point_and_per_curve(scene, exported):
    """An Attribute node on a Curves object reads its point attributes (between a segment's
    keys linearly, as Cycles' curve keys) and its curve attributes (the curve's); they had read
    0 under a message saying Cycles does the same (Cycles: red and green halves)."""
    setup(scene)
    z = np.linspace(0, 1, 3)[:, None] * (0, 0, 1)
    mats = [_attribute_material(f"M{n}", 'ShaderNodeAttribute', attribute=n) for n in ("PCol", "CCol")]
    fur = scenes.hair_curves("Fur", [z, z + (1, 0, 0)], radius=0.05, material=mats[0])
    pattr = fur.data.attributes.new('PCol', 'FLOAT_COLOR', 'POINT')
    pvals = np.array([[1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1]] * 2, np.float32)
    pattr.data.foreach_set('color', pvals.ravel())
    tuft = scenes.hair_curves("Tuft", [z + (3, 0, 0), z + (4, 0, 0)], radius=0.05, material=mats[1])
    cattr = tuft.data.attributes.new('CCol', 'FLOAT_COLOR', 'CURVE')
    cattr.data.foreach_set('color', np.array([[1, 0, 0, 1], [0, 1, 0, 1]], np.float32).ravel())
    data = exported()
    g = data.geometry
    assert not any("no attribute" in t for _, t in data.messages)
    P = g.vertices[g.triangles]                       # (nt, 3, 3) corners
    fur_t = of_object(data, "Fur")
    c, p = g.colors[fur_t][..., :3].reshape(-1, 3), P[fur_t].reshape(-1, 3)
    height = p[:, 2]
    # red at the root, green at the middle key, blue at the tip; in between the blend
    want = np.where(height[:, None] <= 0.5,
                    np.outer(1 - 2 * height, [1, 0, 0]) + np.outer(2 * height, [0, 1, 0]),
                    np.outer(2 - 2 * height, [0, 1, 0]) + np.outer(2 * height - 1, [0, 0, 1]))
    assert np.abs(c - want).max() < 0.35       # Catmull-Rom samples sit near, not on, the keys' heights
    assert np.allclose(c[height < 0.01], [1, 0, 0], atol=1e-5) and np.allclose(c[height > 0.99], [0, 0, 1], atol=1e-5)
    tuft_t = of_object(data, "Tuft")
    x = P[tuft_t][..., 0].mean(axis=1)
    assert np.allclose(g.colors[tuft_t][x < 3.5][..., :3], [1, 0, 0]) and np.allclose(g.colors[tuft_t][x > 3.5][..., :3], [0, 1, 0])
    # a point cloud (Mesh to Points carries the mesh's point attribute): each sphere its point's
    dots = scenes.point_cloud("Dots", np.array([[0, 5, 0], [2, 5, 0]]), radius=0.1,
                              material=_attribute_material("MDots", 'ShaderNodeAttribute', attribute="DCol"))
    dattr = dots.data.attributes.new('DCol', 'FLOAT_COLOR', 'POINT')
    dattr.data.foreach_set('color', np.array([[0.2, 0.4, 0.6, 1], [0.9, 0.1, 0.3, 1]], np.float32).ravel())
    data = exported()
    g = data.geometry
    sel = np.isin(g.material, [i for i, m in enumerate(data.materials) if m.name == "MDots"])
    x = g.vertices[g.triangles[sel]][..., 0].mean(axis=1)
    assert sel.sum() > 0 and not any("no attribute" in t for _, t in data.messages)
    assert np.allclose(g.colors[sel][x < 1][..., :3], [0.2, 0.4, 0.6]) and np.allclose(g.colors[sel][x > 1][..., :3], [0.9, 0.1, 0.3])


def test_an_instancer_attribute_of_an_object_of_its_own_reads_its_property(scene, exported):
    """An Attribute node of type Instancer on an object that is no instance reads the object's
    own property, as Cycles (it had been reported 'not read'; Geometry Nodes instances:
    tests/addon/test_instancer_attributes.py)."""
    setup(scene)
    mat = _attribute_material("MInst", 'ShaderNodeAttribute', attribute='col')
    next(n for n in mat.node_tree.nodes if n.type == 'ATTRIBUTE').attribute_type = 'INSTANCER'
    scenes.plane("P", materials=(mat,))['col'] = (0.7, 0.3, 0.1)
    data = exported()
    m = {m.name: m for m in data.materials}["MInst"]
    assert "not read" not in m.approximated, m.approximated
    assert np.allclose(data.geometry.colors[of_object(data, "P")][..., :3], (0.7, 0.3, 0.1), atol=1e-6)


def test_colour_attributes_per_corner(scene, exported):
    """A Color Attribute (or Attribute) node into the diffuse colour: the material is marked
    with the attribute, Geometry.colors holds w x the attribute + k per triangle corner (point,
    corner and face domains, as Cycles reads them; 0 where the mesh lacks it, as Cycles), 1 on
    other triangles. A chain that is not a scale and offset of the colour (Gamma) is evaluated
    on the corners' values and interpolated, reported."""
    setup(scene)
    quad = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    made = {}
    for i, (domain, kind) in enumerate((('POINT', 'FLOAT_COLOR'), ('CORNER', 'BYTE_COLOR'), ('FACE', 'FLOAT_COLOR'))):
        ob = scenes.mesh(domain, quad, [(0, 1, 2, 3)], location=(3 * i, 0, 0),
                         materials=(_attribute_material(f"M{domain}", chain=lambda nt, s: scenes.mix_node(
                             nt, 'MULTIPLY', s, (0.5, 1.0, 2.0), 1.0).outputs['Result']),))
        attr = ob.data.color_attributes.new('Col', kind, domain)
        values = np.linspace(0.1, 0.9, len(attr.data) * 4).reshape(-1, 4).astype(np.float32)
        values[:, 3] = 1.0
        attr.data.foreach_set('color', values.ravel())
        back = np.empty(len(attr.data) * 4, np.float32)
        attr.data.foreach_get('color', back)          # (bytes round the values)
        made[domain] = back.reshape(-1, 4)[:, :3]
    mirror = scenes.mesh("Mirror", quad, [(0, 1, 2, 3)], location=(-3, 0, 0), materials=(_attribute_material("MMirror"),))
    mirror.scale.x = -1.0                     # rewound triangles: the colours follow their corners
    mattr = mirror.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    mvalues = np.random.default_rng(1).random((4, 4)).astype(np.float32)
    mattr.data.foreach_set('color', mvalues.ravel())
    scenes.mesh("Bare", quad, [(0, 1, 2, 3)], location=(9, 0, 0), materials=(_attribute_material("MBare"),))
    scenes.mesh("Plain", quad, [(0, 1, 2, 3)], location=(12, 0, 0), materials=(scenes.diffuse("P", (0.5, 0.5, 0.5)),))
    gamma = scenes.mesh("Gamma", quad, [(0, 1, 2, 3)], location=(15, 0, 0), materials=(_attribute_material(
        "MGamma", 'ShaderNodeAttribute', chain=lambda nt, s: _gamma(nt, s)),))
    gattr = gamma.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    gvalues = np.random.default_rng(2).random((4, 4)).astype(np.float32)
    gattr.data.foreach_set('color', gvalues.ravel())
    data = exported()
    table = {m.name: m for m in data.materials}
    g = data.geometry
    tint = np.array([0.5, 1.0, 2.0])
    for domain, values in made.items():
        m = table[f"M{domain}"]
        assert m.color_attribute == color_attribute_key('Col') and m.texture is None and m.approximated == '', m.approximated
        assert np.allclose(m.base_color, 1.0)
        tris = np.asarray(data.geometry.triangles)[of_object(data, domain)]
        colors = g.colors[of_object(data, domain)]
        if domain == 'POINT':
            want = values[tris - tris.min()] * tint
        elif domain == 'FACE':
            want = np.broadcast_to(values[0] * tint, colors.shape)
        else:                                 # corners: the face's loops in the triangles' order
            want = None
            gap = np.abs(colors.reshape(-1, 1, 3) - (values * tint)[None]).max(axis=2).min(axis=1)
            assert gap.max() < 1e-6, gap                   # every corner is one of the face's loops
        if want is not None:
            assert np.allclose(colors, want, atol=1e-6), domain
    mtris = np.asarray(g.triangles)[of_object(data, "Mirror")]
    assert np.allclose(g.colors[of_object(data, "Mirror")], mvalues[mtris - mtris.min(), :3], atol=1e-6)
    assert np.allclose(g.colors[of_object(data, "Bare")], 0.0)          # Cycles: a missing attribute is 0
    assert any("'Bare'" in t and "no attribute 'Col' on the mesh" in t for _, t in data.messages)
    assert np.allclose(g.colors[of_object(data, "Plain")], 1.0)
    # any other chain: computed per point on the interpolated attribute, as Cycles (it had been
    # evaluated on the corners' values, then interpolated, said; tests/parity/test_attribute_chains_per_point.py)
    assert table["MGamma"].color_attribute is None and table["MGamma"].approximated == ''
    assert isinstance(table["MGamma"].texture, ProceduralTexels)


def _gamma(nt, socket):
    node = nt.nodes.new('ShaderNodeGamma')
    node.inputs['Gamma'].default_value = 2.0
    nt.links.new(socket, node.inputs['Color'])
    return node.outputs['Color']


def test_adaptive_subdivision_is_reported(scene, exported):
    """Cycles dices an adaptive Subdivision modifier by its dicing rate; DACRT renders the
    modifier's Render Levels, and says so (it was silent: a tester's cube at Render Levels 0
    rendered as its 12 raw triangles, 25% off Cycles' rounded shape)."""
    setup(scene)
    ob = scenes.cube("Smooth")
    mod = ob.modifiers.new("Subdivision", 'SUBSURF')
    mod.levels = mod.render_levels = 1
    data = exported()
    assert not any("adaptive" in t for _, t in data.messages)
    mod.use_adaptive_subdivision = True
    data = exported()
    assert any("'Smooth'" in t and "adaptive subdivision is not rendered" in t and "Render Levels (1)" in t
               for _, t in data.messages)
    # under Simplify > Max Subdivision the levels rendered are capped, and said so (it named the
    # modifier's 3 where 1 was rendered)
    mod.render_levels = 3
    scene.render.use_simplify, scene.render.simplify_subdivision_render = True, 1
    data = exported()
    assert len(data.geometry.triangles) == 48
    assert any("Render Levels (1)" in t for _, t in data.messages), data.messages


def test_object_random_is_cycles(scene):
    """Object Info Random as Cycles computes it, values read from Cycles renders: objects of
    their own hash their names, instances divide their random_id."""
    assert [round(export.objectinfo.object_random(n, 0, False), 7) for n in ("P0", "P1", "P2")] == \
        [0.3344228, 0.644282, 0.5273009]
    assert export.objectinfo.object_random("Any", 360212060, True) == pytest.approx(0.08386841, abs=1e-7)
    assert 0.0 <= export.objectinfo.object_random("Ünïcode", 0, False) < 1.0


def test_colour_attribute_beside_an_image_or_past_a_clamp(scene, exported, tmp_path):
    """A colour attribute added to an image (a sum is not the image times colours per point)
    reads its node's own value, reported, not the mean of the values the build probes with; a clamp
    after an attribute (float colours go past 1) is no scale and offset: the chain is evaluated
    at the corners, so a colour of 4 x 0.5 clamps to 1 as in Cycles."""
    setup(scene)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "red.png", np.full((2, 2, 3), (204, 25, 25), np.uint8)))

    def plus_image(nt, s):
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = img
        return scenes.mix_node(nt, 'ADD', tex.outputs['Color'], s, 1.0).outputs['Result']

    def clamped_half(nt, s):
        mix = scenes.mix_node(nt, 'MULTIPLY', s, (0.5, 0.5, 0.5), 1.0)
        mix.clamp_result = True
        return mix.outputs['Result']
    quad = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    for i, (name, chain) in enumerate((("Imaged", plus_image), ("Clamped", clamped_half))):
        ob = scenes.mesh(name, quad, [(0, 1, 2, 3)], location=(3 * i, 0, 0),
                         materials=(_attribute_material(name, chain=chain),))
        attr = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
        attr.data.foreach_set('color', np.tile([4.0, 4.0, 0.5, 1.0], 4).astype(np.float32))
    data = exported()
    table = {m.name: m for m in data.materials}
    assert table["Imaged"].color_attribute is None
    assert "colour from 'Color Attribute' node; its own value used" in table["Imaged"].approximated
    # (computed per point, clamped after the interpolation as in Cycles)
    assert table["Clamped"].color_attribute is None and table["Clamped"].approximated == ''
    assert isinstance(table["Clamped"].texture, ProceduralTexels)


def test_object_info_indices_per_object(scene, exported):
    """Object Info's Object Index (the object's pass index) and Material Index (the material's)
    into a colour, through a Math node: one albedo per object, as Cycles reads them."""
    setup(scene)
    mat, nt, out = _shader_material("Indexed")
    mat.pass_index = 5
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    info = nt.nodes.new('ShaderNodeObjectInfo')
    add = nt.nodes.new('ShaderNodeMath')
    add.operation = 'MULTIPLY_ADD'                    # object index x 0.1 + material index x ...
    add.inputs[1].default_value = 0.1
    nt.links.new(info.outputs['Object Index'], add.inputs[0])
    mix = scenes.mix_node(nt, 'ADD', (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 1.0)
    nt.links.new(add.outputs[0], next(s for s in mix.inputs if s.identifier == 'A_Color'))
    nt.links.new(info.outputs['Material Index'], add.inputs[2])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    for i, index in enumerate((3, 7)):
        scenes.plane(f"P{index}", location=(3 * i, 0, 0), materials=(mat,)).pass_index = index
    data = exported()
    for index in (3, 7):
        assert np.allclose(data.geometry.colors[of_object(data, f"P{index}")], 0.1 * index + 5.0), index


def _object_value_material(name, output, attribute=None):
    """A diffuse material coloured by an Object Info output, or (output None) by an Attribute
    node of type Object reading `attribute`."""
    mat, nt, out = _shader_material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    if output:
        src = nt.nodes.new('ShaderNodeObjectInfo').outputs[output]
    else:
        attr = nt.nodes.new('ShaderNodeAttribute')
        attr.attribute_type, attr.attribute_name = 'OBJECT', attribute
        src = attr.outputs['Color']
    nt.links.new(src, d.inputs['Color'])
    return mat


def test_object_info_reads_the_rendered_frame_in_an_animation_render(scene, exported, tmp_path):
    """An animation render (Ctrl-F12, `blender -a`, `-f N`) does not write animated values back
    to the original objects: Object Info's Color and an Object attribute are read from the
    depsgraph's evaluated object, at the frame rendered (they stayed at the file's frame)."""
    setup(scene)
    made = [_object_value_material("Info", 'Color'), _object_value_material("Attr", None, 'tint')]
    info = scenes.plane("Info", materials=(made[0],))
    attr = scenes.plane("Attr", location=(3, 0, 0), materials=(made[1],))
    for frame, rgb in ((1, (0.1, 0.8, 0.1)), (4, (0.9, 0.1, 0.9))):
        info.color = (*rgb, 1.0)
        info.keyframe_insert('color', frame=frame)
        attr['tint'] = rgb
        attr.keyframe_insert('["tint"]', frame=frame)
    scenes.animation_of_one_frame(scene, 4, tmp_path)
    data = exported(animation=True)
    for name in ("Info", "Attr"):
        assert np.allclose(data.geometry.colors[of_object(data, name)][..., :3], (0.9, 0.1, 0.9), atol=1e-6), name


def test_view_layer_overrides_are_read_at_the_rendered_frame_in_an_animation_render(scene, exported, tmp_path):
    """A view layer's World and Material Overrides with keyed values render with the values of
    the frame rendered (the original layer's overrides are the original IDs, which keep the
    file's frame in an animation render: a world keyed 1 -> 8 rendered 1 on every frame)."""
    setup(scene)
    scenes.plane("P")
    world = bpy.data.worlds.new("Override")
    strength = next(n for n in world.node_tree.nodes if n.type == 'BACKGROUND').inputs['Strength']
    clay = scenes.diffuse("Clay", (0.8, 0.8, 0.8))
    colour = next(n for n in clay.node_tree.nodes if n.type == 'BSDF_DIFFUSE').inputs['Color']
    for frame, k, rgb in ((1, 1.0, (0.8, 0.8, 0.8, 1.0)), (4, 8.0, (0.8, 0.0, 0.0, 1.0))):
        strength.default_value = k
        strength.keyframe_insert('default_value', frame=frame)
        colour.default_value = rgb
        colour.keyframe_insert('default_value', frame=frame)
    vl = scene.view_layers[0]
    vl.world_override, vl.material_override = world, clay
    scenes.animation_of_one_frame(scene, 4, tmp_path)
    data = exported(animation=True)
    grey = np.array(world.color)[:3]
    assert np.allclose(data.world, 8.0 * grey, rtol=1e-5)
    clay_out = next(m for m in data.materials if m.name == 'Clay')
    assert np.allclose(clay_out.base_color, (0.8, 0.0, 0.0), atol=1e-6)


def test_instances_read_their_instancers_object_colour(scene, exported):
    """An instance's Object Info Color and Alpha, and an Object attribute 'color', are its
    instancer's (Blender's dupli iterator gives the instance's object the instancer's colour;
    Cycles reads it there): measured in Cycles, a red cube under a blue instancer renders
    blue (0.924 blue; DACRT had rendered it red). Object Index stays the object's own."""
    setup(scene)
    made = [_object_value_material("InfoColor", 'Color'), _object_value_material("InfoAlpha", 'Alpha'),
            _object_value_material("AttrColor", None, 'color')]
    props = bpy.data.collections.new("Props")            # instanced only
    for i, mat in enumerate(made):
        ob = scenes.plane(f"Src{i}", location=(3 * i, 0, 0), materials=(mat,))
        ob.color = (1.0, 0.0, 0.0, 0.9)
        for c in list(ob.users_collection):
            c.objects.unlink(ob)
        props.objects.link(ob)
    for j, rgba in enumerate(((0.0, 0.0, 1.0, 0.3), (0.0, 1.0, 0.0, 0.6))):
        empty = bpy.data.objects.new(f"Instancer{j}", None)
        empty.instance_type, empty.instance_collection = 'COLLECTION', props
        empty.location, empty.color = (0, 10 * j, 0), rgba
        scene.collection.objects.link(empty)
    data = exported()
    geo = data.geometry
    y = geo.vertices[geo.triangles][:, :, 1].mean(axis=1)
    for i in range(3):
        tris = of_object(data, f"Src{i}")
        for j, rgba in enumerate(((0.0, 0.0, 1.0, 0.3), (0.0, 1.0, 0.0, 0.6))):
            here = tris & ((y > 5) == bool(j))
            assert here.sum() == 2, (i, j)
            want = (rgba[3],) * 3 if i == 1 else rgba[:3]
            assert np.allclose(geo.colors[here][..., :3], want, atol=1e-6), (i, j, geo.colors[here][0])


def test_object_attribute_per_object(scene, exported):
    """An Attribute node of type Object reads each object's value as Cycles does (custom
    property, else RNA path such as 'color', else the object data's property; none: 0): the
    Color output the value, Factor its average."""
    setup(scene)
    made = {}
    for out in ('Color', 'Factor'):
        mat, nt, o = _shader_material(out)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(d.outputs[0], o.inputs['Surface'])
        attr = nt.nodes.new('ShaderNodeAttribute')
        attr.attribute_type, attr.attribute_name = 'OBJECT', 'tint'
        nt.links.new(attr.outputs[out], d.inputs['Color'])
        made[out] = mat
    obs = {}
    for i, out in enumerate(('Color', 'Factor')):
        for j, how in enumerate(('prop', 'data', 'none')):
            ob = scenes.plane(f"{out}_{how}", location=(3 * i, 3 * j, 0), materials=(made[out],))
            if how == 'prop':
                ob['tint'] = (0.2, 0.5, 0.8)
            elif how == 'data':
                ob.data['tint'] = 0.4
            obs[ob.name] = {'prop': (0.2, 0.5, 0.8), 'data': (0.4,) * 3, 'none': (0.0,) * 3}[how]
    path, pm, po = _shader_material("Path")
    d = pm.nodes.new('ShaderNodeBsdfDiffuse')
    pm.links.new(d.outputs[0], po.inputs['Surface'])
    attr = pm.nodes.new('ShaderNodeAttribute')
    attr.attribute_type, attr.attribute_name = 'OBJECT', 'color'       # the object's Viewport colour
    pm.links.new(attr.outputs['Color'], d.inputs['Color'])
    scenes.plane("ByPath", location=(9, 0, 0), materials=(path,)).color = (0.9, 0.3, 0.1, 1.0)
    obs["ByPath"] = (0.9, 0.3, 0.1)
    data = exported()
    for name, rgb in obs.items():
        want = np.full(3, np.mean(rgb)) if name.startswith('Factor') else np.asarray(rgb)
        got = data.geometry.colors[of_object(data, name)]
        assert np.allclose(got, want, atol=1e-6), (name, got[0, 0], want)
    assert not any('attribute' in m.approximated for m in data.materials)


def test_image_times_colour_attribute_either_way(scene, exported, tmp_path):
    """An image multiplied by a colour attribute (a glTF import's vertex colours), in either
    input order: the material keeps the image (looked up as Cycles stores it) and the colours
    multiply it per point, exactly, nothing reported."""
    setup(scene)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "red.png", np.full((2, 2, 3), (204, 25, 25), np.uint8)))
    quad = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    for i, image_first in enumerate((True, False)):
        def times_image(nt, s, image_first=image_first):
            tex = nt.nodes.new('ShaderNodeTexImage')
            tex.image = img
            a, b = (tex.outputs['Color'], s) if image_first else (s, tex.outputs['Color'])
            return scenes.mix_node(nt, 'MULTIPLY', a, b, 1.0).outputs['Result']
        name = f"Order{i}"
        ob = scenes.mesh(name, quad, [(0, 1, 2, 3)], location=(3 * i, 0, 0),
                         materials=(_attribute_material(name, chain=times_image),))
        ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT').data.foreach_set(
            'color', np.tile([0.25, 1.0, 0.5, 1.0], 4).astype(np.float32))
    data = exported()
    table = {m.name: m for m in data.materials}
    for i in range(2):
        m = table[f"Order{i}"]
        assert m.approximated == '' and m.color_attribute == color_attribute_key('Col') and stored_texels(m.texture) is not None
        assert np.allclose(m.base_color, 1.0)
        assert np.allclose(data.geometry.colors[of_object(data, f"Order{i}")], (0.25, 1.0, 0.5), atol=1e-6)


def test_world_max_bounces_exported(scene, exported):
    setup(scene)
    w = scenes.world((0.2, 0.2, 0.2), 1.0)
    assert exported().world_max_bounces == 1024         # Blender's default: no limit
    w.cycles.max_bounces = 3
    assert exported().world_max_bounces == 3


def test_nan_shader_inputs_read_as_zero_and_are_named(scene, exported):
    """A NaN a script or driver put into a float input: read as 0, as Cycles' clamps give (a
    Mix Shader's factor: its first shader; measured: 0.4330 vs Cycles 0.4323), named in the
    report; it had failed the render ('refraction must be 3 finite numbers') or turned the
    base colour black (a Principled Roughness: 0.2248, Cycles 0.3858, now 0.3929)."""
    setup(scene)
    mat, nt, mix, first, second = scenes.mix_shader_material("Mixed", 'ShaderNodeBsdfTransparent',
                                                            'ShaderNodeBsdfDiffuse')
    mix.inputs['Fac'].default_value = float('nan')
    scenes.plane("A", materials=(mat,))
    rough, nt2, out2 = scenes._material("Rough")
    p = nt2.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.5, 0.4, 0.3, 1.0)
    p.inputs['Roughness'].default_value = float('nan')
    nt2.links.new(p.outputs[0], out2.inputs['Surface'])
    scenes.plane("B", location=(3, 0, 0), materials=(rough,))
    data = exported()
    by_name = {m.name: m for m in data.materials}
    assert np.all(by_name["Mixed"].transparency == 1.0)            # factor 0: the Transparent BSDF
    assert np.all(np.isfinite(by_name["Rough"].base_color)) and by_name["Rough"].base_color[0] > 0.4
    text = " | ".join(m for _, m in data.messages)
    assert "NaN read as 0" in text
    assert "'Fac' of 'Mix Shader'" in text or "'Factor' of 'Mix Shader'" in text
    assert "'Roughness' of 'Principled BSDF'" in text


def test_lights_beyond_float32_are_skipped_not_the_render(scene, exported):
    """Sizes, radii, angles and strengths whose float32 lamp would hold an infinity (an area
    light of size 1e20 or 1e-20, a point radius 1e-20, a sun angle 1e-25, energy 1e36 x 2^10):
    each skipped with a warning naming it, the rest exported (the render had failed with
    'records[0]: field 13 is not finite')."""
    setup(scene)
    scenes.plane("Floor")
    scenes.light('POINT', 100.0, (0, 0, 3), name="Fine")
    scenes.light('AREA', 100.0, (0, 0, 3), name="Huge").data.size = 1e20
    scenes.light('AREA', 100.0, (0, 0, 3), name="Tiny").data.size = 1e-20
    scenes.light('POINT', 100.0, (0, 0, 3), name="Dot").data.shadow_soft_size = 1e-20
    scenes.light('SUN', 1.0, (0, 0, 3), name="Needle").data.angle = 1e-25
    bright = scenes.light('POINT', 1e36, (0, 0, 3), name="Bright")
    bright.data.exposure = 10.0
    data = exported()
    assert [l.name for l in data.lights] == ["Fine"]
    text = " | ".join(m for _, m in data.messages)
    for name in ("Huge", "Tiny", "Dot", "Needle", "Bright"):
        assert f"light '{name}': its size, radius, angle or strength is beyond float32's range" in text, name


def test_grease_pencil_is_said_to_be_drawn_over_the_render(scene, exported):
    """Blender draws Grease Pencil over an external engine's render, as over Cycles' (a helper
    measured the same 147 pixels changed in both): not 'skipped ... not rendered'."""
    setup(scene)
    scenes.plane("Floor", size=4.0)
    bpy.ops.object.grease_pencil_add(type='MONKEY')
    data = exported()
    said = [t for _, t in data.messages if "Grease Pencil" in t]
    assert len(said) == 1 and "drawn by Blender over the render" in said[0], data.messages
    assert not any("skipped" in t and "Suzanne" in t for _, t in data.messages), data.messages
    assert data.skipped.get('objects_unsupported', 0) == 0


@pytest.mark.parametrize("node_map", ["", "UVMap", "Second"])
def test_normal_map_tangents_are_of_the_normal_map_nodes_uv_map(scene, exported, node_map):
    """The image of a normal map is read on its own UV map (a UV Map node: 'Second', mirrored in
    u), but the tangents are those of the Normal Map node's map ('' the active render one), as
    Cycles reads that map's tangent attribute: DACRT took the image's map's (a helper's plane
    0.11 where Cycles gives 0.62), silently for the node's default."""
    setup(scene)
    img = bpy.data.images.new("Normals", 2, 2)
    img.colorspace_settings.name = 'Non-Color'
    mat = scenes.normal_map_material("Mapped", img)
    nt = mat.node_tree
    uv_node = nt.nodes.new('ShaderNodeUVMap')
    uv_node.uv_map = 'Second'
    nt.links.new(uv_node.outputs[0], nt.nodes['Image Texture'].inputs['Vector'])
    nt.nodes['Normal Map'].uv_map = node_map
    ob = scenes.plane("P", materials=(mat,))
    me = ob.data
    first, second = me.uv_layers[0] if len(me.uv_layers) else me.uv_layers.new(name='UVMap'), None
    first.name = 'UVMap'
    second = me.uv_layers.new(name='Second')
    for i, loop in enumerate(me.loops):
        u, v = first.data[i].uv
        second.data[i].uv = (1.0 - u, v)
    me.uv_layers['UVMap'].active_render = True
    data = exported()
    me.calc_tangents(uvmap=node_map or 'UVMap')
    want = np.array([[list(me.loops[c].tangent) + [me.loops[c].bitangent_sign] for c in t.loops]
                     for t in me.loop_triangles])
    got = data.geometry.tangents[data.geometry.object_index == data.object_names.index("P")]
    np.testing.assert_allclose(got, want, atol=1e-5)
    assert not any("normal map" in t for _, t in data.messages), data.messages


def test_two_materials_of_one_mesh_keep_their_own_normal_maps_tangents(scene, exported):
    """Two materials on one mesh, their Normal Map nodes on two UV maps ('UVMap', and 'Second'
    mirrored in u): each half gets its own map's tangents (both had taken the first name's:
    0.13 where Cycles gives 0.75 on the half whose map runs the other way)."""
    setup(scene)
    img = bpy.data.images.new("Normals", 2, 2)
    img.colorspace_settings.name = 'Non-Color'
    a, b = scenes.normal_map_material("A", img), scenes.normal_map_material("B", img)
    a.node_tree.nodes['Normal Map'].uv_map = 'UVMap'
    b.node_tree.nodes['Normal Map'].uv_map = 'Second'
    ob = scenes.mesh("P", [(-2, -1, 0), (0, -1, 0), (0, 1, 0), (-2, 1, 0), (2, -1, 0), (2, 1, 0)],
                     [(0, 1, 2, 3), (1, 4, 5, 2)], materials=(a, b))
    me = ob.data
    me.polygons[1].material_index = 1
    first = me.uv_layers[0] if len(me.uv_layers) else me.uv_layers.new(name='UVMap')
    first.name = 'UVMap'
    for i, loop in enumerate(me.loops):
        co = me.vertices[loop.vertex_index].co
        first.data[i].uv = ((co.x + 2) / 4, (co.y + 1) / 2)
    second = me.uv_layers.new(name='Second')
    for i in range(len(me.loops)):
        u, v = first.data[i].uv
        second.data[i].uv = (1.0 - u, v)
    data = exported()
    got = data.geometry.tangents[data.geometry.object_index == data.object_names.index("P")]
    names = [data.materials[k].name for k in data.geometry.material[data.geometry.object_index
                                                                      == data.object_names.index("P")]]
    for name, uv in (("A", 'UVMap'), ("B", 'Second')):
        me.calc_tangents(uvmap=uv)
        want = np.array([[list(me.loops[c].tangent) + [me.loops[c].bitangent_sign] for c in t.loops]
                         for t in me.loop_triangles])
        rows = [i for i, n in enumerate(names) if n == name]
        np.testing.assert_allclose(got[rows], want[rows], atol=1e-5, err_msg=name)
    assert not any("normal map" in t for _, t in data.messages), data.messages


def test_a_linked_object_named_as_a_local_one_keeps_its_own_entry(scene, exported, tmp_path):
    """An object linked from a library beside a local object of the same name ('Cube' and
    'Cube [lib.blend]') keeps its own entry: its pass index (Object Index pass) had been the
    local one's, as entries were keyed by the short name."""
    setup(scene)
    cube = scenes.plane("Cube")
    cube.pass_index = 5
    lib = tmp_path / "lib.blend"
    bpy.data.libraries.write(str(lib), {cube})
    cube.pass_index, cube.location.x = 1, 3.0
    with bpy.data.libraries.load(str(lib), link=True) as (_, linked):
        linked.objects = ["Cube"]
    scene.collection.objects.link(linked.objects[0])
    assert linked.objects[0].name == cube.name and linked.objects[0].name_full != cube.name_full
    data = exported()
    g = data.geometry
    x = g.vertices[g.triangles].mean(axis=1)[:, 0]
    index = np.asarray(data.object_pass_index)[g.object_index]
    assert set(index[x > 2.0]) == {1} and set(index[x < 1.0]) == {5}, (data.object_names, data.object_pass_index)


def test_a_mesh_with_n_gons_keeps_its_normal_map(scene, exported):
    """Blender's calc_tangents refuses n-gons, and one n-gon (a default cylinder's caps) had
    dropped the normal map of the whole mesh; the tangents now come from the render's own
    triangles (as Cycles runs mikktspace on its triangles): the sides' are those of the same
    cylinder with triangle-fan caps, and nothing is reported."""
    setup(scene)
    img = bpy.data.images.new("Normals", 2, 2)
    img.colorspace_settings.name = 'Non-Color'
    mat = scenes.normal_map_material("Mapped", img)
    sides = {}
    for fill, x in (('NGON', 0.0), ('TRIFAN', 5.0)):
        bpy.ops.mesh.primitive_cylinder_add(vertices=12, location=(x, 0, 0), end_fill_type=fill)
        ob = bpy.context.active_object
        ob.name = fill
        ob.data.materials.append(mat)
    data = exported()
    g = data.geometry
    assert g.tangents is not None and not any("normal map" in t for _, t in data.messages), data.messages
    for fill in ('NGON', 'TRIFAN'):
        sel = of_object(data, fill)
        side = np.abs(g.normals[sel][:, 0, 2]) < 0.5
        key = np.round(g.vertices[g.triangles[sel][side]].mean(axis=1) - (5.0 if fill == 'TRIFAN' else 0.0, 0, 0), 4)
        order = np.lexsort(key.T)
        sides[fill] = g.tangents[sel][side][order]
        assert np.abs(sides[fill][..., :3]).sum(axis=2).min() > 0.5       # every side corner has one
    np.testing.assert_allclose(sides['NGON'], sides['TRIFAN'], atol=1e-5)


@pytest.mark.parametrize("node, setup_node, want", [
    ('ShaderNodeGamma', lambda n: setattr(n.inputs['Gamma'], 'default_value', 2.0), (1.0, 0.0, 1.0)),
    ('ShaderNodeHueSaturation', lambda n: setattr(n.inputs['Hue'], 'default_value', 0.3), (0.0, 0.2, 1.0)),
    ('ShaderNodeInvert', lambda n: None, (0.0, 1.0, 0.0)),
])
def test_colour_nodes_after_an_environment_texture_without_an_image_act_on_magenta(scene, exported, node,
                                                                                     setup_node, want):
    """Cycles' missing image is opaque magenta, and the colour nodes after it compute on that:
    Hue 0.3 gives (0.0001, 0.199, 0.977) in a Cycles render (here exactly (0, 0.2, 1)). The nodes
    had not been evaluated: the Background's own grey (0.05) stood in."""
    setup(scene)
    w = scenes.environment_world(None, 2.0)
    nt = w.node_tree
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    n = nt.nodes.new(node)
    setup_node(n)
    nt.links.new(env.outputs['Color'], n.inputs['Color'])
    nt.links.new(n.outputs[0], bg.inputs['Color'])
    data = exported()
    assert data.environment is None and np.allclose(data.world, 2.0 * np.array(want), atol=1e-5), data.world
    assert any("Environment Texture without an image (magenta" in t for _, t in data.messages)
    assert not any("not evaluated" in t for _, t in data.messages)


def test_instances_no_ray_sees_are_counted_as_instances_not_objects(scene, exported):
    """A collection instanced by 4 empties that no ray type sees: 4 instances skipped (said as
    '4 instances'), not 4 objects, beside the one plane of the scene's own that no ray sees."""
    setup(scene)
    coll = bpy.data.collections.new("Props")
    prop = bpy.data.objects.new("Prop", bpy.data.meshes.new("Prop"))
    prop.data.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    coll.objects.link(prop)
    for i in range(4):
        e = bpy.data.objects.new(f"Holder{i}", None)
        e.instance_type, e.instance_collection = 'COLLECTION', coll
        e.location.x = 3.0 * i
        e.visible_camera = e.visible_diffuse = e.visible_glossy = e.visible_transmission = False
        e.visible_volume_scatter = e.visible_shadow = False
        scene.collection.objects.link(e)
    gone = scenes.plane("Gone", location=(0, 5, 0))
    gone.visible_camera = gone.visible_diffuse = gone.visible_glossy = gone.visible_transmission = False
    gone.visible_volume_scatter = gone.visible_shadow = False
    scenes.plane("Shown", location=(0, -5, 0))
    data = exported()
    assert data.skipped['instances_invisible'] == 4 and data.skipped['objects_invisible'] == 1
    from addon.engine import _skipped_text
    assert _skipped_text({'objects': 1, 'instances': 4}) == "1 object, 4 instances"
