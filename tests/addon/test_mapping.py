"""Mapping nodes on image texture coordinates: the export turns a chain of Mapping nodes on the
UV map into the affine map Cycles applies (svm_mapping), checked here against the formulas
worked by hand and against Blender's own Euler matrices; the renders are compared with Cycles
in tests/parity/test_mapping.py."""
import math

import bpy
import numpy as np
import pytest
from mathutils import Euler

from addon import mapping, nodegraph
from tests.bench import fairmaterials

from . import scenes
from .test_nodegraph import _group


def _textured(name, *, source='TEX_COORD'):
    """A Diffuse material whose Image Texture reads the UV map (a Texture Coordinate 'UV' or a
    UV Map node) through the Mapping nodes the caller links; returns (material, tree, image
    node, the coordinate output socket)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image(name + "Image", np.full((2, 2, 4), 0.5, np.float32))
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    if source == 'TEX_COORD':
        coords = nt.nodes.new('ShaderNodeTexCoord').outputs['UV']
    else:
        coords = nt.nodes.new('ShaderNodeUVMap').outputs['UV']
    return mat, nt, tex, coords


def _mapping(nt, kind, loc=None, rot=None, scale=None):
    m = nt.nodes.new('ShaderNodeMapping')
    m.vector_type = kind
    for name, v in (('Location', loc), ('Rotation', rot), ('Scale', scale)):
        if v is not None:
            m.inputs[name].default_value = v
    return m


def _apply(T, u, v):
    return T @ np.array([u, v, 1.0])


def test_rotation_is_blenders_euler_xyz():
    rng = np.random.default_rng(5)
    for _ in range(20):
        e = rng.uniform(-4, 4, 3)
        assert np.allclose(mapping._rotation(e), np.array(Euler(e, 'XYZ').to_matrix()), atol=1e-6)


def test_point_mapping_worked_by_hand(dacrt_addon):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, tex, uv = _textured("Point")
    m = _mapping(nt, 'POINT', loc=(0.25, 0.5, 7.0), rot=(0, 0, math.pi / 2), scale=(2, 3, 1))
    nt.links.new(uv, m.inputs['Vector'])
    nt.links.new(m.outputs[0], tex.inputs['Vector'])
    reasons = []
    T = mapping.texture_transform(tex, reasons)
    # scale (2u, 3v), rotate 90 degrees about z: (-3v, 2u), then move by (0.25, 0.5)
    assert np.allclose(T, [[0, -3, 0.25], [2, 0, 0.5]], atol=1e-6) and reasons == []
    assert mapping.coordinates_approximation(tex) == ''


def test_texture_mapping_undoes_point_mapping(dacrt_addon):
    """Texture is Point's inverse (same inputs); a chain of the two maps the UV map to itself.
    A zero scale component maps that axis to 0 (Cycles' safe_divide)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, tex, uv = _textured("Inverse", source='UVMAP')
    args = dict(loc=(0.3, -0.2, 0.1), rot=(0.4, -0.3, 1.1), scale=(1.5, 0.5, 2.0))
    p, t = _mapping(nt, 'POINT', **args), _mapping(nt, 'TEXTURE', **args)
    nt.links.new(uv, p.inputs['Vector'])
    nt.links.new(p.outputs[0], t.inputs['Vector'])
    nt.links.new(t.outputs[0], tex.inputs['Vector'])
    T = mapping.texture_transform(tex, [])
    assert T is None or np.allclose(T, [[1, 0, 0], [0, 1, 0]], atol=1e-6)
    nt.links.new(uv, t.inputs['Vector'])               # Texture alone: R^T (v - l) / s
    T = mapping.texture_transform(tex, [])
    R = np.array(Euler(args['rot'], 'XYZ').to_matrix())
    for u, v in ((0.0, 0.0), (1.0, 0.0), (0.3, 0.8)):
        want = (R.T @ (np.array([u, v, 0.0]) - args['loc'])) / args['scale']
        assert np.allclose(_apply(T, u, v), want[:2], atol=1e-6)
    t.inputs['Scale'].default_value = (0.0, 2.0, 1.0)
    T = mapping.texture_transform(tex, [])
    assert np.allclose(T[0], 0.0) and not np.allclose(T[1], 0.0)


def test_vector_type_ignores_location_and_unlinked_vector_is_a_point(dacrt_addon):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, tex, uv = _textured("Vector")
    m = _mapping(nt, 'VECTOR', rot=(0, 0, math.pi), scale=(2, 2, 2))
    nt.links.new(uv, m.inputs['Vector'])
    nt.links.new(m.outputs[0], tex.inputs['Vector'])
    assert np.allclose(mapping.texture_transform(tex, []), [[-2, 0, 0], [0, -2, 0]], atol=1e-6)
    # a Mapping with nothing in its Vector input maps its own constant vector (Cycles renders
    # one texel everywhere; tests/parity/test_mapping.py)
    p = _mapping(nt, 'POINT', loc=(0.5, 0.25, 0))
    p.inputs['Vector'].default_value = (0.1, 0.2, 0.0)
    nt.links.new(p.outputs[0], tex.inputs['Vector'])
    assert np.allclose(mapping.texture_transform(tex, []), [[0, 0, 0.6], [0, 0, 0.45]], atol=1e-6)


def test_mapping_inside_a_group_and_unsupported_sources(dacrt_addon):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, tex, uv = _textured("Grouped")
    g, gi, go = _group("Tile", inputs=(('UV', 'NodeSocketVector'),), outputs=(('Vector', 'NodeSocketVector'),))
    m = g.nodes.new('ShaderNodeMapping')
    m.inputs['Scale'].default_value = (4, 4, 1)
    g.links.new(gi.outputs['UV'], m.inputs['Vector'])
    g.links.new(m.outputs[0], go.inputs['Vector'])
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = g
    nt.links.new(uv, node.inputs['UV'])
    nt.links.new(node.outputs['Vector'], tex.inputs['Vector'])
    reasons = []
    assert np.allclose(mapping.texture_transform(tex, reasons), [[4, 0, 0], [0, 4, 0]]) and reasons == []
    gen = nt.nodes.new('ShaderNodeTexCoord').outputs['Generated']
    nt.links.new(gen, node.inputs['UV'])                 # Generated coordinates: reported
    reasons = []
    assert np.allclose(mapping.texture_transform(tex, reasons), [[4, 0, 0], [0, 4, 0]])
    assert reasons == ["Generated texture coordinates read as the UV map"]
    coords = nt.nodes.new('ShaderNodeTexCoord')          # UV from the instancer: reported
    coords.from_instancer = True
    nt.links.new(coords.outputs['UV'], node.inputs['UV'])
    reasons = []
    mapping.texture_transform(tex, reasons)
    assert reasons == [f"UV coordinates from the instancer ('{coords.name}') read as the object's own"]
    m.vector_type = 'NORMAL'
    assert "Normal read without its normalisation" in mapping.coordinates_approximation(tex)


def test_export_keeps_the_transform_and_the_fair_editor_keeps_the_mapping(scene, exported):
    scenes.camera((0, 0, 5), (0, 0, 0))
    mat, nt, tex, uv = _textured("Tiled")
    m = _mapping(nt, 'POINT', scale=(3, 2, 1))
    nt.links.new(uv, m.inputs['Vector'])
    nt.links.new(m.outputs[0], tex.inputs['Vector'])
    scenes.plane("P", materials=(mat,)).data.uv_layers.new(name="UVMap")
    data = exported()
    got = data.materials[data.geometry.material[0]]
    assert got.name == "Tiled" and not got.approximated
    assert np.allclose(got.texture_transform, [[3, 0, 0], [0, 2, 0]])
    assert "Tiled" not in fairmaterials.make_diffuse([mat]) and tex.inputs["Vector"].is_linked


def test_mapping_inputs_driven_by_constant_nodes(dacrt_addon):
    """A Value node on Scale (one number tiling both ways), an RGB node on Location and a Math
    node on Rotation are constants Cycles computes: read exactly, as (v, v, v) for the Value. A
    Noise Texture on Scale is not: reported, and the socket's own value used."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, tex, uv = _textured("Driven")
    m = _mapping(nt, 'POINT', loc=(9, 9, 9), rot=(1, 1, 1), scale=(7, 7, 7))
    nt.links.new(uv, m.inputs['Vector'])
    nt.links.new(m.outputs[0], tex.inputs['Vector'])
    value = nt.nodes.new('ShaderNodeValue')
    value.outputs[0].default_value = 3.0
    nt.links.new(value.outputs[0], m.inputs['Scale'])
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.25, 0.5, 0.0, 1.0)
    nt.links.new(rgb.outputs[0], m.inputs['Location'])
    angle = nt.nodes.new('ShaderNodeMath')
    angle.operation = 'MULTIPLY'
    angle.inputs[0].default_value, angle.inputs[1].default_value = 0.25, math.pi
    nt.links.new(angle.outputs[0], m.inputs['Rotation'])
    reasons = []
    T = mapping.texture_transform(tex, reasons)
    assert reasons == []
    R = np.array(Euler((math.pi / 4,) * 3, 'XYZ').to_matrix())
    for u, v in ((0.0, 0.0), (1.0, 0.0), (0.3, 0.8)):
        want = R @ (3.0 * np.array([u, v, 0.0])) + np.array([0.25, 0.5, 0.0])
        assert np.allclose(_apply(T, u, v), want[:2], atol=1e-12)
    noise = nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(noise.outputs['Fac'], m.inputs['Scale'])
    reasons = []
    T = mapping.texture_transform(tex, reasons)
    assert reasons == ["Mapping Scale driven by nodes; its own value used"]
    want = R @ (7.0 * np.array([1.0, 0.0, 0.0])) + np.array([0.25, 0.5, 0.0])
    assert np.allclose(_apply(T, 1.0, 0.0), want[:2], atol=1e-12)


def test_an_unlinked_group_input_is_a_constant_point(dacrt_addon):
    """An Image Texture inside a group whose Vector comes from the Group Input, the Group node's
    Vector left at its value: Cycles reads that one point (one texel everywhere), not the UV
    map an unlinked Vector means (read as the UV map: 0.40/2.43/0.77x Cycles' mean)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    g, gi, go = _group("Lookup", inputs=(('Vector', 'NodeSocketVector'),), outputs=(('Color', 'NodeSocketColor'),))
    inner = g.nodes.new('ShaderNodeTexImage')
    g.links.new(gi.outputs['Vector'], inner.inputs['Vector'])
    g.links.new(inner.outputs['Color'], go.inputs['Color'])
    mat, nt, out = scenes._material("Group vector")
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = g
    node.inputs['Vector'].default_value = (0.3, 0.6, 0.0)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(node.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    tex = nodegraph.linked_node(node.outputs['Color'].links[0].to_socket)   # as the export reaches it
    assert tex.node == inner and tex.groups[0] == node
    reasons = []
    assert np.allclose(mapping.texture_transform(tex, reasons), [[0, 0, 0.3], [0, 0, 0.6]]) and reasons == []
    unlinked = nt.nodes.new('ShaderNodeTexImage')        # the image's own Vector unlinked: the UV map
    assert mapping.texture_transform(unlinked, reasons) is None and reasons == []
    # ... unless the group's Vector input has Hide Value: it has no value, and the image inside
    # reads its UV map (Cycles: the same image as outside the group; the texel at (0.3, 0.6)
    # everywhere had been 0.86 off in places)
    g.interface.items_tree['Vector'].hide_value = True
    assert node.inputs['Vector'].hide_value
    assert mapping.texture_transform(tex, reasons) is None and reasons == []


@pytest.mark.parametrize('kind', ['POINT', 'TEXTURE', 'VECTOR'])
def test_a_texture_nodes_own_mapping_is_applied_first(dacrt_addon, kind):
    """node.texture_mapping (the sidebar's Texture Mapping panel): Cycles' compute_transform,
    the axis remap, then loc x rot x scale (inverted for Texture, no location for Vector),
    against mathutils; an image's UV transform and a procedural's coordinates take it before
    their Vector chain (Cycles 5.0, an image and a checker scaled (2.5, 1.5), moved (0.3, 0.2),
    turned 0.4 and X/Y swapped: within 0.004 per 8x8 block; ignored before, up to 0.52 off)."""
    from mathutils import Matrix
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, out = scenes._material("Own mapping")
    tex = nt.nodes.new('ShaderNodeTexImage')
    reasons = []
    assert mapping.node_texture_mapping(tex, reasons) is None and mapping.texture_transform(tex, reasons) is None
    tm = tex.texture_mapping
    tm.vector_type, tm.translation, tm.rotation, tm.scale = kind, (0.3, 0.2, 0.1), (0.1, -0.2, 0.4), (2.5, 1.5, 0.5)
    tm.mapping_x, tm.mapping_y, tm.mapping_z = 'Y', 'X', 'NONE'
    M, t = mapping.node_texture_mapping(tex, reasons)
    remap = np.array([[0, 1, 0], [1, 0, 0], [0, 0, 0]], np.float64)
    full = np.array(Matrix.LocRotScale((0.3, 0.2, 0.1) if kind != 'VECTOR' else (0, 0, 0),
                                       Euler((0.1, -0.2, 0.4), 'XYZ'), (2.5, 1.5, 0.5)))
    if kind == 'TEXTURE':
        full = np.linalg.inv(full)
    np.testing.assert_allclose(M, full[:3, :3] @ remap, atol=1e-6)       # (mathutils: float32)
    np.testing.assert_allclose(t, full[:3, 3], atol=1e-6)
    uv = np.array([0.25, 0.7, 1.0])                   # (u, v, 1): the image reads M (u, v, 0) + t
    T = mapping.texture_transform(tex, reasons)
    np.testing.assert_allclose(T @ uv, (M @ np.array([0.25, 0.7, 0.0]) + t)[:2], atol=1e-9)
    assert reasons == []
    tm.use_min = True                 # Cycles does not read min/max (get_tex_mapping): silent
    mapping.node_texture_mapping(tex, reasons)
    assert reasons == []
