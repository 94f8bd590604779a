"""Normal maps on non-planar quads against Cycles. Cycles runs mikktspace over its own triangles
(MikkMeshWrapper::GetNumFaces is the triangle count); Blender's calc_tangents on the mesh runs
it over the faces, so a quad that is not planar, which any deforming quad mesh has (a Wave, an
armature, a sculpt), got other tangents: the image was off by 5-11% in places. Compared here
on the Normal pass (the bent normal, as each engine writes it; 8 x 8 blocks of 8 x 8 pixels,
32 spp), which needs few samples."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _normal_image(tmp_path):
    """A 32 x 32 Non-Color map whose normal turns both ways along u and v."""
    n = 32
    y, x = np.mgrid[0:n, 0:n] / n
    nx, ny = 0.5 * np.sin(x * 2 * np.pi), 0.5 * np.cos(y * 2 * np.pi)
    nz = np.sqrt(1 - nx ** 2 - ny ** 2)
    px = (np.stack([nx, ny, nz], -1) * 127.5 + 127.5).round().astype(np.uint8)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "normal.png", px))
    img.colorspace_settings.name = 'Non-Color'
    return img


def _quad_grid(tmp_path, jitter, smooth, flat_every=0, sharp_edge_every=0):
    """A 4 x 4 grid of 12 x 12 quads, vertex heights jittered (non-planar quads), planar UVs;
    with flat_every every so many faces flat among smooth ones, with sharp_edge_every every so
    many edges marked sharp."""
    import bmesh                     # (importable once bpy is)
    me = bpy.data.meshes.new("Grid")
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=12, y_segments=12, size=2.0)
    rnd = np.random.default_rng(3)
    for v in bm.verts:
        v.co.z += float(rnd.uniform(-jitter, jitter))
    bm.to_mesh(me)
    bm.free()
    co = np.array([v.co[:] for v in me.vertices])
    corner_vert = np.array([c.vertex_index for c in me.loops])
    me.uv_layers.new(name="UVMap").uv.foreach_set('vector', (co[corner_vert, :2] / 4 + 0.5).ravel())
    me.shade_smooth() if smooth else me.shade_flat()
    for every, name, domain, n in ((flat_every, 'sharp_face', 'FACE', len(me.polygons)),
                                   (sharp_edge_every, 'sharp_edge', 'EDGE', len(me.edges))):
        if every:
            flags = np.zeros(n, bool)
            flags[::every] = True
            attr = me.attributes.get(name) or me.attributes.new(name, 'BOOLEAN', domain)
            attr.data.foreach_set('value', flags)
    ob = bpy.data.objects.new("Grid", me)
    bpy.context.scene.collection.objects.link(ob)
    me.materials.append(scenes.normal_map_material("Bumpy", _normal_image(tmp_path)))
    return ob


def _normals(tmp_path):
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 64
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=3.6)
    scenes.world((0.5, 0.5, 0.5))
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    out = {}
    for e, exr in exrs.items():
        n = np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1)
        out[e] = n.reshape(8, 8, 8, 8, 3).mean(axis=(1, 3))        # 8 x 8 blocks of 8 x 8 pixels
    return out


@pytest.mark.parametrize('smooth,atol', [(True, 0.003), (False, 0.03)])
def test_jittered_quads_bend_normals_as_cycles(smooth, atol, tmp_path):
    """Largest block difference of the bent normal, before / after: smooth 0.015 / 0.0006, flat
    0.110 / 0.009 (a flat triangle's own normal, as Cycles takes it; its edges make that pass
    noisier)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    _quad_grid(tmp_path, 0.3, smooth)
    n = _normals(tmp_path)
    assert np.abs(n['CYCLES'] - n['CYCLES'].mean((0, 1))).max() > 0.2, "the map must bend the normals"
    np.testing.assert_allclose(n['DACRT'], n['CYCLES'], atol=atol)


@pytest.mark.parametrize('sharp_edge_every', [0, 7])
def test_flat_quads_among_smooth_ones_bend_normals_as_cycles(sharp_edge_every, tmp_path):
    """Every third quad flat: Cycles' mikktspace reads the normals it shades with, the vertex
    normals across the flat faces (a flat triangle its own) where only flat faces make Blender's
    normals CORNER, the split corner normals (a flat face's its normal) with sharp edges too;
    Blender's calc_tangents had read its corner normals, split at every flat face. Largest
    block difference, before / after: 0.054 / 0.005, with sharp edges 0.019 / 0.004."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    _quad_grid(tmp_path, 0.3, True, flat_every=3, sharp_edge_every=sharp_edge_every)
    n = _normals(tmp_path)
    np.testing.assert_allclose(n['DACRT'], n['CYCLES'], atol=0.01)


def test_planar_quads_under_a_warped_uv_map_bend_normals_as_cycles(tmp_path):
    """Planar quads whose UV map is not affine over each quad (any unwrap that stretches): the
    quad's two triangles have other tangents, which mikktspace on the faces averaged: 0.160
    before, 0.003 after. (Planar quads mapped affinely keep Blender's calc_tangents on the
    faces: the same tangents, no temporary mesh.)"""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    me = _quad_grid(tmp_path, 0.0, True).data
    co = np.array([v.co[:] for v in me.vertices])
    x, y = co[[c.vertex_index for c in me.loops]].T[:2]
    uv = np.stack([x / 4 + 0.5 + 0.15 * np.sin(2 * y) * x, y / 4 + 0.5 + 0.1 * x * x], -1)
    me.uv_layers[0].uv.foreach_set('vector', uv.ravel())
    n = _normals(tmp_path)
    np.testing.assert_allclose(n['DACRT'], n['CYCLES'], atol=0.01)


def test_flat_mapped_quads_are_told_apart():
    """_flat_mapped_quads: planar quads mapped affinely (a default grid) take calc_tangents on
    the faces; a lifted corner or a warped UV map does not."""
    from addon.export import meshes
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=4, size=2, rotation=(0.3, 0.2, 0.1))
    me = bpy.context.active_object.data

    def told():
        return meshes._flat_mapped_quads(me, 'UVMap', np.array([v.co[:] for v in me.vertices], np.float32))
    assert told()
    me.vertices[6].co.z += 0.01
    assert not told()
    me.vertices[6].co.z -= 0.01
    assert told()
    me.uv_layers[0].uv[5].vector.x += 0.01
    assert not told()


def test_wave_deformed_quads_bend_normals_as_cycles(tmp_path):
    """An animated Wave modifier at frame 9 (planar quads on frame 1, bent ones after): 0.009
    before, 0.0009 after."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    ob = _quad_grid(tmp_path, 0.0, True)
    wave = ob.modifiers.new("Wave", 'WAVE')
    wave.height, wave.width, wave.speed = 0.8, 1.2, 0.4
    bpy.context.scene.frame_set(9)
    n = _normals(tmp_path)
    np.testing.assert_allclose(n['DACRT'], n['CYCLES'], atol=0.003)
