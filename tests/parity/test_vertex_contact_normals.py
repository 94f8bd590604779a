"""Faces Blender's corner normals shade apart but Cycles 5.0 joins at a vertex: Cycles splits a
CORNER-domain mesh only along sharp edges and flat faces' edges, then keeps one normal per
vertex, the corner normal of the vertex's last face. Faces touching at a vertex alone (a floor
and a wall, in both face orders; three fans), across a non-manifold edge (a fin on a floor's
edge) or across an edge of two faces wound against each other share that normal there, and
Blender's free corner normals are not split either. Each mesh has a sharp edge elsewhere, as
the OBJ importer's meshes do, so its normals are CORNER. Rendered as Geometry Normal emission
(direct, K = 0) against Cycles: the mean within 1% and 4 x 4 blocks within 4%. Before
(Blender's corner normals as they were): bowtie means 0.965 / 0.999, blocks 20% off; three
fans 0.884 / 1.097; fin 0.957; a floor-and-wall bowtie under a point light D/C 1.11."""
import bpy
import numpy as np
import pytest
from mathutils import Vector

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

FLOOR, WALL = [(0, 0, 0), (2, 0, 0), (0, 2, 0)], [(0, 0, 2), (2, 0, 2)]
AWAY = [(5, 5, 5), (5, 6, 5)]      # with another vertex, a triangle whose sharp edge makes CORNER


def _normal_emission():
    mat = bpy.data.materials.new("N")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    half = nt.nodes.new('ShaderNodeVectorMath')
    half.operation = 'MULTIPLY_ADD'
    half.inputs[1].default_value = half.inputs[2].default_value = (0.5, 0.5, 0.5)
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(geo.outputs['Normal'], half.inputs[0])
    nt.links.new(half.outputs[0], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _diffuse():
    mat = bpy.data.materials.new("D")
    nt = mat.node_tree
    nt.nodes.clear()
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], nt.nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    return mat


def _mesh(verts, faces, sharp, material, free=None):
    me = bpy.data.meshes.new("M")
    me.from_pydata(verts, [], faces)
    me.update()
    me.shade_smooth()
    for e in me.edges:
        if sorted(e.vertices) == sorted(sharp):
            e.use_edge_sharp = True
    if free is not None:
        a = me.attributes.new('custom_normal', 'FLOAT_VECTOR', 'CORNER')
        a.data.foreach_set('vector', free(len(me.loops)).astype(np.float32).ravel())
        me.update()
    assert me.normals_domain == 'CORNER'
    me.materials.append(material)
    scenes.link(bpy.data.objects.new("M", me))
    return me


def _free_normals(n):
    rows = np.random.default_rng(1).normal(size=(n, 3)) * 0.4 + (0, 0, 1)
    return rows / np.linalg.norm(rows, axis=1, keepdims=True)


GRID = [(x, y, 0.1 * x * y) for y in (-1, 0, 1) for x in (-1, 0, 1)]
CASES = {
    # name: (vertices, faces, sharp edge, camera, target)
    'bowtie floor first': (FLOOR + WALL + AWAY, [(0, 1, 2), (0, 3, 4), (5, 6, 3)], (5, 6),
                           (1.3, -2.8, 2.6), (0.5, 0.5, 0.5)),
    'bowtie wall first': (FLOOR + WALL + AWAY, [(0, 3, 4), (0, 1, 2), (5, 6, 3)], (5, 6),
                          (1.3, -2.8, 2.6), (0.5, 0.5, 0.5)),
    'three fans': (FLOOR + WALL + [(-2, 0.3, 1.2), (-1.5, 1.8, 0.4)], [(0, 5, 6), (0, 1, 2), (0, 3, 4)],
                   (1, 2), (0.0, -3.2, 3.0), (-0.4, 0.5, 0.5)),
    'non-manifold fin': ([(0, -1, 0), (0, 1, 0), (-1.5, 0, 0), (1.5, 0, 0), (0, 0, 1.2)],
                         [(0, 1, 2), (1, 0, 3), (0, 1, 4)], (1, 2), (1.6, -2.0, 2.0), (0, 0, 0.3)),
    'flipped neighbours': ([(0, -1, 0), (0, 1, 0), (-1.5, 0, 0.3), (1.5, 0, 0.6)] + AWAY,
                           [(0, 1, 2), (0, 1, 3), (4, 5, 3)], (4, 5), (1.6, -2.5, 2.5), (0, 0, 0.3)),
    'free corner normals': (GRID, [(0, 1, 4, 3), (1, 2, 5, 4), (3, 4, 7, 6), (4, 5, 8, 7)], (1, 4),
                            (0.8, -2.2, 2.6), (0, 0, 0)),
}


def _camera(location, target, lens=30.0):
    rotation = (Vector(target) - Vector(location)).to_track_quat('-Z', 'Y').to_euler()
    scenes.camera(location, rotation, lens=lens)


def _render_both(sc, tmp_path, samples):
    sc.render.resolution_x = sc.render.resolution_y = 64
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.view_settings.view_transform = 'Standard'
    images = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        images[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
    return images['CYCLES'], images['DACRT']


def _blocks(img, n=4):
    h, w = img.shape[0] // n, img.shape[1] // n
    return img[:h * n, :w * n].mean(-1).reshape(n, h, n, w).mean(axis=(1, 3))


@pytest.mark.parametrize('case', list(CASES))
def test_joined_fans_share_cycles_vertex_normal(case, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    verts, faces, sharp, cam, target = CASES[case]
    _mesh(verts, faces, sharp, _normal_emission(), _free_normals if case.startswith('free') else None)
    _camera(cam, target)
    scenes.black_world()
    c, d = _render_both(sc, tmp_path, 16)
    mc, md = c.mean(), d.mean()
    assert abs(md / mc - 1) < 0.01, (mc, md)
    bc, bd = _blocks(c), _blocks(d)
    lit = bc > 0.25 * bc.max()              # (blocks the mesh mostly covers)
    rel = np.abs(bd[lit] / bc[lit] - 1)
    assert rel.max() < 0.04, (rel.max(), np.round(bd / np.maximum(bc, 1e-6), 3).tolist())


def test_bowtie_under_a_point_light_matches_cycles(tmp_path):
    """The report's case: a floor and a wall sharing a vertex, wall first, a point light, direct
    light only. Before: DACRT 0.10426 vs Cycles 0.09389 (1.11)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    verts, faces, sharp, cam, target = CASES['bowtie wall first']
    _mesh(verts, faces, sharp, _diffuse())
    _camera((1.6, -4.0, 3.0), (0.7, 0.5, 0.6), lens=35.0)
    scenes.black_world()
    scenes.light('POINT', 100.0, location=(1.0, -1.0, 1.0), shadow_soft_size=0.05)
    c, d = _render_both(sc, tmp_path, 64)
    assert abs(d.mean() / c.mean() - 1) < 0.02, (c.mean(), d.mean())
