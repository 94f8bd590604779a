"""Normals as Cycles reads them for every normals domain, against Cycles.

Cycles 5.0 (blender/mesh.cc create_mesh) shades a mesh whose normals domain is not Corner with
Blender's vertex normals, smooth on a triangle where the mesh's sharp_face attribute leaves its
face smooth, flat (the geometric normal) where it marks it sharp, and flat everywhere on the
Face domain when the mesh has no sharp_face attribute. Free custom normals on the Face domain
(Set Mesh Normal, Free, Face) never shade a face directly: smooth faces take the vertex normals,
their angle-weighted mean around each vertex. DACRT had shaded every Face-domain triangle flat:
the half-smooth ico sphere's 8 px blocks 0.78x Cycles, silently.

Meshes without custom normals whose every edge is marked sharp (domain Face) follow the same
rule. Each scene holds up to four spheres in one render, over a floor in a sun, 64x48, 1 bounce."""
import math
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _face_normals_mesh(name, location, sharp):
    """A bmesh ico sphere with free custom normals on its faces (each tilted toward +x), and a
    sharp_face attribute set to `sharp` (a function of the face's centre), kept even where it
    is all False: then Cycles shades every face smooth."""
    import bmesh        # importable once bpy is
    me = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=2, radius=0.7)
    bm.to_mesh(me)
    bm.free()
    centres = np.array([p.center for p in me.polygons], np.float32)
    attr = me.attributes.get('sharp_face') or me.attributes.new('sharp_face', 'BOOLEAN', 'FACE')
    attr.data.foreach_set('value', np.array([sharp(c) for c in centres], bool))
    n = centres + np.array([0.8, 0.0, 0.0], np.float32)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    me.attributes.new('custom_normal', 'FLOAT_VECTOR', 'FACE').data.foreach_set('vector', n.ravel())
    me.update()
    me.materials.append(scenes.diffuse(name, (0.7, 0.4, 0.2)))
    ob = scenes.link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def _face_domain(sc):
    scenes.custom_normal_ico('HalfUp', (-2.4, 0.6, 0.0), 'FACE', 'half', 'up')           # the report's sphere
    scenes.custom_normal_ico('HalfField', (-0.8, 0.6, 0.0), 'FACE', 'half', 'field', after=('SUBSURF',))
    _face_normals_mesh('AllSmooth', (0.8, 0.6, 0.0), lambda c: False)   # sharp_face all False
    scenes.custom_normal_ico('AllSmoothGone', (2.4, 0.6, 0.0), 'FACE', 'all', 'field', after=('TRIANGULATE',))
    return dict.fromkeys(('HalfUp', 'HalfField', 'AllSmooth', 'AllSmoothGone'), ('FACE', True))


def _other_domains(sc):
    scenes.custom_normal_ico('PointHalf', (-2.4, 0.6, 0.0), 'POINT', 'half', 'field', after=('MIRROR',))
    scenes.custom_normal_ico('CornerHalf', (-0.8, 0.6, 0.0), 'CORNER', 'half', 'field')
    _face_normals_mesh('FaceQuarter', (0.8, 0.6, 0.0), lambda c: c[0] > 0.2)
    scenes.custom_normal_ico('FaceFlat', (2.4, 0.6, 0.0), 'FACE', 'none', 'field')
    return {'PointHalf': ('POINT', True), 'CornerHalf': ('CORNER', True), 'FaceQuarter': ('FACE', True),
            'FaceFlat': ('FACE', True)}


def _sharp_edges(sc):
    """No custom normals: every edge marked sharp (Blender's domain: FACE) and the upper half's
    faces smooth: Cycles still shades those smooth, with the vertex normals."""
    import bmesh        # importable once bpy is
    for name, x, smooth in (('EdgesHalf', -1.25, lambda c: c.z > 0), ('EdgesQuarter', 1.25, lambda c: c.x > 0.2)):
        me = bpy.data.meshes.new(name)
        bm = bmesh.new()
        bmesh.ops.create_icosphere(bm, subdivisions=1, radius=1.1)
        bm.to_mesh(me)
        bm.free()
        for f in me.polygons:
            f.use_smooth = smooth(f.center)
        for e in me.edges:
            e.use_edge_sharp = True
        me.materials.append(scenes.diffuse(name, (0.7, 0.4, 0.2)))
        scenes.link(bpy.data.objects.new(name, me)).location = (x, 0.6, 0.0)
    return {'EdgesHalf': ('FACE', False), 'EdgesQuarter': ('FACE', False)}


def _scene(build):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera((0.0, -5.5, 1.8), (math.radians(74), 0, 0), lens=30)
    scenes.light('SUN', 2.0, rotation=(0.5, 0.4, 0.3), angle=0.1)
    scenes.world((0.05, 0.05, 0.05), 1.0)
    scenes.plane("Floor", 14.0, (0, 0, -0.8), materials=(scenes.diffuse("Floor", (0.7, 0.7, 0.7)),))
    domains = build(sc)
    rendering.fair_scene_settings(sc)
    return sc, domains


def _blocks(img, n=8):
    h, w = img.shape[:2]
    return img[:h - h % n, :w - w % n].reshape(h // n, n, w // n, n, -1).mean(axis=(1, 3, 4))


@pytest.mark.parametrize('build', [_face_domain, _other_domains, _sharp_edges], ids=['face', 'other', 'sharp_edges'])
def test_normals_of_every_domain_shade_as_in_cycles(tmp_path, build):
    sc, domains = _scene(build)
    dg = bpy.context.evaluated_depsgraph_get()
    for name, (domain, custom) in domains.items():
        me = bpy.data.objects[name].evaluated_get(dg).data
        assert me.has_custom_normals == custom and me.normals_domain == domain, (name, me.normals_domain)
    spec = SimpleNamespace(cycles_samples=128, dacrt_samples=128, bounces=1, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    img = {}
    for engine, setup in (('CYCLES', rendering.set_cycles), ('DACRT', rendering.set_dacrt)):
        setup(sc, spec, 0)
        img[engine] = rendering.render_combined(sc, str(tmp_path / f"{engine}.exr"))[..., :3]
    c, d = img['CYCLES'], img['DACRT']
    bc, bd = _blocks(c), _blocks(d)
    ratio = (bd + 1e-3) / (bc + 1e-3)
    print('mean C %.4f D %.4f ratio %.4f; 8 px blocks %.3f-%.3f, max diff %.4f'
          % (c.mean(), d.mean(), d.mean() / c.mean(), ratio.min(), ratio.max(), np.abs(bd - bc).max()))
    assert np.abs(bd - bc).max() < 0.006, np.array2string(ratio, precision=3)
    assert abs(d.mean() / c.mean() - 1) < 0.003, (c.mean(), d.mean())
