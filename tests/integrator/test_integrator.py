"""The render loop: determinism, pass blocking, robustness (NaN, empty scenes, bad input),
ray visibility, holdout and transparency, data passes, textures and the engine-facing API."""
import numpy as np
import pytest

import dacrt
from addon import scenedata as sd
from addon.integrator import Integrator, Progress, offset_ray_origin, texture_lookup, triangle_offsets

from .scenes import (ALL_VIS, cornell_box, geometry, light, material, ortho_down, plane_scene, quad,
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
    assert integ.film.nan_dropped > 0 and integ.stats['nan_dropped'] == integ.film.nan_dropped
    counts = integ.film.sample_counts()
    assert counts.min() < 16 and counts.max() == 16
    assert any('NaN' in text for _, text in integ.messages)


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

@pytest.mark.parametrize('size,height', [(1000.0, 0.0), (1.0, 0.0), (0.01, 3000.0), (1e-4, 1e-5)])
def test_offset_rays_never_rehit_their_triangle(size, height):
    """Rays leaving a two-triangle plane (huge, tiny, or far from the origin) from random surface
    points into the upper hemisphere must never hit the plane; nor may rays aimed at points on
    it stop short (shadow rays end at an offset point in front of it)."""
    v, t = quad((0.0, 0.0, height), size, size)
    scene = dacrt.Scene(v.astype(np.float32), t.astype(np.int32))
    rng = np.random.default_rng(0)
    n = 20000
    u = rng.random((2, n)).astype(np.float32)
    vf = v.astype(np.float32)
    P = (vf[0][:, None] + (vf[1] - vf[0])[:, None] * u[0] + (vf[3] - vf[0])[:, None] * u[1]).astype(np.float32)
    ng = np.zeros((3, n), np.float32)
    ng[2] = 1.0
    mag = np.full(n, np.abs(vf).max(), np.float32)
    O = offset_ray_origin(P, ng, mag)
    # the render loop's per-triangle form gives the same points
    step = triangle_offsets(vf[t], np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]], np.float32))
    assert np.array_equal(P + step[:, :1], O)
    d = rng.normal(size=(3, n))
    d[2] = np.abs(d[2]) + 1e-3
    d /= np.linalg.norm(d, axis=0)
    assert not scene.occluded(dacrt.make_rays(O.T, d.T)).any()
    # from above, aim at offset points on the plane: never occluded by the plane itself
    src = P + np.float32(size) * d.astype(np.float32)
    aim = O - src
    dist = np.linalg.norm(aim, axis=0)
    assert not scene.occluded(dacrt.make_rays(src.T, (aim / dist).T, dist.astype(np.float32))).any()


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


def test_visibility_bits():
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
    img = render(roofed(sd.VIS_SHADOW, max_bounces=0)).film.combined()[..., 0]
    assert img.max() == 0.0


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


def test_textured_albedo_multiplies_base_colour():
    scene = plane_scene([light('SUN', np.pi, np.eye(4))], samples=4)
    tex = np.full((1, 1, 4), 0.5, np.float32)
    scene.geometry.uvs = np.zeros((2, 3, 2), np.float32)
    scene.materials[1] = material('tex', (0.8, 0.4, 0.2), texture=tex)
    assert np.allclose(render(scene).film.combined()[..., :3], [0.4, 0.2, 0.1], rtol=1e-5)


# --- smooth normals -----------------------------------------------------------------------------

def test_smooth_normals_shade_with_the_interpolated_normal():
    """Corner normals tilted by 45 degrees about X: a sun from +Z sees cos 45 on the plane."""
    scene = plane_scene([light('SUN', 3.0, np.eye(4))], samples=4)
    n = np.array([0.0, -np.sqrt(0.5), np.sqrt(0.5)], np.float32)
    scene.geometry.normals[:] = n
    img = render(scene).film.combined()[..., 0]
    assert img == pytest.approx(0.8 * 3.0 * np.sqrt(0.5) / np.pi, rel=1e-5)
