"""Texture coordinates on hair (addon/export/strands.py): Cycles gives each strand one Generated
coordinate and one UV, both at its root and constant along it (blender/curves.cpp): a hair
particle strand its root in the emitter's texture space and the emitter's UV maps there
(uv_on_emitter), a Curves object's strands their 'surface_uv_coordinate'. Checked on the
exported corners; the repro renders agree with Cycles within its noise."""
import bpy
import numpy as np

from tests.addon import scenes


def _names(data):
    return np.array([m.name for m in data.materials])[data.geometry.material]


def _image_material(name, uv_map=''):
    """A diffuse coloured by an image on the active UV map, or on uv_map by a UV Map node."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image(name, np.ones((2, 2, 4), np.float32))
    if uv_map:
        uv = nt.nodes.new('ShaderNodeUVMap')
        uv.uv_map = uv_map
        nt.links.new(uv.outputs['UV'], tex.inputs['Vector'])
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _generated_material(name):
    """A diffuse coloured by a noise texture on the Generated coordinates."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tc, nz = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(tc.outputs['Generated'], nz.inputs['Vector'])
    nt.links.new(nz.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _emitter(materials, systems=1, count=6):
    """A 4 x 2 plane over x 1..5, y -1..1 (auto texture space: location (3, 0, 0), size
    (2, 1, 1)) with straight hair along +z, 0.01 thick, from each system's own slot."""
    em = scenes.mesh("Emitter", [(1, -1, 0), (5, -1, 0), (5, 1, 0), (1, 1, 0)], [(0, 1, 2, 3)],
                     materials=materials)
    for k in range(systems):
        em.modifiers.new(f"hair{k}", 'PARTICLE_SYSTEM')
        s = em.particle_systems[k].settings
        s.type, s.count, s.hair_length, s.material = 'HAIR', count, 1.0, k + 1
        s.root_radius, s.tip_radius, s.radius_scale, s.use_close_tip = 1.0, 1.0, 0.02, False
    return em


def test_hair_particle_generated_is_the_root_in_the_emitter_texture_space(scene, exported):
    """Cycles' Generated on a hair particle strand is its root mapped through the emitter's
    texture space ((co - loc) / (2 size) + 1/2: here ((x - 3) / 4 + 1/2, y / 2 + 1/2, 1/2)),
    one value along the strand. It had been the tubes' own bounds: z ran 0..1 from root to
    tip (a repro's strands read 0.14 at the bottom, 0.41 at the top, where Cycles' read
    0.23-0.25 all along)."""
    scenes.camera()
    _emitter([_generated_material("Fur")], count=8)
    data = exported()
    g = data.geometry
    hair = _names(data) == "Fur"
    assert hair.sum() > 0
    gen = np.asarray(g.coords)[hair][..., :3].reshape(-1, 3)
    at = np.asarray(g.vertices)[g.triangles[hair]].reshape(-1, 3)      # the corners, world = object
    np.testing.assert_allclose(gen[:, 2], 0.5, atol=1e-6)             # the root's, not the strand's height
    # straight strands: every corner is within the tube's radius (0.01, its ring a bit wider)
    # of its root
    want = np.stack([(at[:, 0] - 3) / 4 + 0.5, at[:, 1] / 2 + 0.5], axis=1)
    assert np.abs(gen[:, :2] - want).max() < 0.0061


def test_hair_particle_uv_is_the_emitter_uv_at_the_root(scene, exported):
    """Cycles reads every UV map of the emitter at each strand's root (uv_on_emitter, the map
    by its index; children by their own index): an image on the active map reads (x - 1) / 4,
    (y + 1) / 2 here, one by a UV Map node on 'Second' that map's (1 - u, 1 - v), on parents
    and on interpolated children. Every strand had read UV (0, 0), the image's corner texel (a
    repro's 2x2 image: hair (0.482, 0, 0) where Cycles gives (0.241, 0.211, 0.173))."""
    scenes.camera()
    em = _emitter([_image_material("Fur"), _image_material("Fur2", uv_map="Second")], systems=2)
    me = em.data
    x = np.array([me.vertices[l.vertex_index].co.x for l in me.loops])
    y = np.array([me.vertices[l.vertex_index].co.y for l in me.loops])
    first = np.stack([(x - 1) / 4, (y + 1) / 2], axis=1)
    me.uv_layers.new(name="UVMap").uv.foreach_set('vector', first.astype(np.float32).ravel())
    me.uv_layers.new(name="Second").uv.foreach_set('vector', (1 - first).astype(np.float32).ravel())
    me.uv_layers["UVMap"].active_render = True
    for children in (False, True):
        if children:
            for ps in em.particle_systems:
                ps.settings.child_type, ps.settings.rendered_child_count = 'INTERPOLATED', 3
        data = exported()
        g = data.geometry
        names = _names(data)
        for name, flip in (("Fur", False), ("Fur2", True)):
            hair = names == name
            assert hair.sum() > 0
            at = np.asarray(g.vertices)[g.triangles[hair]].reshape(-1, 3)
            want = np.stack([(at[:, 0] - 1) / 4, (at[:, 1] + 1) / 2], axis=1)
            want = 1 - want if flip else want
            uv = np.asarray(g.uvs)[hair].reshape(-1, 2)
            assert np.abs(uv - want).max() < 0.0061, (name, children)     # within the radius of the root
            assert g.has_uv is None or np.asarray(g.has_uv)[hair].all()


def test_curves_uv_is_their_surface_uv_coordinate(scene, exported):
    """A Curves object's UV in Cycles is its 'surface_uv_coordinate' (2D, on curves), one
    value along each curve; a UV Map node reads a 2D attribute by name, a point one between
    the curve's points. They had read (0, 0) (a repro's 8 curves: (0.479, 0, 0) where Cycles
    gives (0.302, 0.182, 0))."""
    scenes.camera()
    z = np.array([[0, 0, 0], [0, 0, 0.5], [0, 0, 1.0]])
    fur = scenes.hair_curves("Fur", [z, z + (1, 0, 0)], radius=0.05, material=_image_material("Fur"))
    uv = fur.data.attributes.new('surface_uv_coordinate', 'FLOAT2', 'CURVE')
    uv.data.foreach_set('vector', np.array([0.2, 0.3, 0.7, 0.9], np.float32))
    named = _image_material("Named", uv_map="along")
    strip = scenes.hair_curves("Strip", [z + (3, 0, 0)], radius=0.05, material=named)
    along = strip.data.attributes.new('along', 'FLOAT2', 'POINT')
    along.data.foreach_set('vector', np.array([[0, h] for h in (0, 0.5, 1)], np.float32).ravel())
    strip.data.set_types(type='POLY')       # straight: v follows z between the points
    data = exported()
    g = data.geometry
    names = _names(data)
    hair = names == "Fur"
    at = np.asarray(g.vertices)[g.triangles[hair]].reshape(-1, 3)
    want = np.where((at[:, 0] < 0.5)[:, None], [0.2, 0.3], [0.7, 0.9])
    np.testing.assert_allclose(np.asarray(g.uvs)[hair].reshape(-1, 2), want, atol=1e-6)
    named = names == "Named"        # the point attribute by name, between the points linearly
    assert named.sum() > 0
    at = np.asarray(g.vertices)[g.triangles[named]].reshape(-1, 3)
    # (the Poly strip's round end caps take their end point's value, as Cycles' end spheres)
    v = np.clip(at[:, 2], 0.0, 1.0)
    np.testing.assert_allclose(np.asarray(g.uvs)[named].reshape(-1, 2), np.stack([0 * v, v], 1), atol=1e-5)


def test_hair_is_not_placed_again_on_the_emitters_own_geometry_nodes_instances(scene, exported):
    """An emitter whose Geometry Nodes modifier adds instances (its input joined with cones on
    points) keeps one placement of its hair, as Cycles renders it: the instance entries are
    copies of the emitter that carry its particle systems, and the hair had been placed once
    per cone too (7 tufts for 1)."""
    scenes.camera()
    em = _emitter((scenes.diffuse("Skin", (0.5, 0.5, 0.5)),))
    ng = bpy.data.node_groups.new("Cones", 'GeometryNodeTree')
    ng.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gin, gout = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    grid = ng.nodes.new('GeometryNodeMeshGrid')
    grid.inputs['Vertices X'].default_value, grid.inputs['Vertices Y'].default_value = 3, 2
    cone, inst, join = (ng.nodes.new(t) for t in ('GeometryNodeMeshCone', 'GeometryNodeInstanceOnPoints',
                                                  'GeometryNodeJoinGeometry'))
    ng.links.new(grid.outputs['Mesh'], inst.inputs['Points'])
    ng.links.new(cone.outputs['Mesh'], inst.inputs['Instance'])
    ng.links.new(gin.outputs[0], join.inputs[0])
    ng.links.new(inst.outputs['Instances'], join.inputs[0])
    ng.links.new(join.outputs[0], gout.inputs[0])

    def triangles():
        return len(exported().geometry.triangles)
    hair_and_plane = triangles()
    em.modifiers.new("GN", 'NODES').node_group = ng
    em.modifiers["hair0"].show_render = False
    cones = triangles() - 2                                      # (the plane's two)
    em.modifiers["hair0"].show_render = True
    assert triangles() == hair_and_plane + cones, (hair_and_plane, cones)
