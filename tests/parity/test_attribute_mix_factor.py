"""A Mix Shader whose factor reads a mesh's or strand's attribute (Attribute, Color Attribute,
Curves Info, Point Info), with no image or procedural texture on the way, against Cycles: the
attribute interpolated at each shading point, the factor's nodes run there, the two shaders
mixed by it (procedurals.compile_socket's attributes, texturedmixes._procedural_mix).

The factor had stood at its own value 0.5, said ("Mix Shader factor not computed (value from
'Attribute' node)"): a red and a blue emission mixed by a float attribute rendered
(0.492, 0, 0.492) where Cycles renders (0.550, 0, 0.440); two Diffuse BSDFs likewise; strands
mixed by Curves Info Intercept lost their root-to-tip gradient (top third 0.219 red where Cycles
has 0.346). Emission, diffuse and the transparent cut-out sides all follow the factor per point.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_curve_standard_attributes import _curves, _points, _scene as _strand_scene

pytestmark = pytest.mark.usefixtures('parity_addon')

W = 32


def _mix(nt, out, first, second):
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(first.outputs[0], mix.inputs[1])
    nt.links.new(second.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mix


def _emissions(nt):
    red, blue = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new('ShaderNodeEmission')
    red.inputs['Color'].default_value, blue.inputs['Color'].default_value = (1, 0, 0, 1), (0, 0, 1, 1)
    return red, blue


def _sides(nt, kind):
    if kind == 'diffuse':
        a, b = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeBsdfDiffuse')
        a.inputs['Color'].default_value, b.inputs['Color'].default_value = (0.9, 0.1, 0.1, 1), (0.1, 0.2, 0.9, 1)
        return a, b
    if kind == 'cutout':
        b = nt.nodes.new('ShaderNodeEmission')
        b.inputs['Color'].default_value = (0.2, 0.5, 1.0, 1)
        return nt.nodes.new('ShaderNodeBsdfTransparent'), b
    return _emissions(nt)


def _plane_scene(kind, source):
    """A subdivided plane filling an orthographic view, a float point attribute 'f' (a wave) and a
    random byte Color Attribute 'Col' on it; its material mixes two shaders (kind) by `source`:
    'attribute' (Attribute 'f' Fac) or 'color_ramp' (Color Attribute 'Col' into a Color Ramp)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    mat, nt, out = scenes._material("Mixed")
    mix = _mix(nt, out, *_sides(nt, kind))
    if source == 'attribute':
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = 'f'
        fac = a.outputs['Fac']
    else:
        a = nt.nodes.new('ShaderNodeVertexColor')
        a.layer_name = 'Col'
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].position, ramp.color_ramp.elements[1].position = 0.3, 0.6
        nt.links.new(a.outputs['Color'], ramp.inputs[0])
        fac = ramp.outputs[0]
    nt.links.new(fac, mix.inputs['Fac'])
    import bmesh        # importable once bpy is
    me = bpy.data.meshes.new("Plane")
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=5, y_segments=5, size=2.0)
    bm.to_mesh(me)
    bm.free()
    me.materials.append(mat)
    scenes.link(bpy.data.objects.new("Plane", me))
    co = np.array([v.co for v in me.vertices])
    me.attributes.new('f', 'FLOAT', 'POINT').data.foreach_set(
        'value', (0.5 + 0.5 * np.sin(2 * co[:, 0] + co[:, 1])).astype(np.float32))
    cols = np.random.default_rng(1).random((len(me.loops), 4)).astype(np.float32)
    cols[:, 3] = 1.0
    me.color_attributes.new('Col', 'BYTE_COLOR', 'CORNER').data.foreach_set('color', cols.ravel())
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    if kind == 'diffuse':
        scenes.light('SUN', 2.0)
    sc.render.resolution_x = sc.render.resolution_y = W
    sc.render.film_transparent = kind == 'cutout'
    sc.cycles.samples = sc.dacrt.samples = 8
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 1
    return sc


def _images(sc, tmp_path):
    layer = sc.view_layers[0].name
    return {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}


def _blocks(img, n=8):
    h, w = img.shape[:2]
    return img[:h - h % n, :w - w % n].reshape(h // n, n, w // n, n, -1).mean(axis=(1, 3))


CASES = [('emission', 'attribute'), ('diffuse', 'attribute'), ('cutout', 'attribute'), ('emission', 'color_ramp')]


@pytest.mark.parametrize('kind,source', CASES, ids=[f'{k}-{s}' for k, s in CASES])
def test_mesh_attribute_mix_factor_as_in_cycles(kind, source, tmp_path, said):
    img = _images(_plane_scene(kind, source), tmp_path)
    c, d = img['CYCLES'], img['DACRT']
    bc, bd = _blocks(c), _blocks(d)
    # the factor varies: its blocks span much more than the noise allowed between the engines
    assert np.ptp(bc[..., :3]) > 0.2, "the attribute must vary the mix"
    assert np.abs(bd - bc).max() < 0.02, np.abs(bd - bc).max()
    assert not [m for m in said if 'factor not computed' in m], said


def _strand_mix(node, output):
    mat = bpy.data.materials.new("StrandMix")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    mix = _mix(nt, out, *_emissions(nt))
    info = nt.nodes.new(node)
    nt.links.new(info.outputs[output], mix.inputs['Fac'])
    return mat


STRANDS = {'curves_intercept': (_curves, 'ShaderNodeHairInfo', 'Intercept'),
           'curves_random': (_curves, 'ShaderNodeHairInfo', 'Random'),
           'points_random': (_points, 'ShaderNodePointInfo', 'Random')}


@pytest.mark.parametrize('case', list(STRANDS))
def test_strand_info_mix_factor_as_in_cycles(case, tmp_path, said):
    build, node, output = STRANDS[case]
    sc = _strand_scene()
    build(_strand_mix(node, output))
    img = _images(sc, tmp_path)
    c, d = img['CYCLES'], img['DACRT']
    # thirds from root to tip, each channel: the gradient (or each strand's own mix), not a grey 0.5
    for part in np.array_split(np.arange(d.shape[0]), 3):
        for ch in (0, 2):
            np.testing.assert_allclose(d[part, :, ch].mean(), c[part, :, ch].mean(), rtol=0.03, atol=0.003,
                                       err_msg=f"{case}, rows {part[0]}-{part[-1]}, channel {ch}")
    assert abs(c[..., 0].mean() - c[..., 2].mean()) > 0.005, "the mix must vary"
    assert not [m for m in said if 'factor not computed' in m], said


def test_object_info_random_mix_factor_per_object_and_instance(tmp_path, said):
    """Object Info Random as the factor: each object and each collection instance mixes by its
    own value, as in Cycles (it had stood at 0.5 for all: (0.49, 0, 0.49) where Cycles' tiles
    range from (0.02, 0, 0.98) to (0.86, 0, 0.14))."""
    import bmesh        # importable once bpy is
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    mat, nt, out = scenes._material("ByObject")
    mix = _mix(nt, out, *_emissions(nt))
    nt.links.new(nt.nodes.new('ShaderNodeObjectInfo').outputs['Random'], mix.inputs['Fac'])
    me = bpy.data.meshes.new("Tile")
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.8)
    bm.to_mesh(me)
    bm.free()
    me.materials.append(mat)
    coll = bpy.data.collections.new("Tiles")
    coll.objects.link(bpy.data.objects.new("Tile", me))
    for i, x in enumerate((-3, -1, 1, 3)):
        scenes.link(bpy.data.objects.new(f"T{i}", me)).location = (x, 1.2, 0)
        e = scenes.link(bpy.data.objects.new(f"I{i}", None))
        e.instance_type, e.instance_collection, e.location = 'COLLECTION', coll, (x, -1.2, 0)
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=8.0)
    scenes.black_world()
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    img = _images(sc, tmp_path)
    c, d = img['CYCLES'], img['DACRT']
    # each tile's middle (4x4 pixels): one object's or instance's factor
    mids = [(r, k) for r in (8, 24) for k in (8, 24, 40, 56)]
    tc = np.array([c[r - 2:r + 2, k - 2:k + 2, :3].mean(axis=(0, 1)) for r, k in mids])
    td = np.array([d[r - 2:r + 2, k - 2:k + 2, :3].mean(axis=(0, 1)) for r, k in mids])
    assert np.ptp(tc[:, 0]) > 0.3, tc
    np.testing.assert_allclose(td, tc, atol=0.01)
    assert not [m for m in said if 'factor not computed' in m], said
