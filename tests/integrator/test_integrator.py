"""The render loop: determinism, pass blocking, robustness (NaN, empty scenes, bad input),
ray visibility, holdout and transparency, data passes, textures and the engine-facing API."""
import dataclasses

import numpy as np
import pytest

import dacrt
from addon import scenedata as sd
import addon.integrator as integrator_module
from addon.integrator import Integrator, Progress
from addon.texture import MISSING_TILE, UdimTiles, texture_lookup

from .scenes import (ALL_VIS, cornell_box, geometry, icosphere, light, material, ortho_down, plane_scene, quad,
                     render, translation)


def small_cornell(**kw):
    args = dict(width=32, height=24, samples=8, max_bounces=3)
    args.update(kw)
    return cornell_box(**args)


# --- determinism ----------------------------------------------------------------------------------

def test_same_seed_same_image_other_seed_other_noise():
    a = render(small_cornell(seed=3, samples=32)).film.combined()
    b = render(small_cornell(seed=3, samples=32)).film.combined()
    c = render(small_cornell(seed=4, samples=32)).film.combined()
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    # different noise, same picture: the means agree (seed-to-seed spread here is about 3%)
    assert a[..., :3].mean() == pytest.approx(c[..., :3].mean(), rel=0.1)


@pytest.mark.parametrize('paths', [97, 768, 100000])
def test_image_does_not_depend_on_pass_blocking(paths):
    """Blocks of whole samples, of a few pixels of one sample, and one block for everything."""
    ref = render(small_cornell(seed=1), paths_per_pass=32 * 24 * 8).film.combined()
    got = render(small_cornell(seed=1), paths_per_pass=paths).film.combined()
    assert np.allclose(got, ref, rtol=1e-5, atol=1e-7)


def test_progress_and_stats():
    integ = Integrator(small_cornell(samples=6), paths_per_pass=32 * 24 * 2)
    steps = list(integ.passes())
    assert [p.samples_done for p in steps] == [2, 4, 6]
    assert all(isinstance(p, Progress) and p.samples_total == 6 for p in steps)
    last = steps[-1]
    assert last.fraction == 1.0 and last.eta_seconds == 0.0 and last.rays_traced > 0
    s = integ.stats
    assert s['rays']['camera'] == 32 * 24 * 6
    assert s['rays_total'] == sum(s['rays'].values()) == last.rays_traced
    assert 0.0 < s['trace_share'] < 1.0
    assert s['python_seconds'] == pytest.approx(s['render_seconds'] - s['trace_seconds'])
    assert s['samples'] == 6 and s['nan_dropped'] == 0 and s['tracer_scenes'] == 1
    assert np.all(integ.film.sample_counts() == 6)
    assert integ._scenes == {}                            # tracer scenes dropped at the end


def test_cancel_between_passes_keeps_a_partial_image():
    integ = Integrator(small_cornell(samples=8), paths_per_pass=32 * 24)
    for p in integ.passes():
        if p.samples_done == 2:
            break
    assert np.all(integ.film.sample_counts() == 2)
    assert integ.film.combined()[..., :3].max() > 0


# --- robustness ---------------------------------------------------------------------------------

def test_nan_texture_never_reaches_the_film():
    scene = plane_scene([light('POINT', 1000.0, translation(z=2.0))], samples=16)
    tex = np.ones((4, 4, 4), np.float32)
    tex[:, :2] = np.nan
    tex[0, 3] = np.inf
    uvs = np.array([[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]], np.float32)
    scene.geometry.uvs = uvs
    scene.materials[1] = material('nan', (0.8,) * 3, texture=tex, texture_interpolation='Closest')
    # the view covers both halves of the texture
    scene.camera = ortho_down(view=2000.0 * 0.9)
    integ = render(scene)
    img = integ.film.combined()
    assert np.isfinite(img).all()
    # NaN and infinite texels read 0 (black there, as Cycles renders them): nothing
    # non-finite reaches the film to be dropped (an infinite texel had turned its paths
    # infinite; the film's own dropping: tests/stress/test_renderer.py)
    assert integ.film.nan_dropped == 0 and integ.stats['nan_dropped'] == 0
    assert (img[..., :3] == 0.0).any() and (img[..., :3] > 0.0).any()
    # every sample counts, and alpha stays 1 (an opaque plane)
    assert (integ.film.sample_counts() == 16).all() and (img[..., 3] == 1.0).all()


def test_nan_vertices_are_skipped_and_reported():
    scene = plane_scene([light('POINT', 1000.0, translation(z=2.0))], samples=4)
    v, t = quad((0.0, 0.0, 0.5), 1.0, 1.0)
    v[0, 2] = np.nan
    scene.geometry = geometry([(quad((0.0, 0.0, 0.0), 1000.0, 1000.0)[0], quad((0, 0, 0), 1, 1)[1], 1, ALL_VIS),
                               (v, t, 1, ALL_VIS)])
    integ = render(scene)
    assert np.isfinite(integ.film.combined()).all()
    assert any('non-finite vertex' in text for _, text in integ.messages)


def test_empty_scene_renders_black_or_world():
    scene = plane_scene(samples=2)
    scene.geometry = sd.Geometry.empty()
    img = render(scene).film.combined()
    assert np.all(img[..., :3] == 0.0) and np.all(img[..., 3] == 1.0)
    scene.world = np.array([0.2, 0.3, 0.4], np.float32)
    img = render(scene).film.combined()
    assert np.allclose(img[..., :3], [0.2, 0.3, 0.4]) and np.all(img[..., 3] == 1.0)


def test_no_lights_is_black_and_traces_no_shadow_rays():
    integ = render(plane_scene(samples=2, max_bounces=4))
    assert np.all(integ.film.combined()[..., :3] == 0.0)
    assert integ.stats['rays']['shadow'] == 0 and integ.stats['rays']['bounce'] > 0


def test_zero_strength_light_is_skipped_and_reported():
    integ = render(plane_scene([light('POINT', 0.0, translation(z=2.0), name='Dark')], samples=2))
    assert integ.stats['rays']['shadow'] == 0 and integ.stats['lights'] == 0
    assert any('Dark' in text for _, text in integ.messages)


@pytest.mark.parametrize('change,message', [
    (lambda s: setattr(s.settings, 'samples', 0), 'samples'),
    (lambda s: setattr(s.settings, 'max_bounces', -1), 'max_bounces'),
    (lambda s: setattr(s.settings, 'filter_type', 'CATMULL'), 'filter_type'),
    (lambda s: setattr(s.settings, 'passes', ('Shadow',)), 'pass'),
    (lambda s: setattr(s.geometry, 'material', np.array([5, 5], np.int32)), 'material'),
    (lambda s: setattr(s.geometry, 'normals', np.zeros((1, 3, 3), np.float32)), 'normals'),
    (lambda s: setattr(s.geometry, 'triangles', np.array([[0, 1, 9], [0, 1, 2]], np.int32)), 'vertex'),
    (lambda s: s.lights.append(light('LASER', 1.0, np.eye(4))), 'kind'),
    (lambda s: s.lights.append(light('AREA', 1.0, np.eye(4), shape='STAR')), 'shape'),
    (lambda s: s.lights.append(light('POINT', np.nan, np.eye(4))), 'strength'),
    (lambda s: setattr(s.materials[1], 'base_color', np.array([np.inf, 0, 0], np.float32)), 'base_color'),
    (lambda s: setattr(s, 'world', np.array([-1.0, 0, 0], np.float32)), 'world'),
    (lambda s: setattr(s.settings, 'partition', 'octree'), 'partition'),
])
def test_bad_input_gets_a_clear_message(change, message):
    scene = plane_scene()
    change(scene)
    with pytest.raises(ValueError, match=message):
        Integrator(scene)


# --- self-intersection ------------------------------------------------------------------------

def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q


def _grid(half, n):
    """n x n quads (2n^2 triangles, shared vertices) covering [-half, half]^2 at z = 0."""
    xs = np.linspace(-half, half, n + 1)
    v = np.array([(x, y, 0.0) for y in xs for x in xs])
    t = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            t += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    return v, np.array(t)


def _fold(half, angle):
    """Triangle 0 at z = 0, x <= 0; triangles 1, 2 bend down by `angle` past the edge x = 0
    (a convex edge seen from +z)."""
    c, s = np.cos(angle), np.sin(angle)
    v = np.array([(-half, -half, 0), (0, -half, 0), (0, half, 0), (half * c, -half, -half * s),
                  (half * c, half, -half * s)], float)
    return v, np.array([(0, 1, 2), (1, 3, 4), (1, 4, 2)])


# name: ((vertices, triangles), seed of a random rotation (None: as built), shift, triangles the rays
# leave (None: all))
SURFACES = {
    '2 km plane': (_grid(1000.0, 1), 1, (0, 0, 0), None),
    '2 km plane, 8x8 grid': (_grid(1000.0, 8), 2, (0, 0, 0), None),
    '2 km plane, axis-aligned': (_grid(1000.0, 1), None, (0, 0, 0), None),
    '1 m plane': (_grid(0.5, 2), 3, (0, 0, 0), None),
    '1 cm plane 3.9 km away': (_grid(0.005, 2), 4, (3000.0, -2000.0, 1500.0), None),
    '0.2 mm plane near the origin': (_grid(1e-4, 2), 5, (0, 0, 1e-5), None),
    '200 m 16x16 grid 600 m away': (_grid(100.0, 16), 6, (500.0, 300.0, -200.0), None),
    'right-angle edge, 1 m': (_fold(1.0, np.pi / 2), 7, (0, 0, 0), [0]),
    'nearly flat edge, 1 km': (_fold(1000.0, 1e-3), 8, (0, 0, 0), [0]),
}


def _surface_points(integ, tris, n, rng):
    """Points on the given triangles as the render loop makes them (half of them within a
    hair of an edge), arriving from the front from afar; returns prim, P, P_off, ng."""
    prim = rng.choice(tris, n).astype(np.int32)
    r = rng.random((2, n))
    su = np.sqrt(r[0])
    u, v = r[1] * su, 1.0 - su
    edge = rng.random(n) < 0.5
    u = np.where(edge, rng.random(n) * 10.0 ** rng.uniform(-9, -3, n), u)
    v = np.minimum(v, 1.0 - u)
    ng = integ.tri.geo[9:12][:, prim]
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    # arriving from afar: the full step (one is cut only for rays from next to the plane)
    hits['prim'], hits['u'], hits['v'], hits['t'] = prim, u, v, np.inf
    P, ng, _, P_off = integ._surface(hits, None, np.ascontiguousarray(-ng))
    return prim, P, P_off, ng


def _directions(ng, rng, min_elevation=0.0):
    """Unit directions in the hemisphere of ng: cosine-distributed, 30% grazing (down to 1e-5 rad:
    a cosine-sampled bounce is that flat once in 10^10; flatter rays skim a 600 m distant plane
    within float32 resolution of its coordinates for hundreds of metres)."""
    n = ng.shape[1]
    el = np.where(rng.random(n) < 0.3, 10.0 ** rng.uniform(-5, -0.2, n), np.arcsin(np.sqrt(rng.random(n))))
    el = np.maximum(el, min_elevation)
    phi = 2 * np.pi * rng.random(n)
    nn = ng.astype(np.float64)
    a = np.where(np.abs(nn[0:1]) > 0.9, [[0.0], [1.0], [0.0]], [[1.0], [0.0], [0.0]])
    t = np.cross(nn.T, a.T).T
    t /= np.linalg.norm(t, axis=0)
    b = np.cross(nn.T, t.T).T
    d = t * (np.cos(el) * np.cos(phi)) + b * (np.cos(el) * np.sin(phi)) + nn * np.sin(el)
    return (d / np.linalg.norm(d, axis=0)).astype(np.float32)


@pytest.mark.parametrize('scenes', ['separate', 'shared'])
@pytest.mark.parametrize('name', list(SURFACES))
def test_rays_leaving_a_surface_never_rehit_it(name, scenes, monkeypatch):
    """Bounce and shadow rays leave from the render loop's offset origins and skip the triangle
    they leave: over huge, tiny, distant, subdivided and folded surfaces, at points hugging the
    edges and in grazing directions, none may hit the surface (its own triangle or a neighbour
    across a shared edge). A camera-only triangle listed first shifts the bounce and shadow
    scenes' numbering (separate scenes), or is masked out of one shared scene, so skip must be
    translated. The step stays tiny (8 ULPs of the triangle's largest coordinate; 256 ULPs
    biased lights near a huge plane)."""
    monkeypatch.setattr(integrator_module, '_SHARED_SCENE_FRACTION', 2.0 if scenes == 'separate' else 0.0)
    (v, t), rot, shift, tris = SURFACES[name]
    v = (v if rot is None else v @ _rotation(rot).T) + np.asarray(shift)
    decoy = (np.array([(0, 0, 9e3), (1, 0, 9e3), (0, 1, 9e3)], float), np.array([(0, 1, 2)]))
    scene = plane_scene([light('POINT', 1.0, translation(z=5.0))], samples=1)
    scene.geometry = geometry([(*decoy, 1, sd.VIS_CAMERA), (v, t, 1, ALL_VIS)])
    integ = Integrator(scene)
    if scenes == 'separate':
        assert integ._local['bounce'] is not None and integ._local['shadow'] is not None
    else:
        assert integ.stats['tracer_scenes'] == 1 and integ._visible['bounce'] == sd.VIS_DIFFUSE
    rng = np.random.default_rng(0)
    n = 60000
    prim, P, P_off, ng = _surface_points(integ, np.arange(1, len(t) + 1) if tris is None else np.array(tris) + 1,
                                         n, rng)
    D = _directions(ng, rng)
    hits = integ._intersect('bounce', P_off, D, np.full(n, np.inf, np.float32), prim)
    assert np.count_nonzero(hits['prim'] >= 0) == 0
    assert not integ._occluded(P_off, D, np.full(n, np.inf, np.float32), prim).any()
    mag = np.abs(v).max()
    step = np.linalg.norm((P_off - P).astype(np.float64), axis=0)
    assert step.max() <= 8 * 2.0 ** -22 * max(mag, 2.0 ** -100)


def test_skip_alone_keeps_rays_off_their_own_triangle(monkeypatch):
    """With no offset at all, rays leaving exactly from the surface (tilted, so every coordinate
    is rounded) away from any edge are kept off their own triangle by skip alone, in the bounce
    and shadow scenes, whose numbering a camera-only triangle listed first has shifted."""
    import addon.surfacetables as surfacetables
    monkeypatch.setattr(surfacetables, 'OFFSET_ULPS', np.float32(0.0))
    v, t = _grid(1.0, 4)
    v = v @ _rotation(9).T
    decoy = (np.array([(0, 0, 9e3), (1, 0, 9e3), (0, 1, 9e3)], float), np.array([(0, 1, 2)]))
    scene = plane_scene([light('POINT', 1.0, translation(z=5.0))], samples=1)
    scene.geometry = geometry([(*decoy, 1, sd.VIS_CAMERA), (v, t, 1, ALL_VIS)])
    integ = Integrator(scene)
    rng = np.random.default_rng(2)
    n = 40000
    prim = rng.integers(1, len(t) + 1, n).astype(np.int32)
    b = rng.uniform(0.1, 0.45, (2, n)).astype(np.float32)        # well inside the triangle
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits['prim'], hits['u'], hits['v'] = prim, b[0], b[1]
    P, ng, _, P_off = integ._surface(hits, None, np.ascontiguousarray(-integ.tri.geo[9:12][:, prim]))
    assert np.array_equal(P, P_off)
    D = _directions(ng, rng, min_elevation=0.1)
    inf = np.full(n, np.inf, np.float32)
    assert np.count_nonzero(integ._intersect('bounce', P, D, inf, prim)['prim'] >= 0) == 0
    assert not integ._occluded(P, D, inf, prim).any()
    # without skip about half of these rays re-hit the triangle they leave
    assert np.count_nonzero(integ._intersect('bounce', P, D, inf)['prim'] >= 0) > n // 10


@pytest.mark.parametrize('name', list(SURFACES))
def test_shadow_rays_reach_emitter_triangles(name):
    """Shadow rays aimed at emitter triangles (points hugging the edges, from 0.1 to 10^4 times
    the triangle size away, but at least 128 ULPs of its coordinates: nearer points cannot even
    be told apart from the surface in float32) end in front of them and are never stopped by the
    emitter itself or its neighbours."""
    (v, t), rot, shift, tris = SURFACES[name]
    v = (v if rot is None else v @ _rotation(rot).T) + np.asarray(shift)
    scene = plane_scene(samples=1)
    scene.materials[1] = material('glow', (0.5,) * 3, (1.0, 1.0, 1.0))
    scene.geometry = geometry([(v, t, 1, ALL_VIS)])
    integ = Integrator(scene)
    emit = integ.lights.triangles
    assert len(emit) == len(t)
    rng = np.random.default_rng(1)
    n = 60000
    which = rng.choice(len(t) if tris is None else np.array(tris), n)
    u1 = np.where(rng.random(n) < 0.5, 1.0 - 10.0 ** rng.uniform(-7, -2, n), rng.random(n)).astype(np.float32)
    u2 = np.where(rng.random(n) < 0.5, 10.0 ** rng.uniform(-7, -2, n), rng.random(n)).astype(np.float32)
    # shading points above the emitter, in front of its sampled points
    ng = emit.geo[9:12][:, which]
    size = np.linalg.norm(emit.geo[3:6][:, which], axis=0)
    q = emit.geo[0:3][:, which] + emit.geo[3:6][:, which] * 0.3 + emit.geo[6:9][:, which] * 0.3
    dist = np.maximum(size * 10.0 ** rng.uniform(-1, 4, n), 2.0 ** -16 * np.abs(v).max())
    S = (q + _directions(ng, rng, 0.02) * dist).astype(np.float32)
    ls = emit.sample(S, which, u1, u2)
    assert (ls.value.max(axis=0) > 0).all()
    rays, valid = dacrt.shading.shadow_rays(S, ls.wi, ls.dist, ls.target, np.arange(n), integrator_module._END_SHORTEN)
    assert valid.all()
    assert not integ._occluded_rays(rays).any()


# --- visibility, holdout, transparency --------------------------------------------------------

def roofed(roof_bits, samples=8, **kw):
    """Plane lit by a point light, with a roof between them carrying the given visibility bits."""
    scene = plane_scene([light('POINT', 1000.0, translation(z=2.0))], samples=samples, **kw)
    plane = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    roof = quad((0.0, 0.0, 1.0), 5.0, 5.0, up=False)
    scene.camera = ortho_down(height=1.5)
    scene.materials.append(material('roof', (0.0, 0.0, 0.0), (0.25, 0.25, 0.25)))   # black, glowing
    scene.geometry = geometry([(*plane, 1, ALL_VIS), (*roof, 2, roof_bits)])
    return scene


@pytest.mark.parametrize('scenes', ['separate', 'shared'])
def test_visibility_bits(scenes, monkeypatch):
    """Each ray kind sees the triangles its visibility bit allows, whether it traces its own
    subset (a scene per subset) or one scene shared with per-triangle masks."""
    monkeypatch.setattr(integrator_module, '_SHARED_SCENE_FRACTION', 2.0 if scenes == 'separate' else 0.0)
    lit = 5.06606                                              # the point light alone
    # the roof (emission 0.25, 10 x 10 m, 1 m up) seen from the plane: E = L * 4 * corner(5, 5, 1)
    A = 5.0 / np.hypot(5.0, 1.0)
    glow = 0.8 / np.pi * 0.25 * 4 * 0.5 * 2 * A * np.arctan(A)
    # roof fully visible: the camera sees the roof's emission
    img = render(roofed(ALL_VIS)).film.combined()[..., 0]
    assert img == pytest.approx(0.25, rel=1e-6)
    # camera-invisible roof: the camera sees the plane, shadowed from the point light but lit
    # by the roof's emission (sampled as a light because bounce rays can hit it)
    img = render(roofed(sd.VIS_DIFFUSE | sd.VIS_SHADOW, 512, max_bounces=0)).film.combined()[..., 0]
    assert img.mean() == pytest.approx(glow, rel=0.01)
    # shadow-invisible roof: the light passes it
    # (the light is picked half the time: 4096 spp make 1% five standard errors)
    img = render(roofed(sd.VIS_DIFFUSE, 4096, max_bounces=0)).film.combined()[..., 0]
    assert img.mean() == pytest.approx(lit + glow, rel=0.01)
    # only shadow rays see the roof: it blocks the light and is no light itself
    integ = render(roofed(sd.VIS_SHADOW, max_bounces=0))
    assert integ.film.combined()[..., 0].max() == 0.0
    assert integ.stats['tracer_scenes'] == (2 if scenes == 'separate' else 1)


def test_shared_scene_renders_what_separate_scenes_render(monkeypatch):
    """Masks trace exactly the subsets separate scenes hold: the same image, bit for bit."""
    images = []
    for fraction in (2.0, 0.0):
        monkeypatch.setattr(integrator_module, '_SHARED_SCENE_FRACTION', fraction)
        integ = render(roofed(sd.VIS_DIFFUSE | sd.VIS_SHADOW, 16, max_bounces=2))
        images.append(integ.film.combined())
        assert integ.stats['tracer_scenes'] == (2 if fraction > 1 else 1)
    assert np.array_equal(images[0], images[1])


def test_holdout_and_transparent_film():
    scene = roofed(ALL_VIS | sd.HOLDOUT)
    scene.world = np.array([0.5, 0.5, 0.5], np.float32)
    img = render(scene).film.combined()
    assert np.all(img == 0.0)                                  # holdout: RGB 0 and alpha 0
    scene = plane_scene(world=(0.5, 0.5, 0.5), samples=4, film_transparent=True)
    scene.geometry = sd.Geometry.empty()
    img = render(scene).film.combined()
    assert np.all(img == 0.0)                                  # transparent: the world is not seen
    scene = plane_scene(world=(1.0, 1.0, 1.0), samples=64, film_transparent=True)
    img = render(scene).film.combined()
    assert np.all(img[..., 3] == 1.0) and img[..., 0].mean() == pytest.approx(0.8, rel=0.03)


# --- passes -------------------------------------------------------------------------------------

def test_data_passes():
    scene = plane_scene([light('POINT', 1000.0, translation(z=2.0))], samples=4,
                        passes=('Depth', 'Normal', 'DiffCol'))
    scene.camera = ortho_down(height=0.5, width=8, px=4)
    scene.camera.border = (0, 0, 4, 4)
    plane = quad((0.0, 0.0, 0.0), 1000.0, 1000.0, up=False)   # seen from its back: normals flip
    scene.geometry = geometry([(*plane, 1, ALL_VIS)])
    assert np.allclose(scene.geometry.normals, [0, 0, -1])
    integ = render(scene)
    assert np.allclose(integ.film.combined()[:, :4, 0], 5.06606, rtol=1e-5)
    depth = integ.film.pass_image('Depth')
    assert depth.shape == (4, 8, 1)
    assert np.allclose(depth[:, :4], 0.5) and np.all(depth[:, 4:] == 0.0)
    assert np.allclose(integ.film.pass_image('Normal')[:, :4], [0, 0, 1], atol=1e-6)
    assert np.allclose(integ.film.pass_image('DiffCol')[:, :4], 0.8)
    scene.geometry = sd.Geometry.empty()
    assert np.all(render(scene).film.pass_image('Depth')[:, :4] == 1e10)
    with pytest.raises(KeyError):
        render(plane_scene(samples=1)).film.pass_image('Depth')


def test_depth_comes_from_the_pixel_centre_whatever_the_seed():
    """Cycles sends sample 0 through the pixel centre (integrate_camera_sample: the filter table
    read at 0.5), and the data passes come from sample 0: on a sloped plane Depth is the
    distance at each pixel's centre, exactly, for any seed and filter."""
    v = np.array([[-10, -10, -3], [10, -10, 3], [10, 10, 3], [-10, 10, -3]], np.float64)   # z = 0.3 x
    t = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    centre_x = -1.0 + (np.arange(8) + 0.5) * 0.25          # ortho view 2 wide, 8 pixels
    for seed, filt in ((0, 'BLACKMAN_HARRIS'), (7, 'GAUSSIAN'), (11, 'BOX')):
        scene = plane_scene([light('SUN', 1.0, np.eye(4))], samples=3, passes=('Depth',), seed=seed,
                            filter_type=filt, filter_width=2.0)
        scene.camera = ortho_down(height=5.0, width=8, px=8, view=2.0)
        scene.geometry = geometry([(v, t, 1, ALL_VIS)])
        depth = render(scene).film.pass_image('Depth')[..., 0]
        assert np.allclose(depth, 5.0 - 0.3 * centre_x[None, :], atol=1e-5), (seed, filt)


def test_position_uv_and_index_passes():
    """Cycles' Position, UV, Object Index and Material Index passes (film/data_passes.h) on two
    quads far from the origin (the render recentres the scene; Position is world space), 1 x 1
    unit pixels, box filter: Position, Object and Material Index from each pixel's sample 0
    (through its centre), UV = (u, v, 1) averaged over the samples; the pixels that see nothing stay 0 (Depth 1e10)."""
    T = np.array([1000.0, -2000.0])
    a = quad((T[0] - 2.0, T[1], 0.0), 2.0, 2.0)                 # pixel columns 0-3
    b = quad((T[0] + 1.5, T[1], 0.0), 1.5, 2.0)                 # columns 4-6; column 7: nothing
    mats = [material('default'), material('a', pass_index=3), material('b', pass_index=7)]
    g = geometry([(*a, 1, ALL_VIS), (*b, 2, ALL_VIS)])
    corners = g.vertices[g.triangles]                            # (M, 3, 3)
    g.uvs = np.stack([(corners[..., 0] - T[0]) / 8 + 0.5, (corners[..., 1] - T[1]) / 4 + 0.5],
                     axis=-1).astype(np.float32)
    scene = sd.SceneData(ortho_down(height=0.5, width=8, px=4, view=8.0, target=T), g, mats, [],
                         np.zeros(3, np.float32),
                         sd.Settings(samples=16, filter_type='BOX',
                                     passes=('Depth', 'Position', 'UV', 'IndexOB', 'IndexMA')),
                         object_names=['A', 'B'], object_pass_index=np.array([5, 9]))
    integ = render(scene)
    assert np.abs(integ.origin).max() > 100                      # the render did recentre
    film = integ.film
    col = np.arange(8)[None, :].repeat(4, axis=0)
    row = np.arange(4)[:, None].repeat(8, axis=1)
    on = col < 7
    ob, ma = film.pass_image('IndexOB')[..., 0], film.pass_image('IndexMA')[..., 0]
    assert np.array_equal(ob, np.where(col < 4, 5.0, np.where(on, 9.0, 0.0)))
    assert np.array_equal(ma, np.where(col < 4, 3.0, np.where(on, 7.0, 0.0)))
    pos = film.pass_image('Position')
    x0, y0 = T[0] - 4 + col, T[1] - 2 + row                     # each pixel's footprint corner
    assert np.all((pos[on][:, 0] >= x0[on] - 1e-3) & (pos[on][:, 0] <= x0[on] + 1 + 1e-3))
    assert np.all((pos[on][:, 1] >= y0[on] - 1e-3) & (pos[on][:, 1] <= y0[on] + 1 + 1e-3))
    assert np.allclose(pos[on][:, 2], 0.0, atol=1e-3) and np.all(pos[~on] == 0.0)
    # sample 0 goes through the pixel centre (Cycles), so Position is the centre's point
    assert np.allclose(pos[on][:, 0] - x0[on], 0.5, atol=1e-3) and np.allclose(pos[on][:, 1] - y0[on], 0.5, atol=1e-3)
    uv = film.pass_image('UV')
    # the mean of 16 uniform points: the pixel centre's UV within ~4 standard errors
    assert np.allclose(uv[on][:, 0], (col[on] + 0.5) / 8, atol=4 * (1 / 8) / np.sqrt(12 * 16))
    assert np.allclose(uv[on][:, 1], (row[on] + 0.5) / 4, atol=4 * (1 / 4) / np.sqrt(12 * 16))
    assert np.allclose(uv[on][:, 2], 1.0) and np.all(uv[~on] == 0.0)
    depth = film.pass_image('Depth')[..., 0]
    assert np.allclose(depth[on], 0.5, rtol=1e-4) and np.all(depth[~on] == 1e10)
    scene.geometry.has_uv = scene.geometry.object_index == 0     # quad b's mesh has no UV map
    uv_b = render(scene).film.pass_image('UV')
    assert np.allclose(uv_b[col < 4], uv[col < 4]) and np.all(uv_b[(col >= 4)][:, 2] == 0.0)
    scene.geometry.uvs = scene.geometry.has_uv = None            # no UV map: Cycles reads 0
    assert np.all(render(scene).film.pass_image('UV') == 0.0)


def test_denoising_data_closed_form():
    """Cycles' Denoising Data on a plane of albedo 0.8 half in view under a world of 0.25:
    normal (0, 0, -1) in camera space (z into the view), albedo 0.8 on the plane and the world
    where rays miss (Cycles adds what camera rays see), depth from the clip-start plane."""
    scene = plane_scene(world=(0.25, 0.25, 0.25), samples=8,
                        passes=('DenoiseNormal', 'DenoiseAlbedo', 'DenoiseDepth'))
    scene.camera = ortho_down(height=0.5, width=8, px=4)      # clip start 1e-3
    v, t = quad((-0.00025, 0.0, 0.0), 0.00025, 1.0)            # the left half of the view
    scene.geometry = geometry([(v, t, 1, ALL_VIS)])
    film = render(scene).film
    normal, albedo = film.pass_image('DenoiseNormal'), film.pass_image('DenoiseAlbedo')
    depth = film.pass_image('DenoiseDepth')[..., 0]
    assert np.allclose(normal[:, :3], [0, 0, -1], atol=1e-6) and np.all(normal[:, 5:] == 0)
    assert np.allclose(albedo[:, :3], 0.8, rtol=1e-6) and np.allclose(albedo[:, 5:], 0.25, rtol=1e-6)
    assert np.allclose(depth[:, :3], 0.5 - 1e-3, rtol=1e-5) and np.all(depth[:, 5:] == 0)
    assert 'Emit' not in scene.settings.passes and 'Env' in film.passes   # kept for the albedo
    # transparent film: the world camera rays miss into is not evaluated (Cycles: 0 in the
    # albedo there, the world again with the Environment pass on; DACRT had added it always)
    clear = dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, film_transparent=True))
    albedo = render(clear).film.pass_image('DenoiseAlbedo')
    assert np.allclose(albedo[:, :3], 0.8, rtol=1e-6) and np.all(albedo[:, 5:] == 0)
    env = dataclasses.replace(clear, settings=dataclasses.replace(
        clear.settings, passes=tuple(clear.settings.passes) + ('Env',)))
    film = render(env).film
    assert np.allclose(film.pass_image('DenoiseAlbedo')[:, 5:], 0.25, rtol=1e-6)
    assert np.allclose(film.pass_image('Env')[:, 5:], 0.25, rtol=1e-6)


@pytest.mark.parametrize('start,depth,falloff', [(0.1, 1.0, 2.0), (0.2, 0.5, 1.0), (0.0, 2.0, 0.5),
                                                  (1.0, 3.0, 2.0)])
def test_mist_pass_closed_form(start, depth, falloff):
    """Cycles' mist of the first surface: ((distance - start) / depth) clamped to [0, 1], to
    the falloff's power; the orthographic camera's distance is along its axis (0.5 to the
    plane everywhere); rays that meet nothing give 1, partly covered pixels the mean."""
    scene = plane_scene(samples=8, passes=('Mist',), mist=(start, depth, falloff))
    scene.camera = ortho_down(height=0.5, width=8, px=4)
    v, t = quad((-0.00025, 0.0, 0.0), 0.00025, 1.0)            # covers the left half of the view
    scene.geometry = geometry([(v, t, 1, ALL_VIS)])
    mist = render(scene).film.pass_image('Mist')[..., 0]
    want = min(max((0.5 - start) / depth, 0.0), 1.0) ** falloff
    assert mist.shape == (4, 8)
    assert np.allclose(mist[:, :3], want, atol=1e-6)          # pixels wholly on the plane
    assert np.allclose(mist[:, 5:], 1.0)                       # pixels wholly off it
    assert np.all((mist[:, 3:5] >= min(want, 1.0) - 1e-6) & (mist[:, 3:5] <= 1.0 + 1e-6))


# --- textures -----------------------------------------------------------------------------------

def test_texture_lookup_modes():
    tex = np.zeros((2, 4, 4), np.float32)
    tex[..., 0] = np.arange(4)[None, :]                        # red = column index
    tex[..., 1] = np.arange(2)[:, None]                        # green = row index (row 0 at the bottom)
    u = np.array([0.125, 0.375, 0.25, 1.125, -0.125, 0.5], np.float32)
    v = np.array([0.25, 0.25, 0.75, 0.25, 0.25, 0.5], np.float32)
    closest = texture_lookup(tex, u, v, 'Closest', 'REPEAT')
    assert np.allclose(closest[0], [0, 1, 1, 0, 3, 2]) and np.allclose(closest[1], [0, 0, 1, 0, 0, 1])
    lin = texture_lookup(tex, u, v, 'Linear', 'EXTEND')
    assert np.allclose(lin[0], [0, 1, 0.5, 3, 0, 1.5]) and np.allclose(lin[1], [0, 0, 1, 0, 0, 0.5])
    clip = texture_lookup(tex, u, v, 'Closest', 'CLIP')
    assert np.allclose(clip[0], [0, 1, 1, 0, 0, 2])
    rep = texture_lookup(tex, np.array([0.0], np.float32), np.array([0.25], np.float32), 'Linear', 'REPEAT')
    assert rep[0, 0] == pytest.approx(1.5)                     # wraps between columns 3 and 0


def _mirror(i, n):
    """Blender's mirrored repeat of texel index i: 0 .. n-1, n-1 .. 0, 0 .. (period 2n)."""
    m = i % (2 * n)
    return m if m < n else 2 * n - 1 - m


def _cubic_reference(tex, u, v, extension):
    """Cycles' bicubic lookup in float64, texel by texel: the uniform cubic B-spline
    (1/6)[(1-t)^3, 3t^3 - 6t^2 + 4, -3t^3 + 3t^2 + 3t + 1, t^3] over texels floor(x - 1/2) - 1 .. + 2."""
    h, w = tex.shape[:2]
    def weights(t):
        return np.array([(1 - t) ** 3, 3 * t ** 3 - 6 * t ** 2 + 4, -3 * t ** 3 + 3 * t ** 2 + 3 * t + 1, t ** 3]) / 6
    def index(i, n):
        if extension == 'REPEAT':
            return i % n, True
        if extension == 'MIRROR':
            return _mirror(i, n), True
        if extension == 'EXTEND':
            return min(max(i, 0), n - 1), True
        return min(max(i, 0), n - 1), 0 <= i < n                # CLIP
    out = np.zeros((3, len(u)))
    for k in range(len(u)):
        x, y = float(u[k]) * w - 0.5, float(v[k]) * h - 0.5
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        wx, wy = weights(x - x0), weights(y - y0)
        for a in range(4):
            iy, iny = index(y0 - 1 + a, h)
            for b in range(4):
                ix, inx = index(x0 - 1 + b, w)
                out[:, k] += wy[a] * wx[b] * tex[iy, ix, :3] * (iny and inx)
    return out


@pytest.mark.parametrize('extension', ['REPEAT', 'EXTEND', 'CLIP', 'MIRROR'])
def test_texture_cubic_and_mirror_as_cycles(extension):
    """'Cubic' (and 'Smart', which the export maps to it) is Cycles' bicubic B-spline, and
    MIRROR its mirrored repeat, against a float64 reference written texel by texel; at texel
    centres the B-spline does not reproduce the texel (it smooths: 1/6, 2/3, 1/6)."""
    rng = np.random.default_rng(5)
    tex = rng.random((5, 7, 4)).astype(np.float32)
    u = rng.uniform(-1.5, 2.5, 400).astype(np.float32)
    v = rng.uniform(-1.5, 2.5, 400).astype(np.float32)
    got = texture_lookup(tex, u, v, 'Cubic', extension)
    np.testing.assert_allclose(got, _cubic_reference(tex, u, v, extension), atol=2e-6)
    line = np.zeros((1, 3, 4), np.float32)
    line[0, 1, :3] = 1.0
    centre = texture_lookup(line, np.array([0.5], np.float32), np.array([0.5], np.float32), 'Cubic', 'CLIP')
    # the lit texel's centre: weight 4/6 across, and 4/6 down (CLIP: the rows above and below
    # are outside the one-row image)
    assert centre[0, 0] == pytest.approx((4 / 6) * (4 / 6), rel=1e-6)
    mirrored = texture_lookup(tex, (np.arange(-7, 21, dtype=np.float32) + 0.5) / 7,
                              np.full(28, 0.5 / 5, np.float32), 'Closest', 'MIRROR')
    np.testing.assert_array_equal(mirrored[0], tex[0, [_mirror(i, 7) for i in range(-7, 21)], 0])


def test_udim_lookup_picks_the_tile_as_cycles():
    """Tile (int) u, (int) v -> 1001 + tx + 10 ty, read at the UV minus the tile's corner with
    the node's extension; no tile, tx outside 0..9, or a non-finite UV: magenta."""
    tiles = {1001: np.zeros((1, 2, 4), np.float32), 1002: np.zeros((2, 1, 4), np.float32),
             1013: np.zeros((1, 1, 4), np.float32)}
    tiles[1001][..., 0] = [[1, 2]]                             # red: which tile, which texel
    tiles[1002][..., 0] = [[3], [4]]
    tiles[1013][..., 0] = 5
    udim = UdimTiles.stack(tiles)
    assert udim.numbers == (1001, 1002, 1013) and udim.shapes == ((1, 2), (2, 1), (1, 1))
    u = np.array([0.25, 0.75, 1.5, 1.5, 2.5, -0.25, 2.5, 0.5, 10.5, -1.5, np.nan, np.inf], np.float32)
    v = np.array([0.5, 0.5, 0.25, 0.75, 1.5, 0.5, 0.5, 1.5, 0.5, 0.5, 0.5, 0.5], np.float32)
    got = texture_lookup(udim, u, v, 'Closest', 'REPEAT')
    magenta = MISSING_TILE[0]
    # u = -0.25 truncates to tile 1001 and reads it at -0.25 (REPEAT: its last texel)
    assert got[0].tolist() == [1, 2, 3, 4, 5, 2, magenta, magenta, magenta, magenta, magenta, magenta]
    missing = got[:, 6:]
    assert np.array_equal(missing, np.repeat(MISSING_TILE[:, None], missing.shape[1], axis=1))
    # the tile's own extension: CLIP reads black outside it, never the neighbouring tile
    clip = texture_lookup(udim, np.array([-0.25], np.float32), np.array([0.5], np.float32), 'Closest', 'CLIP')
    assert clip[0, 0] == 0
    with pytest.raises(ValueError, match="UDIM texels"):
        udim.with_texels(np.zeros((1, 3, 4), np.float32))


def test_udim_texture_renders_per_tile():
    """A UdimTiles material texture goes through the integrator: each tile's albedo where its
    UVs fall, magenta (1, 0, 1) x base colour where no tile is."""
    scene = plane_scene([light('SUN', np.pi, np.eye(4))], samples=4)
    udim = UdimTiles.stack({1001: np.full((1, 1, 4), 0.5, np.float32), 1002: np.full((1, 1, 4), 0.25, np.float32)})
    for uv, expect in (((0.5, 0.5), 0.5), ((1.5, 0.5), 0.25), ((0.5, 1.5), None)):
        scene.geometry.uvs = np.tile(np.array(uv, np.float32), (2, 3, 1))
        scene.materials[1] = material('udim', (0.8, 0.4, 0.2), texture=udim)
        rgb = render(scene).film.combined()[..., :3]
        want = np.array([0.8, 0.4, 0.2]) * (MISSING_TILE if expect is None else expect)
        assert np.allclose(rgb, want, rtol=1e-5, atol=1e-7), (uv, rgb.reshape(-1, 3)[0], want)


def test_textured_albedo_multiplies_base_colour():
    scene = plane_scene([light('SUN', np.pi, np.eye(4))], samples=4)
    tex = np.full((1, 1, 4), 0.5, np.float32)
    scene.geometry.uvs = np.zeros((2, 3, 2), np.float32)
    scene.materials[1] = material('tex', (0.8, 0.4, 0.2), texture=tex)
    assert np.allclose(render(scene).film.combined()[..., :3], [0.4, 0.2, 0.1], rtol=1e-5)


def test_texture_transform_moves_the_lookup():
    """The material's (2, 3) texture transform maps the UV map before the lookup: a shift by
    half the width reads the texel to the right; a transform of the wrong shape is refused."""
    scene = plane_scene([light('SUN', np.pi, np.eye(4))], samples=4)
    tex = np.ones((2, 2, 4), np.float32)
    tex[0, 0, :3], tex[0, 1, :3] = (0.2, 0.3, 0.4), (0.6, 0.5, 0.1)
    scene.geometry.uvs = np.full((2, 3, 2), 0.25, np.float32)
    scene.materials[1] = material('tex', (1.0, 1.0, 1.0), texture=tex, texture_interpolation='Closest')
    assert np.allclose(render(scene).film.combined()[..., :3], [0.2, 0.3, 0.4], rtol=1e-5)
    scene.materials[1].texture_transform = np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.0]])
    assert np.allclose(render(scene).film.combined()[..., :3], [0.6, 0.5, 0.1], rtol=1e-5)
    scene.materials[1].texture_transform = np.eye(2)
    with pytest.raises(ValueError, match="texture_transform must be"):
        render(scene)


# --- smooth normals -----------------------------------------------------------------------------

def test_smooth_normals_shade_with_the_interpolated_normal():
    """Corner normals tilted by 45 degrees about X: a sun from +Z sees cos 45 on the plane."""
    scene = plane_scene([light('SUN', 3.0, np.eye(4))], samples=4)
    n = np.array([0.0, -np.sqrt(0.5), np.sqrt(0.5)], np.float32)
    scene.geometry.normals[:] = n
    img = render(scene).film.combined()[..., 0]
    assert img == pytest.approx(0.8 * 3.0 * np.sqrt(0.5) / np.pi, rel=1e-5)


def test_cancel_is_polled_per_bounce_and_drops_the_unfinished_pass():
    """A pass of very long paths (inside a closed sphere of albedo 0.999, 1000 bounces) polls
    check_break between bounces: Esc stops it within a bounce, and its partial samples do not
    reach the film (the completed passes stay)."""
    v, t = icosphere(5.0, subdiv=2)
    t = t[:, ::-1].copy()                                  # facing inward: the camera is inside
    mats = [material('default'), material('furnace', (0.999,) * 3, emission=(1.0, 1.0, 1.0))]
    scene = sd.SceneData(ortho_down(height=0.0, width=8, px=8, view=1.0), geometry([(v, t, 1, ALL_VIS)]),
                         mats, [], np.zeros(3, np.float32),
                         sd.Settings(samples=4, max_bounces=1000, passes=('Depth',), cryptomatte=('CryptoObject',)))
    state = {'armed': False, 'polls': 0}

    def check_break():                                   # Esc 5 bounces into the second pass
        state['polls'] += state['armed']
        return state['polls'] > 5
    integ = Integrator(scene, paths_per_pass=8 * 8 * 2, check_break=check_break)
    done = []
    for p in integ.passes():
        done.append(p.samples_done)
        state['armed'] = True
    assert done == [2], done                              # the first pass (2 samples) only
    assert state['polls'] == 6                            # stopped at the first poll after Esc
    img = integ.film.combined()
    assert np.all(img[..., 0] > 1.0)                      # the first pass's samples are there
    full = render(scene, paths_per_pass=8 * 8 * 2)
    first = Integrator(scene, paths_per_pass=8 * 8 * 2)
    steps = first.passes()
    next(steps)
    steps.close()
    assert np.array_equal(img, first.film.combined())     # exactly the first pass, nothing more
    assert not np.array_equal(img, full.film.combined())
    # nor its Cryptomatte coverage or sample-0 passes (coverage had reached 1.25 a pixel)
    crypto = integ.film.cryptomatte_images()['CryptoObject00']
    assert np.allclose(crypto[..., 1], 1.0)
    assert np.array_equal(crypto, first.film.cryptomatte_images()['CryptoObject00'])
    assert np.array_equal(integ.film.pass_image('Depth'), first.film.pass_image('Depth'))



def test_cancel_inside_a_trace_drops_the_unfinished_pass(monkeypatch):
    """Esc while the tracer runs a batch: the trace asks check_break itself (dacrt's `cancel`)
    and stops part-way, without waiting for the bounce to end; the pass is dropped as at a
    bounce, the completed one stays."""
    import inspect
    monkeypatch.setattr(dacrt, "CANCEL_POLL_SECONDS", 0.0)      # ask at every step of a trace
    scene = plane_scene([light('POINT', 100.0, translation(z=2.0))], samples=4)
    state = {'armed': False, 'inside': 0}

    def check_break():                                   # Esc inside the second pass's first trace
        if not state['armed']:
            return False
        inside = any(f.function in ('_intersect', '_occluded_rays') for f in inspect.stack()[1:4])
        state['inside'] += inside
        return inside
    integ = Integrator(scene, paths_per_pass=scene.camera.width * scene.camera.height * 2, check_break=check_break)
    done = []
    for p in integ.passes():
        done.append(p.samples_done)
        state['armed'] = True
    assert done == [2] and state['inside'] == 1, (done, state)
    first = Integrator(scene, paths_per_pass=scene.camera.width * scene.camera.height * 2)
    steps = first.passes()
    next(steps)
    steps.close()
    assert np.array_equal(integ.film.combined(), first.film.combined())


def test_film_exposure_scales_light_not_alpha_or_data():
    """Cycles' Film > Exposure: Combined RGB, the light passes and light groups scale by it;
    alpha and the data passes (Diffuse Color, Depth) do not."""
    passes = ('DiffCol', 'DiffDir', 'Emit', 'Depth')
    base = render(plane_scene([light('POINT', 100.0, translation(z=2.0))], samples=4, passes=passes,
                              film_transparent=True)).film
    lit = render(plane_scene([light('POINT', 100.0, translation(z=2.0))], samples=4, passes=passes,
                             film_transparent=True, film_exposure=2.5)).film
    a, b = base.combined(), lit.combined()
    assert a[..., :3].max() > 0 and np.allclose(b[..., :3], 2.5 * a[..., :3], rtol=1e-6)
    assert np.array_equal(a[..., 3], b[..., 3])
    assert np.allclose(lit.pass_image('DiffDir'), 2.5 * base.pass_image('DiffDir'), rtol=1e-6)
    for name in ('DiffCol', 'Depth'):
        assert np.array_equal(lit.pass_image(name), base.pass_image(name)), name
    with pytest.raises(ValueError, match="exposure"):
        render(plane_scene(samples=1, film_exposure=-1.0))


def test_attribute_colours_multiply_the_albedo_per_point():
    """A material with color_attribute: its albedo times the triangle's interpolated
    Geometry.colors, for light and the Diffuse Color pass alike; other materials ignore them.
    Under a sun of strength E straight down: L = E / pi x albedo x colour."""
    scene = plane_scene([light('SUN', 3.0, np.eye(4))], samples=4, max_bounces=0, passes=('DiffCol',))
    plain = render(scene).film
    scene.materials[1].color_attribute = 'Col'
    c = np.array([0.5, 0.25, 1.0], np.float32)
    scene.geometry.colors = np.broadcast_to(c, (len(scene.geometry.triangles), 3, 3)).copy()
    coloured = render(scene).film
    assert np.allclose(plain.combined()[..., :3], 3.0 / np.pi * 0.8, rtol=1e-5)
    assert np.allclose(coloured.combined()[..., :3], 3.0 / np.pi * 0.8 * c, rtol=1e-5)
    assert np.allclose(coloured.pass_image('DiffCol'), 0.8 * c, rtol=1e-5)
    scene.materials[1].color_attribute = None                  # not read by other materials
    assert np.allclose(render(scene).film.combined(), plain.combined())
