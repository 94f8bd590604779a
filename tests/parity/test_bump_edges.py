"""Bump edge cases against Cycles: back faces, see-through surfaces and the passes, far-side
light of translucent surfaces, points and curves, the Filter Width (tests/parity/test_bump.py
holds the base cases and the helpers)."""
import math

import bpy
import numpy as np
import pytest

from tests.parity.test_bump import _bumped, _compare, _plane_scene, _wave

pytestmark = pytest.mark.usefixtures('parity_addon')


def _wave_on(coordinate):
    def make(nt):
        w = _wave()(nt)
        if coordinate is not None:
            nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs[coordinate], w.inputs['Vector'])
        return w
    return make


@pytest.mark.parametrize('case', ['below', 'mirrored', 'displacement mirrored', 'object coordinates below'])
def test_a_bump_seen_from_behind_matches_cycles(case, tmp_path):
    """On a back face Cycles' taps of interpolated attributes (Generated, UV) move opposite to
    the position's, so a Generated relief seen from behind is the front's negated (a bump is a
    dent from there), while an Object-coordinate relief keeps its shape mirrored in N. A plane
    seen from below under a sun 20 degrees below it, and one scaled (1, 1, -1) seen from above.
    Before: Generated bands 0.2498 vs Cycles 0.2704, 4x4 blocks 153% off, lit and dark slopes
    swapped."""
    coordinate = 'Object' if 'object' in case else None
    distance = 0.1 if coordinate else 0.4        # (Object coordinates span 4x Generated's: as steep)
    if case.startswith('displacement'):
        def make():
            return _bumped("Disp", _wave_on(coordinate), 'Fac', displacement=(0.5, 0.3))
    else:
        def make():
            return _bumped("Waves", _wave_on(coordinate), 'Fac', distance=distance)
    sc = _plane_scene(make)
    plane = next(o for o in sc.objects if o.type == 'MESH')
    if 'below' in case:
        sc.camera.location, sc.camera.rotation_euler = (0, 0, -5), (math.pi, 0, 0)
        sun = next(o for o in sc.objects if o.type == 'LIGHT')
        sun.rotation_euler = (0.0, math.radians(110.0), 0.0)
    else:
        plane.scale = (1, 1, -1)
    img, nrm = _render(sc, tmp_path)
    # (Cycles' Object-coordinate normals seen from behind lean 0.017 along y: its differentials)
    _compare(img, nrm, normal_atol=0.02 if coordinate else 0.01)
    c = img['CYCLES']
    assert c.max() > 1.5 * c.min(), "the relief must show"


def _passes(sc, tmp_path, names):
    from tests.addon import scenes
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = True
    sc.view_layers[0].cycles.denoising_store_passes = 'Denoising Normal' in names
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    return {n: {e: np.stack([exr[f"{layer}.{n}.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
            for n in names}


@pytest.mark.parametrize('case', ['alpha 0.8', 'unrelated clear cube'])
def test_the_normal_passes_of_a_bump_with_see_through_surfaces_match_cycles(case, tmp_path):
    """The Normal and Denoising Normal passes of a bumped plane take the bent normal when the scene
    has see-through surfaces too (their data passes go another way), averaged as Cycles averages
    the closures' (the transparent closure's is the unbent N): a Principled of Alpha 0.8 and
    Base Color 0.8 weighs the bent 0.64 and the flat 0.2. Before: flat wherever a transparent
    surface was in the scene, (0, 0, 1) vs Cycles' (-0.0114, 0, 0.9526) for Alpha 0.8, blocks
    26% off; (0, 0, 1) vs (-0.0148, 0, 0.9197) over a whole opaque plane beside an alpha-0 cube."""
    names = ('Normal', 'Denoising Normal')

    def make():
        if case == 'alpha 0.8':
            mat = _bumped("P", _wave(), 'Fac', distance=0.4)
            nt = mat.node_tree
            p = nt.nodes.new('ShaderNodeBsdfPrincipled')
            p.inputs['Base Color'].default_value = (0.8, 0.8, 0.8, 1.0)
            p.inputs['Alpha'].default_value = 0.8
            p.inputs['Roughness'].default_value = 1.0
            p.inputs['Specular IOR Level'].default_value = 0.0
            d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
            bump = next(n for n in nt.nodes if n.type == 'BUMP')
            nt.links.new(bump.outputs['Normal'], p.inputs['Normal'])
            nt.links.new(p.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
            nt.nodes.remove(d)
            return mat
        return _bumped("Waves", _wave(), 'Fac', distance=0.4)
    sc = _plane_scene(make)
    if case == 'alpha 0.8':
        sc.render.film_transparent = True
    else:
        bpy.ops.mesh.primitive_cube_add(size=0.3, location=(1.6, 1.6, 0.5))
        clear = bpy.data.materials.new("clear")
        clear.node_tree.nodes['Principled BSDF'].inputs['Alpha'].default_value = 0.0
        bpy.context.active_object.data.materials.append(clear)
    out = _passes(sc, tmp_path, names)
    for name in names:
        d, c = out[name]['DACRT'], out[name]['CYCLES']
        far = np.ones(d.shape[:2], bool)
        far[:12, -12:] = far[-12:, -12:] = False           # (away from the cube, whichever way up)
        diff = np.abs(d - c).max(-1)[far].mean()
        assert diff < 0.01, f"{name}: {diff:.4f} off Cycles' on average"
        assert np.abs(c[far][:, 0]).mean() > 0.05, "the bend must show"


def _translucent(kind, distance):
    """A bumped Translucent BSDF (0.8), or a leaf: Mix of Diffuse and Translucent (0.8), both bent."""
    def make():
        mat = _bumped("T", _wave(), 'Fac', distance=distance)
        nt = mat.node_tree
        out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
        d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
        bump = next(n for n in nt.nodes if n.type == 'BUMP')
        t = nt.nodes.new('ShaderNodeBsdfTranslucent')
        t.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
        nt.links.new(bump.outputs['Normal'], t.inputs['Normal'])
        if kind == 'translucent':
            nt.links.new(t.outputs[0], out.inputs['Surface'])
            nt.nodes.remove(d)
        else:
            mix = nt.nodes.new('ShaderNodeMixShader')
            nt.links.new(d.outputs[0], mix.inputs[1])
            nt.links.new(t.outputs[0], mix.inputs[2])
            nt.links.new(mix.outputs[0], out.inputs['Surface'])
        return mat
    return make


@pytest.mark.parametrize('kind,distance,light', [('translucent', 1.0, 'sun'), ('leaf', 0.6, 'sun'),
                                                 ('translucent', 1.0, 'area'), ('translucent', 1.0, 'world')])
def test_a_back_lit_bumped_translucent_surface_matches_cycles(kind, distance, light, tmp_path):
    """Cycles takes the bump shadowing term of the Translucent BSDF's light samples, from the
    far side, as of any diffuse closure's (measured: not on its BSDF-sampled bounces, which the
    white world, lit by BSDF rays alone here, checks); its Normal pass averages the closures'
    normals, the Translucent one's raised until its mirror reflection clears the surface. A sun
    20 degrees below the plane seen from above, an area light below it (light samples and BSDF
    rays, two bounces) or a white world. Before: Translucent at distance 1.0 under the sun 0.3388
    vs Cycles 0.2947 (15% bright), Normal.z 0.714 vs 0.777; the leaf at 0.6 0.1563 vs 0.1429;
    the area light 1.5664 vs 1.5161."""
    sc = _plane_scene(_translucent(kind, distance))
    sun = next(o for o in sc.objects if o.type == 'LIGHT')
    sun.rotation_euler = (0.0, math.radians(110.0), 0.0)
    if light != 'sun':
        bpy.data.objects.remove(sun)
    if light == 'area':
        bpy.ops.object.light_add(type='AREA', location=(1.0, 0, -1.0), rotation=(math.pi - 0.5, 0, 0))
        bpy.context.active_object.data.energy = 200.0
        bpy.context.active_object.data.size = 3.0
    elif light == 'world':
        from tests.addon import scenes
        scenes.world((1.0, 1.0, 1.0), scene=sc)
    if light != 'sun':
        sc.cycles.samples = sc.dacrt.samples = 64
    img, nrm = _render(sc, tmp_path, bounces=0 if light == 'sun' else 2)
    _compare(img, nrm, normal_atol=0.015)


def _render(sc, tmp_path, bounces=0):
    """test_bump's _render with so many bounces (diffuse and transmission)."""
    from tests.addon import scenes
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.cycles.transmission_bounces = bounces
    sc.dacrt.max_bounces = bounces
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1).mean(-1) for e, exr in exrs.items()}
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    return img, nrm


def _noise_on_object(nt):
    n = nt.nodes.new('ShaderNodeTexNoise')
    n.inputs['Scale'].default_value = 4.0
    n.inputs['Detail'].default_value = 0.0
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Object'], n.inputs['Vector'])
    return n


def _strand_scene(kind, samples=16):
    """Eight points of radius 0.2, or seven curves of radius 0.08, of a Diffuse bumped by a Noise
    on Object coordinates at distance 0.3, under a sun from the side."""
    from tests.addon import scenes
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    mat = _bumped("Bumped", _noise_on_object, 'Fac', distance=0.3)
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    sc.render.film_transparent = True
    scenes.camera(location=(0, -4, 0), rotation=(np.pi / 2, 0, 0), kind='ORTHO', ortho_scale=2.5)
    if kind == 'points':
        scenes.point_cloud("Pts", [(x, 0, z) for x in np.linspace(-0.9, 0.9, 4) for z in (-0.4, 0.4)], radius=0.2,
                           material=mat)
    else:
        scenes.hair_curves("Hair", [[(x, 0, -1), (x, 0, 0), (x + 0.1, 0, 1)] for x in np.linspace(-1, 1, 7)],
                           radius=0.08, material=mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(60.0), 0.0, math.radians(40.0))
    sc.cycles.samples = sc.dacrt.samples = samples
    return sc


def test_a_bumped_point_cloud_stays_unbent_as_in_cycles(tmp_path):
    """Cycles' points have no surface derivatives (dPdu = dPdv = 0): svm_node_set_bump's gradient
    is 0 there, so a bumped material shades a point cloud as unbumped (its image and Normal pass
    are the flat ones); the spheres DACRT tessellates points into stay unbent likewise. Before:
    bent as a mesh, 0.0626 vs Cycles 0.0790, 4x4 blocks 29% off, Normal 34%."""
    img, nrm = _render(_strand_scene('points', samples=32), tmp_path)
    hit = (np.abs(nrm['CYCLES']).sum(-1) > 0.5) & (np.abs(nrm['DACRT']).sum(-1) > 0.5)
    d, c = img['DACRT'][hit].mean(), img['CYCLES'][hit].mean()
    assert abs(d - c) < 0.02 * c, (d, c)
    diff = np.abs(nrm['DACRT'] - nrm['CYCLES']).max(-1)[hit].mean()
    assert diff < 0.02, f"normals {diff:.4f} off Cycles' on average"


def test_a_bump_on_curves_is_said_approximated(said):
    """Hair curves with a bumped material: their tubes are bent as meshes, Cycles bends curves
    with its own differentials (blocks 17% off): said; a bumped point cloud needs nothing said."""
    from tests.addon import scenes
    for kind in ('curves', 'points'):
        said.clear()
        sc = _strand_scene(kind, samples=1)
        sc.render.engine = 'DACRT'
        scenes.render_rgba(sc)
        text = ' '.join(said)
        if kind == 'curves':
            assert "Bump on hair and curves approximated" in text, text
        else:
            assert "Bump" not in text, text


def test_a_bump_output_read_as_a_value_is_said_and_stands_at_the_unbent_normal(said, tmp_path):
    """A Bump's Normal output wired to an AOV (or a colour): the bent normal is not computed as a
    value, so the normal it bends stands in (not 0, which is no normal), said as such, and the
    bump itself still renders. Before: 'procedural texture not evaluated per point ('Bump' node
    is not read there)', as if the bump were not rendered, and the AOV 0 (Cycles' (-0.0148, 0,
    0.9197) on average)."""
    from tests.addon import scenes

    def make():
        mat = _bumped("A", _wave(), 'Fac', distance=0.4)
        nt = mat.node_tree
        aov = nt.nodes.new('ShaderNodeOutputAOV')
        aov.aov_name = 'bn'
        nt.links.new(next(n for n in nt.nodes if n.type == 'BUMP').outputs['Normal'], aov.inputs['Color'])
        return mat
    sc = _plane_scene(make, samples=1)
    sc.view_layers[0].aovs.add().name = 'bn'
    sc.view_layers[0].aovs['bn'].type = 'COLOR'
    sc.render.engine = 'DACRT'
    said.clear()
    exr = scenes.read_exr(scenes.render_exr(str(tmp_path / 'd.exr'), sc, multilayer=True))
    text = ' '.join(said)
    assert "the Bump node's output is not read as a value (for an AOV or a colour): the unbent normal stands " \
           "in; the bump itself is rendered" in text, text
    assert "not evaluated per point" not in text, text
    layer = sc.view_layers[0].name
    bn = np.stack([exr[f"{layer}.bn.{c}"] for c in 'RGB'], axis=-1)
    np.testing.assert_allclose(bn.reshape(-1, 3).mean(0), (0.0, 0.0, 1.0), atol=1e-3)
    img = np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1).mean(-1)
    assert img.max() > 1.5 * img.min(), "the relief must show"


def _fine_bump(width):
    """A Noise finer than the pixel (scale 40, detail 6, Object coordinates) bumping by 0.02
    with the given Filter Width."""
    def noise(nt):
        n = nt.nodes.new('ShaderNodeTexNoise')
        n.inputs['Scale'].default_value = 40.0
        n.inputs['Detail'].default_value = 6.0
        nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Object'], n.inputs['Vector'])
        return n
    mat = _bumped("Fine", noise, 'Fac', distance=0.02)
    next(n for n in mat.node_tree.nodes if n.type == 'BUMP').inputs['Filter Width'].default_value = width
    return mat


@pytest.mark.parametrize('width', [0.1, 1.0, 4.0])
def test_the_filter_width_softens_a_fine_bump_as_in_cycles(width, tmp_path):
    """Cycles' taps are the ray differentials times the Bump's Filter Width from the point,
    forward differences: a Noise finer than the pixel (scale 40, detail 6, distance 0.02) is seen
    through that footprint, softer as it widens. Before: a step of a tenth of the footprint
    capped at 1e-4 of the scene, whatever the Filter Width: 0.2373 at each vs Cycles 0.2498 /
    0.2609 / 0.2613, 4x4 blocks 5.2% / 9.1% / 9.2% off, Normal.z 0.897 vs 0.962 / 0.999 / 1.0."""
    sc = _plane_scene(lambda: _fine_bump(width), samples=32)
    sc.render.resolution_x = sc.render.resolution_y = 64
    img, nrm = _render(sc, tmp_path)
    _compare(img, None, rtol_mean=0.015, rtol_block=0.03)
    dz, cz = nrm['DACRT'][..., 2].mean(), nrm['CYCLES'][..., 2].mean()
    assert abs(dz - cz) < 0.005, (dz, cz)


def test_a_filter_width_driven_by_nodes_is_said(said):
    """A Filter Width from a texture is read at its own value, and said so."""
    from tests.addon import scenes

    def make():
        mat = _bumped("Driven", _wave(), 'Fac', distance=0.4)
        nt = mat.node_tree
        noise = nt.nodes.new('ShaderNodeTexNoise')
        nt.links.new(noise.outputs['Fac'], next(n for n in nt.nodes if n.type == 'BUMP').inputs['Filter Width'])
        return mat
    sc = _plane_scene(make, samples=1)
    sc.render.engine = 'DACRT'
    said.clear()
    scenes.render_rgba(sc)
    text = ' '.join(said)
    assert "Bump node 'Bump': Filter Width driven by nodes; its own value used" in text, text


@pytest.mark.parametrize('displacement', [False, True])
def test_a_white_noise_height_is_said(said, displacement):
    """A White Noise height (through a Math node) has no gradient: Cycles' bump of it is the
    difference of unrelated values over its pixel-footprint taps. Fuzz seed 7793 (an Add of two
    Diffuse BSDFs bumped by White Noise, equirectangular camera) rendered 0.77x Cycles with no
    message; a Noise height is not said."""
    from tests.addon import scenes

    def white(nt):
        w = nt.nodes.new('ShaderNodeTexWhiteNoise')
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = 'MULTIPLY'
        m.inputs[1].default_value = 0.5
        nt.links.new(w.outputs['Value'], m.inputs[0])
        return m

    def noise(nt):
        return nt.nodes.new('ShaderNodeTexNoise')

    texts = {}
    for name, make_height, out in (("White", white, 'Value'), ("Smooth", noise, 'Fac')):
        def make():
            return _bumped(name, make_height, out, distance=0.2,
                           displacement=(0.5, 0.2) if displacement else None)
        sc = _plane_scene(make, samples=1)
        sc.render.engine = 'DACRT'
        said.clear()
        scenes.render_rgba(sc)
        texts[name] = ' '.join(said)
    assert "height from a White Noise Texture" in texts["White"], texts["White"]
    assert "White Noise" not in texts["Smooth"], texts["Smooth"]


@pytest.mark.parametrize('camera', ['EQUIRECTANGULAR', 'MIRRORBALL', 'wide PERSP'])
def test_a_fine_bump_seen_through_each_cameras_differentials(camera, tmp_path):
    """The fine Noise above (scale 40, detail 6, Filter Width 1) seen by panoramic cameras and a
    12 mm lens: Cycles spaces its taps by the camera's ray differentials, the direction one
    pixel over minus this one's (camera_sample_panorama / _perspective), so an equirectangular
    pixel spans 2 pi / width radians across the equator and a perspective one narrows off the
    axis. DACRT had taken the view plane's span over the width for all: for a panorama the unit
    square's, 2 pi too narrow (0.987x Cycles at the fuzz's Noise of scale 200)."""
    sc = _plane_scene(lambda: _fine_bump(1.0), samples=32, size=40.0)
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    cam = sc.camera
    cam.location = (0, 0, 1.5)
    if camera == 'wide PERSP':
        cam.data.type, cam.data.lens = 'PERSP', 12.0
        cam.rotation_euler = (0, 0, 0)
    else:
        cam.data.type, cam.data.panorama_type = 'PANO', camera
        cam.rotation_euler = (0, math.radians(90), 0) if camera == 'EQUIRECTANGULAR' else (0, 0, 0)
        if camera == 'EQUIRECTANGULAR':                  # the lower half: the plane
            cam.data.latitude_min, cam.data.latitude_max = -math.pi / 2, 0.0
    img, nrm = _render(sc, tmp_path)
    hit = img['CYCLES'] > 0.01                           # (the ball's rim)
    _compare(img, None, rtol_mean=0.015, rtol_block=0.03, hit=hit)
    # the normals' mean tilt, 1 - N.z, within 2.5% of Cycles' (it had been 1.036x and 1.040x
    # under the equirectangular camera and the mirror ball, whose taps were too close, and
    # 0.44x under the 12 mm lens, whose taps were the axis' off it)
    tilt = {e: 1.0 - float(nrm[e][..., 2][hit].mean()) for e in ('DACRT', 'CYCLES')}
    assert abs(tilt['DACRT'] / tilt['CYCLES'] - 1.0) < 0.025, tilt
