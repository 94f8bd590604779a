"""Light units against closed-form irradiance: a diffuse plane (albedo 0.8) seen from above by a
tiny orthographic camera, pixel value = albedo * E / pi (reference blender-cycles.md 2.2, whose
table also lists Cycles' own numbers for the same setups)."""
import dataclasses
import functools

import dacrt
import numpy as np
import pytest

from addon import scenedata as sd
from addon.lights import lamp_records, make_lamp
from addon.sampling import RandomStream

from .scenes import (cornell_box, light, material, ortho_down, pixel_stats, plane_scene, render, rotation_x,
                     translation)

RHO = 0.8


def check(integ, expected, rel=0.01):
    mean, err = pixel_stats(integ)
    assert err < 0.3 * rel * expected, f"too noisy to decide: stderr {err:.5f} for {expected:.5f}"
    assert mean == pytest.approx(expected, rel=rel), f"got {mean:.5f}, expected {expected:.5f} (+-{err:.5f})"
    return mean


def lit(lights, samples=256, **kw):
    return render(plane_scene(lights, samples=samples, **kw))


@pytest.mark.parametrize('angle_deg', [0.0, 20.0])
def test_sun_irradiance_at_normal_incidence(angle_deg):
    sun = light('SUN', 3.0, np.eye(4), angle=np.radians(angle_deg))
    mean = check(lit([sun], samples=64 if angle_deg == 0 else 256), RHO * 3.0 / np.pi)
    assert mean == pytest.approx(0.76394, rel=0.01)            # Cycles 5.0.1: 0.76395 / 0.76393


def test_sun_delta_is_exact_and_obeys_cosine():
    tilt = np.radians(60.0)
    sun = light('SUN', 3.0, rotation_x(tilt))
    integ = lit([sun], samples=4)
    assert integ.film.combined()[..., 0] == pytest.approx(RHO * 3.0 * np.cos(tilt) / np.pi, rel=1e-5)


def test_point_light_radius_zero():
    integ = lit([light('POINT', 1000.0, translation(z=2.0))], samples=4)
    expected = RHO * 1000.0 / (4 * np.pi * 4.0) / np.pi
    assert expected == pytest.approx(5.06606, rel=1e-5)
    assert integ.film.combined()[..., 0] == pytest.approx(expected, rel=1e-5)


def test_point_light_sphere_matches_point():
    sphere = light('POINT', 1000.0, translation(z=2.0), radius=0.5, soft_falloff=False)
    check(lit([sphere]), RHO * 1000.0 / (16 * np.pi) / np.pi)     # Cycles: 5.06604


def test_point_light_soft_falloff_disk():
    # disk of radius r facing the point, radiance Phi / (4 pi^2 r^2): E = Phi / (4 pi (r^2 + h^2))
    soft = light('POINT', 1000.0, translation(z=2.0), radius=0.5, soft_falloff=True)
    expected = RHO * 1000.0 / (4 * np.pi * (0.25 + 4.0)) / np.pi
    assert expected == pytest.approx(4.76812, rel=1e-4)        # Cycles: 4.76785
    check(lit([soft]), expected)


def test_spot_on_axis_equals_point():
    spot = light('SPOT', 1000.0, translation(z=2.0), spot_size=np.radians(45.0), spot_blend=0.5)
    integ = lit([spot], samples=4)
    assert integ.film.combined()[..., 0] == pytest.approx(5.06606, rel=1e-5)


def test_spot_off_axis_smoothstep():
    off = np.radians(20.0)
    x = 2.0 * np.tan(off)
    spot = light('SPOT', 1000.0, translation(z=2.0), spot_size=np.radians(45.0), spot_blend=0.5)
    integ = render(plane_scene([spot], samples=4, camera=ortho_down(target=(x, 0.0))))
    cos_half = np.cos(np.radians(22.5))
    f = (np.cos(off) - cos_half) / ((1 - cos_half) * 0.5)
    d2 = 4.0 + x * x
    expected = RHO * 1000.0 * np.cos(off) / (4 * np.pi * d2) / np.pi * (3 * f * f - 2 * f ** 3)
    assert expected == pytest.approx(1.57394, rel=1e-4)        # Cycles: 1.57389
    # the 1 mm wide view spans a slope of the smoothstep: compare the mean
    assert integ.film.combined()[..., 0].mean() == pytest.approx(expected, rel=1e-3)


def test_sphere_spot_does_not_shape_points_inside_it():
    """Cycles (light/spot.h) applies a sphere spot's cone only outside the sphere: a point inside
    sees the sphere's radiance L = P / (4 pi^2 r^2) over its whole upper hemisphere, E = pi L,
    whatever the cone (here a 60 degree spot pointing down from 0.4 above the plane, radius 0.5;
    the tester's case, 52% dark when the cone shaped it). The camera is inside the sphere too."""
    spot = light('SPOT', 1000.0, translation(z=0.4), radius=0.5, soft_falloff=False,
                 spot_size=np.radians(60.0), spot_blend=0.2)
    integ = render(plane_scene([spot], samples=256, camera=ortho_down(height=0.05, target=(0.1, -0.05))))
    check(integ, RHO * 1000.0 / (4 * np.pi ** 2 * 0.25))


def test_spot_outside_cone_is_dark_and_sends_no_shadow_rays():
    spot = light('SPOT', 1000.0, translation(z=2.0), spot_size=np.radians(30.0), spot_blend=0.2)
    integ = render(plane_scene([spot], samples=4, camera=ortho_down(target=(3.0, 0.0))))
    assert integ.film.combined()[..., 0].max() == 0.0
    assert integ.stats['rays']['shadow'] == 0
    assert integ.stats['shadow_rays_skipped'] == integ.stats['rays']['camera']


def rect_irradiance(L, a, b, h):
    """Irradiance below a corner of an a x b Lambertian rectangle at height h (radiance L)."""
    A, B = a / np.hypot(a, h), b / np.hypot(b, h)
    return 0.5 * L * (A * np.arctan(b / np.hypot(a, h)) + B * np.arctan(a / np.hypot(b, h)))


AREA_AT_1M = {
    # E below the centre: square = 4 corner rectangles; disk: E = pi L R^2 / (R^2 + h^2)
    'SQUARE': (RHO * 4 * rect_irradiance(100.0 / np.pi, 0.5, 0.5, 1.0) / np.pi, 6.09771),     # Cycles: 6.09866
    'DISK': (RHO * 100.0 / (np.pi * np.pi / 4) * 0.25 / (0.25 + 1.0), 6.48456),               # Cycles: 6.48481
}


@pytest.mark.parametrize('use_mis', [True, False])
@pytest.mark.parametrize('shape', list(AREA_AT_1M))
def test_area_light_at_one_metre_is_unbiased(shape, use_mis):
    """1 m square / disk light 1 m above the plane, within 0.15% of the closed form.

    With MIS, BSDF rays that leave the plane find the light too, so they must start where light
    sampling assumes the surface is: bounce origins pushed 1.5 cm up (256 ULPs of the 2 km
    plane's coordinates) made these +0.45% / +0.33%. 32 x 32 independent pixels x 1024 samples
    (fixed seed) give a standard error of about 0.018% (checked below to be at most 0.025%), so
    0.15% is at least 6 standard errors: a correct renderer fails it with any seed at odds below
    1e-9, while the old bias is over 10 standard errors outside it."""
    expected, rounded = AREA_AT_1M[shape]
    assert expected == pytest.approx(rounded, rel=1e-5)
    area = light('AREA', 100.0, translation(z=1.0), shape=shape, size_x=1.0, use_mis=use_mis)
    integ = render(plane_scene([area], samples=1024, seed=11, camera=ortho_down(width=32, px=32)))
    mean, err = pixel_stats(integ)
    assert err < 2.5e-4 * expected, f"too noisy to decide: stderr {err:.5f}"
    assert mean == pytest.approx(expected, rel=1.5e-3), f"got {mean:.5f}, expected {expected:.5f} (+-{err:.5f})"


def test_area_light_over_a_tilted_2km_plane():
    """The same square light with the whole set-up turned by an arbitrary rotation: the plane's
    coordinates now all carry rounding, so bounce and shadow rays rely on the offset and skip
    (no acne, no leaks) while the origins must still stay close enough not to bias MIS."""
    q, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
    R = np.eye(4)
    R[:3, :3] = q * np.sign(np.linalg.det(q))
    scene = plane_scene([light('AREA', 100.0, R @ translation(z=1.0), size_x=1.0)], samples=1024, seed=5,
                        camera=ortho_down(width=32, px=32))
    scene.geometry.vertices = (scene.geometry.vertices.astype(np.float64) @ R[:3, :3].T).astype(np.float32)
    scene.geometry.normals = (scene.geometry.normals.astype(np.float64) @ R[:3, :3].T).astype(np.float32)
    scene.camera.matrix = R @ scene.camera.matrix
    integ = render(scene)
    expected = AREA_AT_1M['SQUARE'][0]
    mean, err = pixel_stats(integ)
    assert err < 2.5e-4 * expected
    assert mean == pytest.approx(expected, rel=1.5e-3), f"got {mean:.5f}, expected {expected:.5f} (+-{err:.5f})"


@pytest.mark.parametrize('half,height', [(0.5, 1.0), (0.05, 1.0), (4.0, 0.25)])
def test_emissive_quad_irradiance(half, height):
    """An emissive mesh quad (2 triangles, black, radiance 10) above the plane, against the
    closed form: 1 m at 1 m and 8 m at 25 cm are sampled by solid angle from below, 10 cm at
    1 m by area. Within 0.5% (about 6 standard errors at 1024 samples x 16 x 16 pixels)."""
    from .scenes import ALL_VIS, geometry, quad
    scene = plane_scene(samples=1024, seed=3, camera=ortho_down(height=height / 2, width=16, px=16))
    scene.materials.append(material('glow', (0.0,) * 3, (10.0,) * 3))
    plane = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    scene.geometry = geometry([(*plane, 1, ALL_VIS), (*quad((0.0, 0.0, height), half, half, up=False), 2, ALL_VIS)])
    expected = RHO * 4 * rect_irradiance(10.0, half, half, height) / np.pi
    integ = render(scene)
    mean, err = pixel_stats(integ)
    assert err < 1e-3 * expected, f"too noisy to decide: stderr {err:.5f}"
    assert mean == pytest.approx(expected, rel=5e-3), f"got {mean:.5f}, expected {expected:.5f} (+-{err:.5f})"


def test_area_rectangle_scaled_object():
    m = translation(z=1.0) @ np.diag([2.0, 0.5, 1.0, 1.0])      # object scale enters the size
    area = light('AREA', 50.0, m, shape='RECTANGLE', size_x=0.5, size_y=1.0)
    L = 50.0 / (np.pi * 1.0 * 0.5)
    check(lit([area], samples=512), RHO * 4 * rect_irradiance(L, 0.5, 0.25, 1.0) / np.pi)




@pytest.mark.parametrize('shape', ['RECTANGLE', 'ELLIPSE'])
def test_area_sheared_is_the_parallelogram_it_spans(shape):
    """A rotated child of a non-uniformly scaled parent: a sheared matrix. The lamp is the
    parallelogram its axes span (or the ellipse inside it) emitting on the side of -z: the
    plane's light equals that of an emissive mesh of that shape and radiance, and light sampling
    alone (MIS off) agrees with MIS (an inconsistent normal, area or local frame would not)."""
    c, s_ = np.cos(0.6), np.sin(0.6)
    turn = np.array([[c, -s_, 0, 0], [s_, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    m = translation(z=0.8) @ np.diag([2.0, 0.5, 1.0, 1.0]) @ turn @ rotation_x(0.3)
    area = light('AREA', 40.0, m, shape=shape, size_x=0.6, size_y=0.9)
    lamp = make_lamp(area)
    assert lamp.sheared
    ax, ay = lamp.axis_x.astype(np.float64), lamp.axis_y.astype(np.float64)
    assert lamp.area == pytest.approx(np.linalg.norm(np.cross(ax, ay)) * (np.pi / 4 if shape == 'ELLIPSE' else 1))
    # the same shape as a mesh: a fan around the centre (64 segments for the ellipse)
    k = 64 if shape == 'ELLIPSE' else 4
    t = 2 * np.pi * (np.arange(k) + 0.5) / k
    rim = (np.stack([np.cos(t), np.sin(t)], 1) * 0.5 if shape == 'ELLIPSE'
           else np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]))
    centre = m[:3, 3]
    verts = np.concatenate([[centre], centre + rim[:, :1] * ax + rim[:, 1:] * ay])
    fan = np.array([(0, 1 + i, 1 + (i + 1) % k) for i in range(k)])
    mesh_area = 0.5 * np.linalg.norm(np.cross(verts[fan[:, 1]] - verts[fan[:, 0]],
                                              verts[fan[:, 2]] - verts[fan[:, 0]]), axis=1).sum()
    radiance = 40.0 / (np.pi * mesh_area)
    base = plane_scene([], samples=512, camera=ortho_down(height=0.3, width=16, px=16, view=1.5))
    from .scenes import ALL_VIS, geometry, quad
    v0, t0 = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    glow = material('glow', (0.0, 0.0, 0.0), emission=(radiance,) * 3)
    mesh = dataclasses.replace(base, materials=base.materials + [glow],
                               geometry=geometry([(v0, t0, 1, ALL_VIS), (verts, fan, 2, ALL_VIS)]))
    ref, ref_err = pixel_stats(render(mesh))
    for use_mis in (True, False):
        lamp_scene = dataclasses.replace(base, lights=[dataclasses.replace(area, use_mis=use_mis)])
        mean, err = pixel_stats(render(lamp_scene))
        assert ref > 0.05 and abs(mean - ref) < 4 * np.hypot(err, ref_err) + 2e-3 * ref, (use_mis, mean, ref, err)


def test_area_is_one_sided():
    down = light('AREA', 100.0, translation(z=1.0) @ rotation_x(np.pi), size_x=1.0)   # emits +Z
    integ = lit([down], samples=16)
    assert integ.film.combined()[..., 0].max() == 0.0


def test_area_unnormalized_radiance():
    area = light('AREA', 10.0, translation(z=1.0), size_x=0.5, normalize=False)
    check(lit([area], samples=512), RHO * 4 * rect_irradiance(10.0 / np.pi, 0.25, 0.25, 1.0) / np.pi)


@functools.lru_cache(maxsize=None)
def spread_irradiance(radiance, half_x, half_y, ellipse, spread, P, n_r=(0.0, 0.0, 1.0), k=1000):
    """Irradiance at P (receiver normal n_r) from an axis-aligned light facing -Z whose centre is
    at the origin of x, y and at height z = 0 (P below it, P[2] < 0), world half extents half_x,
    half_y, radiance `radiance` times the spread profile f. Independent of the sampler: midpoint
    quadrature in polar coordinates about P's foot, over the disk of radius h tan(s/2) outside
    which f is 0 by definition (tan theta = rho / h), times the light's indicator. Within 1e-4
    (against k = 4000) where the disk is cut by the light's outline, to 1e-5 elsewhere."""
    h = -P[2]
    th = spread / 2
    r = h * np.tan(th)
    rho = (np.arange(k) + 0.5) / k * r
    phi = (np.arange(2 * k) + 0.5) / (2 * k) * 2 * np.pi
    R, PH = np.meshgrid(rho, phi)
    dx, dy = R * np.cos(PH), R * np.sin(PH)
    x, y = P[0] + dx, P[1] + dy
    on = ((x / half_x) ** 2 + (y / half_y) ** 2 <= 1) if ellipse else ((np.abs(x) <= half_x) & (np.abs(y) <= half_y))
    f = np.maximum(np.tan(th) - R / h, 0.0) / (np.tan(th) - th)
    t = np.sqrt(R * R + h * h)
    n = np.asarray(n_r, np.float64) / np.linalg.norm(n_r)
    cos_r = np.maximum((n[0] * dx + n[1] * dy + n[2] * h) / t, 0.0)
    return np.sum(radiance * f * (h / t) * cos_r / (t * t) * R * on) * (r / k) * (np.pi / k)


@pytest.mark.parametrize('spread_deg,target', [(60.0, (0.0, 0.0)), (5.0, (0.0, 0.0)), (5.0, (0.48, 0.3)),
                                               (1.0, (0.0, 0.2)), (1.0, (0.497, -0.4985)), (1.0, (0.6, 0.0)),
                                               (0.05, (0.0, 0.2)), (0.005, (0.1, -0.3))])
def test_area_spread_against_quadrature(spread_deg, target):
    """Rendered (light samples and BSDF rays with MIS) under a 1 m square at 1 m: below the centre
    and, for narrow spreads, where the spread's square about the pixel's foot is clamped by an
    edge, by a corner, or misses the light (black). At 1 degree the old sampler (uniform over the
    whole light) found the 9 mm radius spot that can reach a point with 1 sample in 4000: 86 of 91
    lit pixels were 0 at 16 spp, and the noise check in `check` fails it at every narrow case here.
    Below ~0.2 degrees the profile's tan(theta) from 1 - cos^2 in float32 was lost to rounding
    (0.057 degrees rendered 1.9x too bright); it now comes from |w x n| / cos."""
    spread = np.radians(spread_deg)
    area = light('AREA', 100.0, translation(z=1.0), size_x=1.0, spread=spread)
    P = (*target, -1.0)
    E = spread_irradiance(100.0 / np.pi, 0.5, 0.5, False, spread, P)
    if spread_deg == 60.0:
        # independent 2-D midpoint quadrature of L f(theta) cos_l cos_r / t^2 over the square
        k = 801
        g = (np.arange(k) + 0.5) / k - 0.5
        x, y = np.meshgrid(g, g)
        t2 = x * x + y * y + 1.0
        cos = 1.0 / np.sqrt(t2)
        tan_t = np.sqrt(x * x + y * y)
        h = spread / 2
        f = np.maximum(np.tan(h) - tan_t, 0.0) / (np.tan(h) - h)
        E_grid = np.sum(100.0 / np.pi * f * cos * cos / t2) / (k * k)
        assert E == pytest.approx(E_grid, rel=1e-4)
    # a 0.1 mm view where E changes within millimetres
    integ = lit([area], samples=4096 if spread_deg == 60.0 else 1024,
                camera=ortho_down(target=target, view=1e-3 if spread_deg == 60.0 else 1e-4))
    if E == 0:
        assert integ.film.combined()[..., 0].max() == 0.0
        assert integ.stats['rays']['shadow'] == 0
    else:
        check(integ, RHO * E / np.pi)


SPREAD_SHAPES = {'RECTANGLE': dict(shape='RECTANGLE', size_x=1.0, size_y=0.6),   # world 1.5 x 0.6
                 'ELLIPSE': dict(shape='ELLIPSE', size_x=0.8, size_y=1.0)}       # world 1.2 x 1.0
SPREAD_CENTRE = np.array([0.1, -0.2, 1.0])
SPREAD_MATRIX = translation(*SPREAD_CENTRE) @ np.diag([1.5, 1.0, 1.0, 1.0])


def spread_points(half_x, half_y, spread):
    """Shading points (offsets from the light's centre, x, y, then -h) where the spread's square
    of half-size r = h tan(s/2) about the foot is: inside the light; cut by an edge; cut by a
    corner (for an ellipse: off it); past the edge but still reaching in; wholly off the light;
    and (h such that r covers everything) the whole light."""
    th = spread / 2
    r = np.tan(th)                                   # h = 1
    far = 2.0 * max(half_x, half_y) / np.tan(th)
    return {'inside': (0.2 * half_x, -0.3 * half_y, -1.0), 'edge': (half_x - 0.5 * r, 0.0, -1.0),
            'corner': (half_x - 0.3 * r, half_y - 0.4 * r, -1.0), 'past_edge': (0.1 * half_x, -half_y - 0.5 * r, -1.0),
            'empty': (half_x + 1.5 * r, 0.0, -1.0), 'whole': (0.1 * half_x, 0.05 * half_y, -far)}


def irradiance_samples(lamp, P, n_r, n, native, seed=1):
    """Per-sample light-sampling estimates of the irradiance at P: value x max(cos_r, 0)."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random((2, n), np.float32)
    Pn = np.repeat(np.asarray(P, np.float32)[:, None], n, axis=1)
    if native:
        wi, _, value, pdf = dacrt.lamps.lamp_sample(lamp_records([lamp]), np.zeros(n, np.int32), Pn, u1, u2)
    else:
        ls = lamp.sample(Pn, u1, u2)
        wi, value, pdf = ls.wi, ls.value, ls.pdf
    n_r = np.asarray(n_r, np.float64) / np.linalg.norm(n_r)
    return value[0].astype(np.float64) * np.maximum(n_r @ wi.astype(np.float64), 0.0), pdf


@pytest.mark.parametrize('native', [False, True], ids=['python', 'native'])
@pytest.mark.parametrize('spread_deg', [1.0, 5.0, 30.0])
@pytest.mark.parametrize('shape', list(SPREAD_SHAPES))
def test_area_spread_estimator_against_quadrature(shape, spread_deg, native):
    """pbrt-style check of the light-sampling estimator alone (no MIS, no render): at points where
    the spread's square is whole, clamped by an edge or a corner, reaches in from outside, misses
    the light, or covers it all, the mean of value x cos_r (receiver tilted) over 400k samples
    matches the quadrature within 5 standard errors (+3e-4 for the quadrature), and the standard
    error is below 0.5% (the test decides something). Where nothing can reach (the square off
    the light, or at narrow spreads off the ellipse by its bounding rectangle's corner), every
    sample is exactly 0 with pdf 0."""
    kw = SPREAD_SHAPES[shape]
    half_x, half_y = 0.75 * kw['size_x'], 0.5 * kw['size_y']
    ellipse = shape == 'ELLIPSE'
    spread = np.radians(spread_deg)
    lamp = make_lamp(light('AREA', 100.0, SPREAD_MATRIX, spread=spread, **kw))
    n_r = (0.3, -0.2, 1.0)
    lit_points = 0
    for where, off in spread_points(half_x, half_y, spread).items():
        E = spread_irradiance(100.0 / (np.pi * lamp.area), half_x, half_y, ellipse, spread, off, n_r)
        v, pdf = irradiance_samples(lamp, SPREAD_CENTRE + off, n_r, 400_000, native)
        assert (E == 0) == (where == 'empty' or (ellipse and where == 'corner' and spread_deg < 10))
        if E == 0:
            assert not v.any() and not pdf.any(), f'{where}: light where none can reach'
            continue
        lit_points += 1
        mean, err = v.mean(), v.std() / np.sqrt(len(v))
        assert err < 5e-3 * E, f'{where}: too noisy to decide: {mean} +- {err}'
        assert abs(mean - E) < 5 * err + 3e-4 * E, f'{where}: {mean} +- {err}, quadrature {E}'
    assert lit_points >= 4


def test_narrow_spread_samples_only_where_the_light_reaches():
    """2 degree spread, 1 m square at 1 m: the light within reach of a point is a 3.5 cm spot.
    Uniform over the whole light (the old sampler, computed here) 1 sample in 1000 lands in it,
    a per-sample relative standard deviation ~38; sampling the spread's square gives ~1."""
    spread = np.radians(2.0)
    lamp = make_lamp(light('AREA', 100.0, translation(z=1.0), size_x=1.0, spread=spread))
    n = 200_000
    for x0 in (0.0, 0.49):                                       # below the centre, and cut by an edge
        P = np.array([x0, 0.0, 0.0])
        v, _ = irradiance_samples(lamp, P, (0.0, 0.0, 1.0), n, native=False)
        assert (v > 0).mean() > 0.7
        assert v.std() / v.mean() < 1.5
        # old: q uniform over the square, value = L f(theta) cos_l cos_r / (t^2 pdf_area)
        rng = np.random.default_rng(2)
        q = rng.random((2, n)) - 0.5
        d2 = (q[0] - x0) ** 2 + q[1] ** 2
        t2 = d2 + 1.0
        f = np.maximum(np.tan(spread / 2) - np.sqrt(d2), 0.0) / (np.tan(spread / 2) - spread / 2)
        old = 100.0 / np.pi * f / (t2 * t2)
        assert (old > 0).mean() < 0.002
        assert old.std() / old.mean() > 20


@pytest.mark.parametrize('spread_deg', [2.0, 10.0, 45.0])
@pytest.mark.parametrize('shape', ['RECTANGLE', 'ELLIPSE'])
def test_spread_intersect_pdf_equals_sample_pdf(shape, spread_deg):
    """MIS with the clamped sampling: a ray from the shading point along a light sample meets the
    light (intersect) with the radiance and pdf the sample reported, whether the spread's square
    is clamped (by the light or not) or, for an ellipse, covers it whole (concentric map). Rays
    toward any point of the light that intersect does not report are ones the spread profile
    gives 0 (the clamp loses no light)."""
    lamp = make_lamp(light('AREA', 50.0, translation(0.2, -0.1, 1.5) @ rotation_x(0.3), shape=shape,
                           size_x=0.7, size_y=0.4, spread=np.radians(spread_deg)))
    n = 20_000
    rng = np.random.default_rng(4)
    ox, oy = rng.uniform(-0.8, 0.8, (2, n))                      # feet, in the light's local coordinates
    h = rng.uniform(0.05, 3.0, n)
    P = (lamp.center[:, None] + lamp.normal[:, None] * h + lamp.axis_x[:, None] * ox
         + lamp.axis_y[:, None] * oy).astype(np.float32)
    r = h * np.tan(np.radians(spread_deg) / 2)
    rx, ry = r / np.linalg.norm(lamp.axis_x), r / np.linalg.norm(lamp.axis_y)
    whole = (ox - rx <= -0.5) & (ox + rx >= 0.5) & (oy - ry <= -0.5) & (oy + ry >= 0.5)
    if spread_deg == 45.0:
        assert 0.05 < whole.mean() < 0.95
    u1, u2 = rng.random((2, n), np.float32)
    ls = lamp.sample(P, u1, u2)
    good = np.flatnonzero(ls.value.max(axis=0) > 0)
    assert len(good) > n // 10
    D = np.ascontiguousarray(ls.wi[:, good])
    O = np.ascontiguousarray(P[:, good])
    idx, Le, pdf = lamp.intersect(O, D, np.full(len(good), np.inf, np.float32))
    assert len(idx) >= 0.999 * len(good)
    np.testing.assert_allclose(Le, (ls.value * ls.pdf)[:, good][:, idx], rtol=2e-3)
    np.testing.assert_allclose(pdf, ls.pdf[good][idx], rtol=2e-3)

    # rays toward points uniform over the light's bounding rectangle
    q = (lamp.center[:, None] + lamp.axis_x[:, None] * (u1 - 0.5) + lamp.axis_y[:, None] * (u2 - 0.5))
    D = (q - P).astype(np.float64)
    D /= np.linalg.norm(D, axis=0)
    D = D.astype(np.float32)
    idx, Le, pdf = lamp.intersect(P, D, np.full(n, np.inf, np.float32))
    assert np.isfinite(pdf).all() and (pdf > 0).all()
    lost = np.setdiff1d(np.arange(n), idx)
    cos_l = -(lamp.normal @ D[:, lost]).astype(np.float64)
    tan_t = np.sqrt(np.maximum(1 - cos_l * cos_l, 0)) / cos_l
    # off the light, or where f is 0 (up to the rounding of directions at the spread's edge)
    on = np.abs(u1[lost] - 0.5) <= 0.5
    if shape == 'ELLIPSE':
        on = (u1[lost] - 0.5) ** 2 + (u2[lost] - 0.5) ** 2 < 0.2499
    assert (tan_t[on] >= lamp.tan_half_spread * (1 - 1e-4)).all()


def test_world_uniform():
    integ = render(plane_scene(world=(1.0, 1.0, 1.0), samples=512))   # colour 0.5 x strength 2
    check(integ, RHO * 1.0)                                           # Cycles: 0.80000


def test_emission_seen_directly():
    scene = plane_scene(samples=4)
    scene.materials[1] = material('glow', (0.8,) * 3, (1.5, 1.5, 1.5))  # 0.3 x strength 5
    integ = render(scene)
    assert integ.film.combined()[..., 0] == pytest.approx(1.5, rel=1e-6)


def test_several_lights_add_up():
    lamps = [light('POINT', 1000.0, translation(z=2.0)), light('SUN', 3.0, np.eye(4)),
             light('AREA', 100.0, translation(z=1.0), size_x=1.0)]
    expected = RHO / np.pi * (1000.0 / (16 * np.pi) + 3.0 + 4 * rect_irradiance(100 / np.pi, 0.5, 0.5, 1.0))
    check(lit(lamps, samples=1024), expected)


def test_light_without_mis_is_counted_once():
    area = light('AREA', 100.0, translation(z=1.0), size_x=1.0, use_mis=False)
    check(lit([area], samples=1024), RHO * 4 * rect_irradiance(100 / np.pi, 0.5, 0.5, 1.0) / np.pi)


@pytest.mark.parametrize('cast_shadow', [True, False])
def test_cast_shadow(cast_shadow):
    """A roof between the light and the plane: dark when the light casts shadows, else ignored."""
    from .scenes import ALL_VIS, geometry, quad
    scene = plane_scene([light('POINT', 1000.0, translation(z=2.0), cast_shadow=cast_shadow)], samples=4)
    plane = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    roof = quad((0.0, 0.0, 1.5), 5.0, 5.0)
    scene.geometry = geometry([(*plane, 1, ALL_VIS), (*roof, 1, sd.VIS_DIFFUSE | sd.VIS_SHADOW)])
    value = render(scene).film.combined()[..., 0]
    assert value == pytest.approx(0.0 if cast_shadow else 5.06606, rel=1e-5, abs=1e-6)


LAMPS = [
    ('POINT', dict(radius=0.3, soft_falloff=False)),
    ('POINT', dict(radius=0.3, soft_falloff=True)),
    ('SPOT', dict(radius=0.3, soft_falloff=True, spot_size=np.radians(120.0), spot_blend=0.3)),
    ('AREA', dict(shape='RECTANGLE', size_x=0.7, size_y=0.4, spread=np.radians(100.0))),
    ('AREA', dict(shape='ELLIPSE', size_x=0.7, size_y=0.4)),
    ('SUN', dict(angle=np.radians(10.0))),
]


@pytest.mark.parametrize('kind,kw', LAMPS)
def test_sampled_directions_hit_the_light_with_the_same_pdf(kind, kw):
    """MIS needs one emitter seen two ways: a ray along each light sample must meet the light
    (intersect / eval_miss) with the same radiance and pdf the sample reported."""
    m = translation(0.2, -0.1, 1.5) @ rotation_x(0.3)
    lamp = make_lamp(light(kind, 50.0, m, **kw))
    n = 4000
    rs = RandomStream(7)
    keys = rs.path_keys(np.arange(n), np.zeros(n, np.int64))
    u1, u2 = rs.uniform2(keys, 0)
    P = np.zeros((3, n), np.float32)
    P[0] = np.linspace(-0.5, 0.5, n)
    ls = lamp.sample(P, u1, u2)
    good = np.flatnonzero(ls.value.max(axis=0) > 0)
    assert len(good) > n // 2
    Ls = ls.value[:, good] * ls.pdf[good]                     # radiance of the sample
    D = np.ascontiguousarray(ls.wi[:, good])
    O = np.ascontiguousarray(P[:, good])
    if lamp.at_infinity:
        idx, Le, pdf = lamp.eval_miss(D)
    else:
        idx, Le, pdf = lamp.intersect(O, D, np.full(len(good), np.inf, np.float32))
        # and not when the ray stops just short of the sampled point
        short = lamp.intersect(O, D, ls.dist[good] * np.float32(0.999))[0]
        assert len(short) <= 0.001 * len(good)
    assert len(idx) >= 0.999 * len(good)
    assert np.allclose(Le, Ls[:, idx], rtol=2e-3)
    assert np.allclose(pdf, ls.pdf[good][idx], rtol=2e-3)


def looking_up(lamp, **camera):
    """The plane is black; an orthographic camera at z = 0.5 looks straight up at the lamp."""
    cam = ortho_down(**camera)
    cam.matrix = translation(z=0.5) @ rotation_x(np.pi)
    return render(plane_scene([lamp], albedo=0.0, samples=16, camera=cam))


def test_lights_seen_by_camera():
    area = light('AREA', 100.0, translation(z=1.0), size_x=1.0)
    assert looking_up(area).film.combined()[..., 0] == pytest.approx(100.0 / np.pi, rel=1e-5)
    sphere = light('POINT', 1000.0, translation(z=2.0), radius=0.5, soft_falloff=False)
    assert looking_up(sphere).film.combined()[..., 0] == pytest.approx(1000.0 / (4 * np.pi ** 2 * 0.25), rel=1e-5)
    disk = light('POINT', 1000.0, translation(z=2.0), radius=0.5, soft_falloff=True)
    assert looking_up(disk).film.combined()[..., 0] == pytest.approx(1000.0 / (4 * np.pi ** 2 * 0.25), rel=1e-5)
    hidden = light('AREA', 100.0, translation(z=1.0), size_x=1.0, visible_camera=False)
    assert looking_up(hidden).film.combined()[..., 0].max() == 0.0
    back = light('AREA', 100.0, translation(z=1.0) @ rotation_x(np.pi), size_x=1.0)
    assert looking_up(back).film.combined()[..., 0].max() == 0.0      # one-sided
    # Cycles intersects no light whose MIS is off: camera rays do not see it either
    for lamp in (light('AREA', 100.0, translation(z=1.0), size_x=1.0, use_mis=False),
                 light('POINT', 1000.0, translation(z=2.0), radius=0.5, soft_falloff=False, use_mis=False)):
        assert looking_up(lamp).film.combined()[..., 0].max() == 0.0


def test_light_without_diffuse_visibility_lights_nothing():
    """Cycles excludes a light whose diffuse ray visibility is off from diffuse surfaces (light
    sampling and BSDF hits): only camera rays may still see it. It keeps its share of the light
    choice (lights/choiceonly.py), so beside a sun the sun is chosen less often: each sample
    is nothing or the sun's light over its probability."""
    kw = dict(size_x=1.0, visible_diffuse=False)
    integ = lit([light('AREA', 100.0, translation(z=1.0), visible_camera=True, **kw)], samples=16)
    assert integ.film.combined()[..., 0].max() == 0.0
    assert integ.stats['rays']['shadow'] == 0
    seen = looking_up(light('AREA', 100.0, translation(z=1.0), visible_camera=True, **kw))
    assert seen.film.combined()[..., 0] == pytest.approx(100.0 / np.pi, rel=1e-5)
    # with a light the diffuse rays do see, only that one lights the plane: the choice is
    # reweighed by what each lamp gives the view, and the stand-in gives nothing, so the sun
    # keeps all but the uniform part (0.8 + 0.2 / 2); each of a pixel's 64 samples is the sun's
    # light over that probability or nothing, so a pixel is a whole number of 1/64 of it, and
    # the (stratified) picks give the sun its probability's share of them
    both = lit([light('AREA', 100.0, translation(z=1.0), visible_camera=True, **kw),
                light('SUN', 3.0, np.eye(4))], samples=64)
    assert both.lights.num_entries == 2 and len(both.lights.hidden_lamps) == 1
    p = 0.8 + 0.2 / 2
    assert both.lights.lamp_prob[0] == pytest.approx(p, rel=1e-6)
    picks = both.film.combined()[..., 0] * 64 * p / (RHO * 3.0 / np.pi)
    np.testing.assert_allclose(picks, np.round(picks), atol=1e-3)
    assert np.abs(picks / 64 - p).max() <= 1.0 / 64
    unseen = lit([light('AREA', 100.0, translation(z=1.0), name='Ghost', visible_camera=False, **kw)], samples=4)
    assert unseen.film.combined()[..., 0].max() == 0.0
    assert any('Ghost' in text for _, text in unseen.messages)


def test_light_hidden_from_diffuse_rays_keeps_its_share_of_the_tree():
    """Its stand-in (lights/choiceonly.py) sits in the light tree with the lamp's own bounds and
    power, so the visible lamp beside it is picked as often as beside a visible twin of it (as
    Cycles picks it: fuzz seed 306), and its samples give nothing."""
    from addon.lights import LightSet
    key = make_lamp(light('POINT', 200.0, translation(0.5, 0.3, 2.2), radius=0.6, name='Key'))
    twin = light('POINT', 5000.0, translation(-3.0, 2.0, 3.0), radius=0.2, name='Hidden')
    hidden, seen = make_lamp(dataclasses.replace(twin, visible_diffuse=False)), make_lamp(twin)
    P = np.array([[0.0, 1.0, -2.0], [0.0, -1.0, 2.0], [0.0, 0.0, 0.0]], np.float32)
    picks = []
    for other in (hidden, seen):
        lights = LightSet([key, other], None, 0)
        assert lights.num_entries == 2 and lights.tree is not None
        picks.append(lights.tree.pdf(P, np.zeros(3, np.int64)))
    np.testing.assert_array_equal(picks[0], picks[1])
    assert 0.0 < picks[0].min() and picks[0].max() < 1.0
    stand = LightSet([key, hidden], None, 0).hidden_lamps[0]
    b, own = stand.bounds(), hidden.bounds()
    assert b.energy == own.energy > 0 and (b.lo == own.lo).all() and (b.hi == own.hi).all()
    assert not (stand.seen_by_bsdf or stand.seen_by_camera or stand.seen_by_transmission)
    s = stand.sample(P, np.full(3, 0.5, np.float32), np.full(3, 0.5, np.float32))
    assert not s.value.any()
    assert LightSet([key], None, 0).num_entries == 1


# --- choosing a light per shading point ---------------------------------------------------------

def test_light_choice_favours_lights_bsdf_sampling_misses():
    """A delta sun and a sun as wide as the sky (angle 180 degrees: uniform radiance over the
    upper hemisphere, solid-angle pdf 1/(2 pi)) over a plane: the cosine-weighted bounces find
    the wide one as well as light sampling would, so the delta sun gets the 80% share plus its
    10% uniform share and the wide one its 10%; the probabilities stay a distribution and the
    image stays unbiased. Two point lights (both delta, both with a position) are one group, the
    light tree: each holds the whole group's share, and the tree splits it per point."""
    from addon.integrator import Integrator
    wide = light('SUN', 0.5, np.eye(4), angle=np.pi)              # irradiance 0.5 on the plane
    scene = plane_scene([light('SUN', 3.0, np.eye(4)), wide], samples=64, max_bounces=0)
    integ = Integrator(scene)
    p = integ.lights.lamp_prob
    assert p.sum() == pytest.approx(1.0) and integ.lights.cdf[-1] == 1.0
    np.testing.assert_allclose(p, [0.9, 0.1], atol=1e-6)
    mean, err = pixel_stats(render(scene))
    expected = 0.8 / np.pi * (3.0 + 0.5)                    # albedo/pi x irradiance
    assert abs(mean - expected) < 4 * err + 1e-4 * expected
    two = Integrator(plane_scene([light('POINT', 10.0, translation(z=2.0)), light('POINT', 50.0, translation(1, 0, 3))]))
    np.testing.assert_allclose(two.lights.lamp_prob, [1.0, 1.0])
    assert two.lights.tree is not None and two.lights.tree.members == 2


def test_light_choice_keeps_uniform_shares_without_visible_surfaces():
    """No camera ray lands on anything: nothing to estimate from, the default split stays."""
    from addon.integrator import Integrator
    scene = plane_scene([light('SUN', 3.0, np.eye(4)), light('SUN', 0.5, np.eye(4), angle=np.pi)], samples=4)
    scene.camera.matrix[:3, 3] = (0.0, 0.0, -5.0)              # under the plane, looking down
    integ = Integrator(scene)
    np.testing.assert_allclose(integ.lights.lamp_prob, [0.5, 0.5])


def test_uniform_world_is_left_to_bsdf_rays():
    """As Cycles (a world shader that does not vary over directions is not light-sampled), the
    world takes no light samples: every one goes to the sun, and BSDF rays collect the world with
    weight 1. Under the world alone no shadow ray is traced, and the cosine-weighted bounce
    samples the uniform sky exactly: an open plane renders albedo x radiance at 2 samples."""
    from addon.integrator import Integrator
    both = Integrator(plane_scene([light('SUN', 3.0, np.eye(4))], world=(0.05, 0.05, 0.05)))
    np.testing.assert_allclose(both.lights.lamp_prob, [1.0])
    alone = render(plane_scene(world=(0.5, 0.5, 0.5), samples=2, max_bounces=0))
    assert alone.stats['rays']['shadow'] == 0 and alone.stats['lights'] == 1
    np.testing.assert_allclose(alone.film.combined()[..., :3], RHO * 0.5, rtol=1e-5)


@pytest.mark.parametrize('limit', [0, 1, 2])
def test_light_max_bounces_stops_light_sampling_deeper(limit):
    """Cycles' Light > Max Bounces: light sampling skips the light at shading points deeper
    than that (light_select_reached_max_bounces). A point light in the Cornell box (BSDF rays
    cannot meet it) limited to `limit` lights a 4-bounce render exactly as the box rendered
    with `limit` bounces: the same random numbers up to that vertex, nothing after it."""
    box = lambda bounces, light_limit: dataclasses.replace(
        cornell_box(24, 18, samples=4, max_bounces=bounces), lights=[light(
            'POINT', 30.0, translation(0.5, 0.5, 0.9), radius=0.0, max_bounces=light_limit)])
    def lit(scene):
        scene.materials[4] = material('light', (0.78, 0.78, 0.78))     # the ceiling quad: not emissive
        return render(scene).film.combined()
    limited, shallow, full = lit(box(4, limit)), lit(box(limit, 1024)), lit(box(4, 1024))
    assert np.array_equal(limited, shallow)
    assert full[..., 0].mean() > limited[..., 0].mean() * 1.05        # deeper light was cut


def test_light_linking_sets_and_receiver_masks():
    """lights/linking.py: emitters with the same receivers share a light set (0: everyone's);
    an object receives a set when included (or, with nobody included, when not excluded)."""
    from addon.lights.linking import LightLinking, reached, receives
    assert receives("A", (frozenset({"A"}), frozenset())) and not receives("B", (frozenset({"A"}), frozenset()))
    assert not receives("A", (frozenset({"A"}), frozenset({"A"})))             # excluded wins
    assert receives("B", (frozenset(), frozenset({"A"}))) and receives("B", (frozenset(), frozenset()))
    only_a, not_a = (frozenset({"A"}), frozenset()), (frozenset(), frozenset({"A"}))
    messages = []
    link = LightLinking({"Key": only_a, "Fill": not_a, "Rim": only_a}, ["A", "B", None], messages)
    assert link.active and not messages
    assert link.emitter_set("Key") == link.emitter_set("Rim") != link.emitter_set("Fill")
    assert link.emitter_set("Unlinked") == 0
    s_key, s_fill = link.emitter_set("Key"), link.emitter_set("Fill")
    assert reached(link.object_mask, 0).all()                                  # set 0: everyone
    assert list(reached(link.object_mask, s_key)) == [True, False, False]
    assert list(reached(link.object_mask, s_fill)) == [False, True, True]
    many = {f"L{i}": (frozenset({f"O{i}"}), frozenset()) for i in range(70)}
    link = LightLinking(many, ["O0"], messages)
    assert link.emitter_set("L62") > 0 and link.emitter_set("L63") == 0 and "light every object" in messages[0][1]


def test_shadow_linking_traces_against_the_emitters_blockers_only():
    """A plate over half the view shadows a sunlit floor; the sun's blocker collection leaving
    the plate out (excluded, or another object included) lights the floor under it exactly as
    without the plate, while a second, unlinked sun is still shadowed by it."""
    from .scenes import geometry, quad, ALL_VIS
    floor = quad((0.0, 0.0, 0.0), 100.0, 100.0)
    plate = quad((-0.00025, 0.0, 0.1), 0.00025, 1.0)           # over the left half, z = 0.1
    # (equal suns: an even light choice makes every pixel's split of samples exact)
    suns = [light('SUN', 2.0, np.eye(4), name='Sun'), light('SUN', 2.0, np.eye(4), name='Other')]

    def image(with_plate, links):
        scene = plane_scene(suns, samples=4, max_bounces=0)
        scene.camera = ortho_down(height=0.5, width=8, px=4)
        parts = [(*floor, 1, ALL_VIS)] + ([(*plate, 1, ALL_VIS & ~sd.VIS_CAMERA)] if with_plate else [])
        scene.geometry = geometry(parts)
        scene.object_names = ['Floor', 'Plate'][:len(parts)]
        scene.shadow_links = links
        return render(scene).film.combined()[..., 0]

    bare, shadowed = image(False, {}), image(True, {})
    assert shadowed[:, :3].max() < 1e-6 and np.allclose(shadowed[:, 5:], bare[:, 5:])
    for spec in ((frozenset(), frozenset({'Plate'})), (frozenset({'Floor'}), frozenset())):
        only_other = image(True, {'Sun': spec})      # the plate still blocks 'Other'
        assert np.allclose(only_other[:, :3], bare[:, :3] / 2.0, rtol=1e-5)
        assert np.allclose(only_other[:, 5:], bare[:, 5:])


def test_a_shadow_linked_emitter_is_not_blocked_by_what_its_blockers_leave_out():
    """A 6-unit area light 1.5 above a floor, a plate its blocker collection leaves out between
    them: the floor under the plate is lit exactly as without the plate (its light samples are
    the estimator; BSDF rays, which every object stops, had kept their MIS share and darkened it
    to 0.68x of Cycles, a helper's measurement), and an unlinked light is still shadowed."""
    from .scenes import geometry, quad, ALL_VIS
    floor = quad((0.0, 0.0, 0.0), 100.0, 100.0)
    plate = quad((0.0, 0.0, 0.1), 100.0, 100.0)                 # between the light and the floor
    panel = light('AREA', 200.0, translation(z=1.5), size_x=6.0, size_y=6.0, shape='SQUARE', name='Panel')

    def image(with_plate, links):
        scene = plane_scene([panel], samples=32, max_bounces=0)
        parts = [(*floor, 1, ALL_VIS)] + ([(*plate, 1, ALL_VIS & ~sd.VIS_CAMERA)] if with_plate else [])
        scene.geometry = geometry(parts)
        scene.object_names = ['Floor', 'Plate'][:len(parts)]
        scene.shadow_links = links
        return render(scene).film.combined()[..., :3]

    links = {'Panel': (frozenset(), frozenset({'Plate'}))}
    bare, under = image(False, links), image(True, links)
    assert bare.min() > 0 and np.array_equal(under, bare)
    assert image(True, {}).max() == 0.0                         # unlinked: the plate shadows it


def test_a_shadow_linked_emitter_light_sampling_never_picks_lights_by_bsdf_rays():
    """An emissive panel with Emission Sampling None and a blocker collection (shadow linking
    on) lights the floor, as in Cycles (it had lit nothing: shadow-linked emitters gather no
    BSDF hits, 0 where Cycles gives 0.476): it is light-sampled whatever its Emission Sampling
    (only a light sample's shadow ray can be traced against its blockers alone), so it lights
    the floor as the same panel sampled, and as the unlinked panel BSDF rays find."""
    from .scenes import geometry, quad, ALL_VIS
    floor = quad((0.0, 0.0, 0.0), 100.0, 100.0)
    panel = quad((0.0, 0.0, 1.5), 3.0, 3.0)

    def image(sampling, links):
        scene = plane_scene([], samples=64, max_bounces=0)
        scene.materials.append(material('Glow', (0.0, 0.0, 0.0), emission=(2.0, 2.0, 2.0),
                                         emission_sampling=sampling))
        scene.geometry = geometry([(*floor, 1, ALL_VIS), (*panel, len(scene.materials) - 1, ALL_VIS & ~sd.VIS_CAMERA)])
        scene.object_names = ['Floor', 'Panel']
        scene.world = np.zeros(3, np.float32)
        scene.shadow_links = links
        return render(scene).film.combined()[..., :3]

    links = {'Panel': (frozenset({'Floor'}), frozenset())}
    sampled, unsampled = image('FRONT_BACK', links), image('NONE', links)
    assert sampled.mean() > 0.05
    # (not the same image: the sampled panel's BSDF share is gathered by retraced rays and
    # MIS-weighted, as in Cycles, where the unsampled one lights by light samples alone)
    assert unsampled.mean() == pytest.approx(sampled.mean(), rel=0.05)
    assert unsampled.mean() == pytest.approx(image('NONE', {}).mean(), rel=0.05)

