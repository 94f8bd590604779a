"""A normal map on a mesh without a UV map active for render: a Geometry Nodes mesh whose 'UV
Map' is stored as the corner attribute 'UVMap' (GN never flags it active for render), a text
object. Cycles 5.0 then takes no UV map at all (an image on the default UV reads one texel there,
as here) and bends the normal by mikktspace tangents of the positions mapped to a sphere
(scene/mesh.cpp MikkMeshWrapper without ATTR_STD_UV; measured: a GN grid and the same grid with
its UV map removed render alike in Cycles); those are not computed here, so the normal map is
left out, and the message now says why. It had said "the mesh has no such UV map" of a mesh that
has one (a GN grid 1.81x Cycles, the cause unreported).

Naming the map in the Normal Map node (and in a UV Map node for its image) reads that map's
tangents in both engines: the GN grid then matches Cycles."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')


def _normal_image(tmp_path):
    """A 16 x 1 Non-Color normal map tilting the normal along u by a cosine plus a bias."""
    u = (np.arange(16) + 0.5) / 16
    g = 0.5 * np.cos(2 * np.pi * u) + 0.2
    n = np.stack([-g, np.zeros_like(g), np.ones_like(g)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "tilt.png",
                                                  np.round((n + 1) / 2 * 255).astype(np.uint8)[None]))
    img.colorspace_settings.name = 'Non-Color'
    return img


def _material(tmp_path, uv_map=''):
    mat = scenes.normal_map_material("Bumpy", _normal_image(tmp_path))
    nt = mat.node_tree
    nt.nodes.remove(next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE'))
    b = nt.nodes.new('ShaderNodeBsdfPrincipled')
    b.inputs['Specular IOR Level'].default_value = 0.0
    nmap = next(n for n in nt.nodes if n.type == 'NORMAL_MAP')
    nt.links.new(nmap.outputs['Normal'], b.inputs['Normal'])
    nt.links.new(b.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    tex = next(n for n in nt.nodes if n.type == 'TEX_IMAGE')
    tex.extension = 'REPEAT'
    if uv_map:
        nmap.uv_map = uv_map
        uv = nt.nodes.new('ShaderNodeUVMap')
        uv.uv_map = uv_map
        nt.links.new(uv.outputs['UV'], tex.inputs['Vector'])
    return mat


def _gn_grid(mat):
    """A Geometry Nodes grid (2 x 2, 5 x 5 vertices) storing its UV Map output as 'UVMap'."""
    sc = bpy.context.scene
    ob = bpy.data.objects.new("GNGrid", bpy.data.meshes.new("GNGrid"))
    sc.collection.objects.link(ob)
    tree = bpy.data.node_groups.new("GNTree", 'GeometryNodeTree')
    tree.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    out = tree.nodes.new('NodeGroupOutput')
    grid = tree.nodes.new('GeometryNodeMeshGrid')
    grid.inputs['Size X'].default_value = grid.inputs['Size Y'].default_value = 2.0
    grid.inputs['Vertices X'].default_value = grid.inputs['Vertices Y'].default_value = 5
    store = tree.nodes.new('GeometryNodeStoreNamedAttribute')
    store.data_type, store.domain = 'FLOAT2', 'CORNER'
    store.inputs['Name'].default_value = 'UVMap'
    setm = tree.nodes.new('GeometryNodeSetMaterial')
    setm.inputs['Material'].default_value = mat
    tree.links.new(grid.outputs['Mesh'], store.inputs['Geometry'])
    tree.links.new(grid.outputs['UV Map'], store.inputs['Value'])
    tree.links.new(store.outputs[0], setm.inputs['Geometry'])
    tree.links.new(setm.outputs[0], out.inputs[0])
    ob.modifiers.new('GN', 'NODES').node_group = tree
    return ob


def _lit(sc):
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    scenes.world((0.2, 0.2, 0.2), 1.0)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (0.0, math.radians(55.0), 0.0)


def test_gn_mesh_unflagged_uv_map_message_names_the_cause(tmp_path, said):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    _gn_grid(_material(tmp_path))
    sc = bpy.context.scene
    _lit(sc)
    _settings(1, 0)
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "dacrt.exr", sc)
    text = ' '.join(said)
    assert "no UV map is active for render (UV map 'UVMap' exists but is not flagged" in text, said
    assert "no such UV map" not in text, said


def test_gn_mesh_with_the_map_named_matches_cycles(tmp_path, said):
    """The Normal Map node and the image's UV Map node naming 'UVMap': that map's tangents in
    both engines, 8-px blocks within 0.01 of Cycles' (the tilt moves them by 0.1-0.3)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    _gn_grid(_material(tmp_path, 'UVMap'))
    sc = bpy.context.scene
    _lit(sc)
    _settings(16, 0)
    img = _rgb(tmp_path)
    blocks = {e: v[..., 0].reshape(4, 8, 4, 8).mean((1, 3)) for e, v in img.items()}
    assert np.ptp(blocks['CYCLES']) > 0.1, "the normal map must show"
    np.testing.assert_allclose(blocks['DACRT'], blocks['CYCLES'], atol=0.01)
    assert not any("normal map" in t and "not applied" in t for t in said), said


def test_text_object_normal_map_matches_cycles(tmp_path, said):
    """A text object's mesh has its own UV map active for render ('UVMap'): the normal map is
    rendered on its tangents, as in Cycles (mean within 1%, nothing said)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    curve = bpy.data.curves.new("Label", 'FONT')
    curve.body = "HM"
    curve.size = 1.2
    ob = bpy.data.objects.new("Label", curve)
    sc.collection.objects.link(ob)
    curve.materials.append(_material(tmp_path))
    ob.location = (-0.9, -0.4, 0.0)
    _lit(sc)
    _settings(32, 0)
    img = _rgb(tmp_path)
    d, c = img['DACRT'][..., 0], img['CYCLES'][..., 0]
    np.testing.assert_allclose(d.mean(), c.mean(), rtol=0.01)
    assert not any("normal map" in t and "not applied" in t for t in said), said


def test_metaball_message_names_the_cause(tmp_path, said):
    """A metaball's mesh has no UV map: Cycles' sphere-mapped tangents, said (not applied here)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    mb = bpy.data.metaballs.new("Blob")
    mb.elements.new()
    mb.materials.append(_material(tmp_path))
    sc.collection.objects.link(bpy.data.objects.new("Blob", mb))
    _lit(sc)
    _settings(1, 0)
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "dacrt.exr", sc)
    text = ' '.join(said)
    assert "the mesh has no UV map" in text and "positions mapped to a sphere" in text, said
    assert "no such UV map" not in text, said
