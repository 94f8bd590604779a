"""Bump nodes and a Displacement output read as bump, against Cycles (svm_node_set_bump): the
height's gradient bends the shading normal per point, so a plane under a sun at a grazing angle
shows the relief as bands of light and shade. Before, a Bump node with a linked Height was
reported as ignored and a Displacement output was not read: the surfaces rendered flat.

Heights smooth at the pixel scale (DACRT takes the limit of Cycles' finite differences over the
pixel footprint): image means and 4x4-pixel block means within noise of Cycles', the bent
normals (the Normal pass) within 0.01."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _bumped(name, height_node, out_socket, strength=1.0, distance=1.0, invert=False, displacement=None):
    """A Diffuse BSDF (0.8) whose Normal is a Bump node of the given height (height_node(nt) ->
    the node; out_socket its output), or with displacement=(midlevel, scale) a Displacement
    node of that height into the Material Output (Bump Only)."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    h = height_node(nt)
    if displacement is not None:
        disp = nt.nodes.new('ShaderNodeDisplacement')
        disp.inputs['Midlevel'].default_value, disp.inputs['Scale'].default_value = displacement
        nt.links.new(h.outputs[out_socket], disp.inputs['Height'])
        nt.links.new(disp.outputs[0], out.inputs['Displacement'])
        mat.displacement_method = 'BUMP'
        return mat
    bump = nt.nodes.new('ShaderNodeBump')
    bump.inputs['Strength'].default_value = strength
    bump.inputs['Distance'].default_value = distance
    bump.invert = invert
    nt.links.new(h.outputs[out_socket], bump.inputs['Height'])
    nt.links.new(bump.outputs['Normal'], d.inputs['Normal'])
    return mat


def _wave(scale=0.6, direction='X'):
    def make(nt):
        w = nt.nodes.new('ShaderNodeTexWave')
        w.wave_type, w.bands_direction, w.wave_profile = 'BANDS', direction, 'SIN'
        w.inputs['Scale'].default_value = scale
        w.inputs['Distortion'].default_value = 0.0
        return w
    return make


def _render(sc, tmp_path, normals=True):
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = normals
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1).mean(-1) for e, exr in exrs.items()}
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()} \
        if normals else None
    return img, nrm


def _inside(hit, k=2):
    """hit without its pixels within k of a miss (the plane's edge mixes it with the background)."""
    keep = hit.copy()
    for dy in range(-k, k + 1):
        for dx in range(-k, k + 1):
            keep &= np.roll(np.roll(hit, dy, axis=0), dx, axis=1)
    return keep


def _blocks(a, k=4):
    h, w = a.shape[0] // k * k, a.shape[1] // k * k
    return a[:h, :w].reshape(h // k, k, w // k, k).mean(axis=(1, 3))


def _plane_scene(make_mat, samples=16, size=4.0):
    """A plane (size x size, its UVs u along +x) of the material make_mat() seen from above, lit by
    a sun 20 degrees above it from +x."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat = make_mat()
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=size * 0.95)
    bpy.ops.mesh.primitive_plane_add(size=size)             # UVs: u along +x
    bpy.context.active_object.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (0.0, math.radians(70.0), 0.0)      # from +x, 20 degrees above the plane
    sc.cycles.samples = sc.dacrt.samples = samples
    return sc


def _compare(img, nrm, rtol_mean=0.01, rtol_block=0.03, normal_atol=0.01, hit=None):
    d, c = img['DACRT'], img['CYCLES']
    if hit is None:
        hit = np.ones(d.shape, bool)
    dm, cm = d[hit].mean(), c[hit].mean()
    np.testing.assert_allclose(dm, cm, rtol=rtol_mean)
    bd, bc, bh = _blocks(d), _blocks(c), _blocks(hit.astype(float)) == 1.0
    scale = max(float(bc[bh].mean()), 1e-6)
    err = np.abs(bd - bc)[bh] / scale
    assert err.mean() < rtol_block, f"block means differ from Cycles' by {err.mean():.3%} on average"
    if nrm is not None:
        dn, cn = nrm['DACRT'][hit], nrm['CYCLES'][hit]
        assert np.abs(dn - cn).max(-1).mean() < normal_atol, \
            f"bent normals differ from Cycles' by {np.abs(dn - cn).max(-1).mean():.4f} on average"
    return dm, cm


@pytest.mark.parametrize('strength,invert', [(1.0, False), (0.5, False), (1.0, True)])
def test_a_wave_bump_under_a_grazing_sun_matches_cycles(strength, invert, tmp_path):
    """Sine bands along x (a Wave texture on Generated coordinates): the slopes facing the sun
    light up, the others fall dark; strength 0.5 mixes half the flat normal back in; Invert
    swaps the lit and the dark slopes."""
    img, nrm = _render(_plane_scene(lambda: _bumped("Waves", _wave(), 'Fac', strength=strength, distance=0.4,
                                                    invert=invert)), tmp_path)
    _compare(img, nrm)
    c = img['CYCLES']
    assert c.max() > 1.5 * c.min(), "the relief must show"


def _noise(scale=1.5, detail=0.0, coordinate=None):
    def make(nt):
        n = nt.nodes.new('ShaderNodeTexNoise')
        n.inputs['Scale'].default_value = scale
        n.inputs['Detail'].default_value = detail
        if coordinate is not None:
            nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs[coordinate], n.inputs['Vector'])
        return n
    return make


@pytest.mark.parametrize('coordinate', [None, 'Object'])
def test_a_noise_bump_on_a_smooth_sphere_matches_cycles(coordinate, tmp_path):
    """A Noise height (Generated, or Object coordinates) on a smooth UV sphere under a sun from
    the side: the gradient taken in the plane of each point's interpolated normal."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat = _bumped("Noisy", _noise(coordinate=coordinate), 'Fac', distance=0.5)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    sc.render.film_transparent = True
    scenes.camera(location=(0, -5, 0), rotation=(np.pi / 2, 0, 0), kind='ORTHO', ortho_scale=2.2)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0)
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(60.0), 0.0, math.radians(40.0))
    sc.cycles.samples = sc.dacrt.samples = 16
    img, nrm = _render(sc, tmp_path)
    hit = (np.abs(nrm['CYCLES']).sum(-1) > 0.5) & (np.abs(nrm['DACRT']).sum(-1) > 0.5)
    # (the sphere's silhouette pixels mix sphere and background differently: interior blocks)
    inner = np.zeros_like(hit)
    inner[8:40, 8:40] = True
    _compare(img, nrm, rtol_mean=0.01, rtol_block=0.03, hit=hit & inner)


def test_an_image_height_map_on_uv_matches_cycles(tmp_path):
    """A float height image (8 x 8 smooth bumps, bilinear) read on the plane's UV map: the
    gradient of the blend, each texel's slope."""
    def make():
        yy, xx = np.mgrid[0:8, 0:8] + 0.5
        h = 0.5 + 0.5 * np.sin(xx * np.pi / 4) * np.cos(yy * np.pi / 4)
        img = scenes.float_image("Height", np.repeat(h[..., None], 4, axis=-1).astype(np.float32))
        img.colorspace_settings.name = 'Non-Color'

        def tex(nt):
            t = nt.nodes.new('ShaderNodeTexImage')
            t.image, t.interpolation, t.extension = img, 'Linear', 'REPEAT'
            return t
        return _bumped("Heights", tex, 'Color', distance=0.15)
    img, nrm = _render(_plane_scene(make), tmp_path)
    _compare(img, nrm, rtol_block=0.04, normal_atol=0.015)


@pytest.mark.parametrize('space,scale,rotated', [('OBJECT', 1.0, False), ('OBJECT', (1.0, 1.0, 3.0), True),
                                                  ('OBJECT', (0.7, 1.5, 2.5), True), ('WORLD', (2.0, 1.0, 1.0), True)])
def test_a_displacement_output_read_as_bump_matches_cycles(space, scale, rotated, tmp_path):
    """Material Output > Displacement from a Displacement node (Bump Only): the shader's normal
    bent by the height (height - midlevel) x scale, in object space times the object's scale
    along the normal (|M^T N|: a plane scaled 3 along its normal bumps 3x as deep), on planes
    scaled non-uniformly and rotated; and a Bump node on such a plane (world-space gradient of
    a height on Generated coordinates). Gentle bands: on steep ones Cycles' own forward
    differences (a tenth of a pixel apart) bend some 0.02 off the limit."""
    def make():
        mat = _bumped("Displaced", _wave(scale=0.35), "Fac", displacement=(0.5, 0.2))
        next(n for n in mat.node_tree.nodes if n.type == 'DISPLACEMENT').space = space
        return mat
    for build in (make, lambda: _bumped("Waves", _wave(scale=0.35), "Fac", distance=0.2)):
        sc = _plane_scene(build, size=2.0)
        plane = next(o for o in sc.objects if o.type == 'MESH')
        plane.scale = (scale,) * 3 if np.isscalar(scale) else scale
        if rotated:
            plane.rotation_euler = (0.3, 0.0, 0.5)
        sc.camera.data.ortho_scale = 3.6
        img, nrm = _render(sc, tmp_path)
        hit = _inside(np.abs(nrm['CYCLES']).sum(-1) > 0.5)
        _compare(img, nrm, rtol_block=0.03, hit=hit)
        assert img['CYCLES'][hit].max() > 1.5 * img['CYCLES'][hit].min()


def test_displacement_and_bump_bumps_in_object_space(tmp_path):
    """Displacement and Bump: Cycles bumps in object space (bump_from_displacement), on a plane
    scaled 2 the gradient twice as steep again; its true displacement (which moves the vertices,
    reported) is left out, so only a unit or uniform scale is compared."""
    def make():
        mat = _bumped("Both", _wave(), 'Fac', displacement=(0.5, 0.2))
        mat.displacement_method = 'BOTH'
        return mat
    sc = _plane_scene(make, size=2.0)
    next(o for o in sc.objects if o.type == 'MESH').scale = (2.0, 2.0, 2.0)
    img, nrm = _render(sc, tmp_path)
    _compare(img, nrm)


def test_chained_bumps_and_a_normal_map_under_a_bump_match_cycles(tmp_path):
    """A Bump's Normal fed by another Bump (bands along x, then along y), and by a tangent-space
    Normal Map of an image (a tilt toward the sun, +x): each bump bends the normal it is given, in turn."""
    def chained():
        mat = _bumped("Chained", _wave(direction='Y', scale=0.5), 'Fac', distance=0.3)
        nt = mat.node_tree
        outer = next(n for n in nt.nodes if n.type == 'BUMP')
        inner = nt.nodes.new('ShaderNodeBump')
        inner.inputs['Distance'].default_value = 0.4
        nt.links.new(_wave()(nt).outputs['Fac'], inner.inputs['Height'])
        nt.links.new(inner.outputs['Normal'], outer.inputs['Normal'])
        return mat

    def mapped():
        mat = _bumped("Mapped", _wave(), 'Fac', distance=0.3)
        nt = mat.node_tree
        img = bpy.data.images.load(scenes.write_image(tmp_path / "tilt.png", np.array([[[170, 128, 242]]], np.uint8)))
        img.colorspace_settings.name = 'Non-Color'
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = img
        nmap = nt.nodes.new('ShaderNodeNormalMap')
        nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
        nt.links.new(nmap.outputs['Normal'], next(n for n in nt.nodes if n.type == 'BUMP').inputs['Normal'])
        return mat
    for make in (chained, mapped):
        img, nrm = _render(_plane_scene(make), tmp_path)
        _compare(img, nrm)


def test_what_is_not_rendered_is_said(said, tmp_path):
    """A height the export cannot follow per point (Geometry Tangent), and true
    displacement, stay flat and are reported, as are two BSDFs bumped apart (one bump for the
    material, as one normal map); a rendered bump says nothing."""
    def make(which):
        def material():
            if which == 'rendered':
                return _bumped("Waves", _wave(), 'Fac', distance=0.4)
            if which == 'camera':
                def noise(nt):
                    n = _noise()(nt)
                    nt.links.new(nt.nodes.new('ShaderNodeNewGeometry').outputs['Tangent'], n.inputs['Vector'])
                    return n
                return _bumped("Camera", noise, 'Fac', distance=0.4)
            if which == 'two':            # a Mix of two Diffuse BSDFs bumped apart
                mat = _bumped("Two", _wave(), 'Fac', distance=0.4)
                nt = mat.node_tree
                out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
                first = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
                second = nt.nodes.new('ShaderNodeBsdfDiffuse')
                bump = nt.nodes.new('ShaderNodeBump')
                nt.links.new(_noise()(nt).outputs['Fac'], bump.inputs['Height'])
                nt.links.new(bump.outputs['Normal'], second.inputs['Normal'])
                mix = nt.nodes.new('ShaderNodeMixShader')
                nt.links.new(first.outputs[0], mix.inputs[1])
                nt.links.new(second.outputs[0], mix.inputs[2])
                nt.links.new(mix.outputs[0], out.inputs['Surface'])
                return mat
            mat = _bumped("True", _wave(), 'Fac', displacement=(0.5, 0.4))
            mat.displacement_method = 'DISPLACEMENT'
            return mat
        return material
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    for which in ('rendered', 'camera', 'two', 'true'):
        said.clear()
        sc = _plane_scene(make(which), samples=1)
        sc.render.engine = 'DACRT'
        scenes.render_rgba(sc)
        text = ' '.join(said)
        if which == 'rendered':
            assert 'Bump' not in text and 'ignored' not in text, text
        elif which == 'camera':
            assert "Bump node 'Bump' not rendered (Geometry Tangent is not read per point)" in text, text
        elif which == 'two':
            assert "BSDFs with different Bump nodes; the first one's for all" in text, text
        else:
            assert "displacement ignored (true displacement" in text, text


def test_a_bump_under_a_white_world_with_bounces_matches_cycles(tmp_path):
    """A white world lights the bumped plane through light samples and BSDF rays alike (MIS),
    both taking the bump shadowing of the bent normal, and a bounce off a bumped wall: image
    within 1% of Cycles (64 spp)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 24
    scenes.camera(location=(0, -4, 3), rotation=(math.radians(55), 0, 0), lens=30.0)
    mat = _bumped("Waves", _wave(scale=0.5), 'Fac', distance=0.5)
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    bpy.context.active_object.data.materials.append(mat)
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 2, 2), rotation=(math.pi / 2, 0, 0))
    bpy.context.active_object.data.materials.append(mat)
    scenes.world((1.0, 1.0, 1.0), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 2
    layer = sc.view_layers[0].name
    img = {e: exr[f"{layer}.Combined.R"] for e, exr in scenes.render_engines(sc, tmp_path).items()}
    np.testing.assert_allclose(img['DACRT'].mean(), img['CYCLES'].mean(), rtol=0.01)
    np.testing.assert_allclose(_blocks(img['DACRT'], 6), _blocks(img['CYCLES'], 6), rtol=0.04)


def test_a_small_bumped_object_in_a_large_scene_matches_cycles(tmp_path):
    """A 10 cm sphere with a fine Noise height near a perspective camera, over a ground 2 km
    wide: the difference step follows the pixel footprint at the sphere (a share of the
    scene's extent would span the sphere's bumps)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat = _bumped("Fine", _noise(scale=40.0, coordinate='Object'), 'Fac', distance=0.004)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera(location=(0, -0.5, 0), rotation=(np.pi / 2, 0, 0), lens=50.0)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.1)
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    scenes.plane("Ground", size=2000.0, location=(0, 0, -0.2))
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(60.0), 0.0, math.radians(40.0))
    sc.cycles.samples = sc.dacrt.samples = 16
    img, nrm = _render(sc, tmp_path)
    on = _inside((np.abs(nrm['CYCLES'] - np.array([0.0, 0.0, 1.0])).sum(-1) > 0.05) &
                 (np.abs(nrm['CYCLES']).sum(-1) > 0.5), 1)
    assert on.sum() > 200
    _compare(img, nrm, hit=on)


@pytest.mark.parametrize('source', ['Geometry', 'Texture Coordinate'])
def test_a_colour_from_the_normal_under_a_displacement_bump_matches_cycles(source, tmp_path):
    """Cycles sets the Displacement output's bump as the shader's N before the surface's nodes
    run: a colour from Geometry Normal or Texture Coordinate Normal reads the bent normal (on a
    rotated plane: the object-space one turned back)."""
    def make():
        mat = _bumped("Tinted", _wave(), 'Fac', displacement=(0.5, 0.4))
        nt = mat.node_tree
        node = nt.nodes.new('ShaderNodeNewGeometry' if source == 'Geometry' else 'ShaderNodeTexCoord')
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(node.outputs['Normal'], sep.inputs[0])
        ma = nt.nodes.new('ShaderNodeMath')
        ma.operation = 'MULTIPLY_ADD'
        ma.inputs[1].default_value = ma.inputs[2].default_value = 0.5
        nt.links.new(sep.outputs['X'], ma.inputs[0])
        nt.links.new(ma.outputs[0], next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE').inputs['Color'])
        return mat
    sc = _plane_scene(make)
    next(o for o in sc.objects if o.type == 'MESH').rotation_euler = (0.0, 0.0, 0.4)
    img, nrm = _render(sc, tmp_path)
    hit = _inside(np.abs(nrm['CYCLES']).sum(-1) > 0.5)
    _compare(img, nrm, hit=hit)
