"""Cycles' shadow terminator and its light samples below the geometric normal.

- A light sample in front of the shading normal counts even below the geometric one (Cycles'
  diffuse eval has no geometric test): the shadow ray decides. Closed form on an open smooth
  plane lit from below its surface.
- The geometry offset (light/sample.h shadow_ray_offset): next_event's shadow-ray origins and
  skips against a float64 transcription of Cycles' formulas, and the plane above: lifted, its
  shadow rays are meant to meet their own triangle, so it goes dark.
- The shading offset (closure/bsdf.h shift_cos_in): closed forms for light samples (a sun) and
  for BSDF rays (a uniform world), against a quadrature of the stretched cosine.
"""
import numpy as np
import pytest
from dacrt import shading

from .scenes import ALL_VIS, geometry, light, ortho_down, plane_scene, render, rotation_x
from .test_next_event import SHORTEN, _lights, _points

F32 = np.float32
ALPHA, BETA = np.radians(30.0), np.radians(10.0)
# the plane's shading normal, tilted by ALPHA toward -y, and a sun BETA below the horizon on that
# side: behind the geometric normal +z, in front of the shading normal (cos = sin(ALPHA - BETA))
N_TILT = np.array([0.0, -np.sin(ALPHA), np.cos(ALPHA)])
COS_NL = np.sin(ALPHA - BETA)


def tilted_plane(lights, terminator=None, world=(0.0, 0.0, 0.0), samples=8, max_bounces=0):
    scene = plane_scene(lights, world=world, samples=samples, max_bounces=max_bounces)
    g = scene.geometry
    g.normals = np.broadcast_to(N_TILT.astype(F32), g.normals.shape).copy()
    if terminator is not None:
        g.terminator = np.tile(np.asarray(terminator, F32), (len(g.triangles), 1))
    return scene


def low_sun(strength=np.pi):
    # rotation_x(90 deg + BETA) turns the sun's +Z (toward the sun) to (0, -cos BETA, -sin BETA)
    return light('SUN', strength, rotation_x(np.pi / 2 + BETA))


def test_light_below_the_geometric_normal_reaches_an_open_smooth_surface():
    """No offsets: albedo 0.8 x E / pi x cos(ns, L) with E = pi, exactly per sample (DACRT
    dropped such samples, 0)."""
    img = render(tilted_plane([low_sun()])).film.combined()[..., :3]
    assert np.allclose(img, 0.8 * COS_NL, rtol=1e-5)


def test_geometry_offset_lifts_shadow_rays_into_their_own_surface():
    """Cycles' geometry offset lifts a shadow ray off the plane along the shading normal, by a
    share of its triangle's size; below the geometric normal it is then meant to meet the surface
    (no skip): on a plane of 1 m strips it does, black as in Cycles. (On one huge quad the lifted
    ray passes beyond its edge.) Light well above the geometric normal is not lifted."""
    rows = np.arange(-50, 51, dtype=np.float64)
    v = np.array([(x, y, 0.0) for y in rows for x in (-50.0, 50.0)])
    t = np.array([(2 * j + a, 2 * j + b, 2 * j + c) for j in range(len(rows) - 1)
                  for a, b, c in ((0, 1, 3), (0, 3, 2))])
    for sun, want in ((low_sun(), 0.0),
                      (light('SUN', np.pi, rotation_x(np.radians(-20.0))),     # 20 deg toward +y
                       0.8 * N_TILT @ [0.0, np.sin(np.radians(20.0)), np.cos(np.radians(20.0))])):
        scene = tilted_plane([sun], terminator=(0.1, 0.0))
        scene.geometry = geometry([(v, t, 1, ALL_VIS)])
        scene.geometry.normals[:] = N_TILT
        scene.geometry.terminator = np.tile(np.array([0.1, 0.0], F32), (len(t), 1))
        scene.camera = ortho_down(target=(0.3, 0.4))
        img = render(scene).film.combined()[..., :3]
        assert np.allclose(img, want, rtol=1e-5, atol=0.0)


def _shift(c, f):
    """Appleseed's shift_cos_in, float64."""
    c = np.minimum(c, 1.0)
    return np.maximum(np.cos(np.arccos(c) * f), 0.0) / c


def test_shading_offset_dims_a_sun_by_the_stretched_cosine():
    """Shading offset s: Cycles' multiplier f = 1 / (1 - s / 2) stretches the angle to the light;
    a sun at 40 deg from the normal gives 0.8 x max(cos(f x 40 deg), 0) per sample."""
    for s, angle in ((0.6, 40.0), (0.3, 70.0), (1.0, 50.0)):
        f = 1.0 / (1.0 - 0.5 * s)
        sun = light('SUN', np.pi, rotation_x(np.radians(angle)))
        scene = plane_scene([sun], samples=4, max_bounces=0)
        scene.geometry.terminator = np.tile(np.array([0.0, s], F32), (len(scene.geometry.triangles), 1))
        img = render(scene).film.combined()[..., :3]
        want = 0.8 * max(np.cos(f * np.radians(angle)), 0.0)
        assert np.allclose(img, want, rtol=2e-5, atol=1e-7), (s, angle)


def test_shading_offset_dims_bsdf_rays_by_the_stretched_cosine():
    """Under a uniform world W (left to BSDF rays) a plane of albedo a with shading offset s
    reflects a W x 2 int_0^1 max(cos(f acos c), 0) dc: the BSDF sample's weight times
    shift_cos_in, against a quadrature."""
    s, W, a = 0.6, 0.5, 0.8
    f = 1.0 / (1.0 - 0.5 * s)
    scene = plane_scene([], world=(W, W, W), albedo=a, samples=512, max_bounces=0)
    scene.geometry.terminator = np.tile(np.array([0.0, s], F32), (len(scene.geometry.triangles), 1))
    scene.camera = ortho_down(width=32, px=32)
    img = render(scene).film.combined()[..., 0].astype(np.float64)
    c = (np.arange(1_000_000) + 0.5) / 1_000_000
    want = a * W * 2.0 * np.mean(np.maximum(np.cos(f * np.arccos(c)), 0.0))
    assert want < 0.95 * a * W                               # the offset visibly darkens it
    assert img.mean() == pytest.approx(want, rel=4 * img.std(ddof=1) / np.sqrt(img.size) / want + 1e-4)


# --- next_event's shadow rays against Cycles' formulas --------------------------------------------

def _cycles_lift(V, N, u, v, Ng):
    """shadow_ray_smooth_surface_offset in float64 for k points: V, N (k, 3 corners, 3), u, v (k,)
    barycentrics of corners 1 and 2, Ng (k, 3) the geometric normal on the ray's side."""
    w = np.stack([1.0 - u - v, u, v], axis=1)[..., None]
    P, n = (V * w).sum(1), (N * w).sum(1)
    dot = lambda x, y: (x * y).sum(-1)
    a = dot(N[:, 2] - N[:, 0], V[:, 0] - V[:, 2])
    b = dot(N[:, 2] - N[:, 1], V[:, 1] - V[:, 2])
    c = dot(N[:, 1] - N[:, 0], V[:, 1] - V[:, 0])
    U, Vb = w[:, 0, 0], w[:, 1, 0]
    h = a * U * (U - 1) + (a + b + c) * U * Vb + b * Vb * (Vb - 1)
    front = dot(n, Ng) > 0
    hs = []
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        e_f = np.maximum(np.maximum(dot(V[:, i] - V[:, k], N[:, k]), dot(V[:, j] - V[:, k], N[:, k])), 0)
        e_b = np.maximum(np.maximum(dot(V[:, k] - V[:, i], N[:, k]), dot(V[:, k] - V[:, j], N[:, k])), 0)
        hs.append((np.maximum(dot(V[:, k] - P, N[:, k]) + e_f, 0), np.maximum(dot(P - V[:, k], N[:, k]) + e_b, 0)))
    hf = np.maximum(np.minimum(np.minimum(hs[0][0], hs[1][0]), hs[2][0]), h * 0.5)
    hb = np.minimum(-np.minimum(np.minimum(hs[0][1], hs[1][1]), hs[2][1]), h * 0.5)
    return n * np.where(front, hf, hb)[:, None]


def test_shadow_rays_leave_from_cycles_lifted_points():
    """Random smooth triangles (corner normals up to ~35 deg off the face), points on them and
    lamp samples: with a cutoff, each shadow ray leaves from P_off + Cycles' lift x amount, aims
    at the same lamp point, and skips its triangle unless the light is below the geometric
    normal and the ray was lifted; without one nothing changes."""
    rng = np.random.default_rng(3)
    M, n = 200, 20_000
    V = rng.normal(size=(M, 3, 3)) * 0.3
    ng = np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0])
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)
    N = ng[:, None, :] + 0.4 * rng.normal(size=(M, 3, 3))
    N /= np.linalg.norm(N, axis=2, keepdims=True)
    N[rng.random(M) < 0.2] *= -1                             # some meshes with flipped corner normals
    geo, _ = shading.triangle_table(V.reshape(-1, 3).astype(F32), np.arange(3 * M, dtype=np.int32).reshape(M, 3),
                                    F32(8.0), F32(2.0 ** -100))
    normals = shading.corner_rows(N.astype(F32))
    prim = rng.integers(0, M, n).astype(np.int32)
    u = rng.random(n)
    v = rng.random(n) * (1 - u)
    u, v = u.astype(F32), v.astype(F32)
    V32 = np.stack([geo[0:3].T, geo[0:3].T + geo[3:6].T, geo[0:3].T + geo[6:9].T], axis=1).astype(np.float64)
    N32 = np.stack([normals[0:3].T, normals[0:3].T + normals[3:6].T, normals[0:3].T + normals[6:9].T],
                   axis=1).astype(np.float64)
    bary = np.stack([1 - u - v, u, v], 1)[..., None].astype(np.float64)
    P = (V32[prim] * bary).sum(1)
    # the normals facing a random incoming side, as surface() flips them
    flip = np.where(rng.random(n) < 0.5, -1.0, 1.0)[:, None]
    ngp = geo[9:12].T[prim].astype(np.float64) * flip
    nsp = (N32[prim] * bary).sum(1)
    nsp = nsp / np.linalg.norm(nsp, axis=1, keepdims=True) * flip
    P_off = P + 1e-5 * ngp
    rows = lambda a: np.ascontiguousarray(a.T, F32)
    lc = _lights(np.random.default_rng(7), True, False)
    _, _, _, _, _, keys = _points(rng, n, flat=True, thr=False)
    pick = rng.random(n)
    args = (lc, rows(P), rows(P_off), rows(nsp), rows(ngp), None, keys, 11, 12)
    cutoff = np.full(M, 0.3, F32)
    base = shading.next_event(*args, pick=pick, prim=prim, shorten=SHORTEN)
    got = shading.next_event(*args, pick=pick, prim=prim, shorten=SHORTEN,
                             terminator=(geo, normals, cutoff, None, u, v))
    for a, b in zip(base[:2], got[:2]):                      # values and contributions unchanged
        assert np.array_equal(a, b)
    assert np.array_equal(base[3], got[3])
    r0, r1, send = base[2], got[2], got[3]
    wi = r0['dir'].astype(np.float64)                        # lamps: the sampled direction
    i = send
    NL = (nsp[i] * wi).sum(1)
    sign = np.where(NL < 0, -1.0, 1.0)
    Ng = ngp[i] * sign[:, None]
    NgL = (Ng * wi).sum(1)
    NLa = NL * sign
    amount = np.clip(np.where(NLa < 0.3, 2.0 - (NgL + NLa) / 0.3, 1.0 - NgL / 0.3), 0.0, 1.0)
    lift = _cycles_lift(V32[prim[i]], N32[prim[i]], u[i].astype(np.float64), v[i].astype(np.float64), Ng)
    want = P_off[i].astype(F32).astype(np.float64) + lift * amount[:, None]
    scale = 1.0 + np.abs(V32).max()
    err = np.abs(r1['org'] - want).max(axis=1) / scale
    lifted = amount > 0
    assert lifted.mean() > 0.2 and (~lifted).mean() > 0.2   # both cases occur
    assert (np.linalg.norm(lift, axis=1)[lifted] > 1e-3).mean() > 0.5
    assert err.max() < 2e-5
    want_skip = np.where(lifted & (NgL <= 0), -1, prim[i])
    assert np.array_equal(got[4], want_skip)
    assert (want_skip == -1).any()
    # a lifted ray still ends at the lamp point it sampled (finite lamps): P + wi x dist
    fin = np.isfinite(r0['tfar']) & (r0['tfar'] < 1e30) & lifted
    end0 = P[i][fin] + wi[fin] * r0['tfar'][fin, None]
    end1 = r1['org'][fin] + r1['dir'][fin] * r1['tfar'][fin, None]
    assert fin.any() and np.abs(end1 - end0).max() < 1e-4
    unlifted = ~lifted
    assert np.array_equal(r1[unlifted], r0[unlifted])


def test_shading_offset_scales_light_samples_by_shift_cos_in():
    rng = np.random.default_rng(4)
    n, M = 20_000, 50
    P, P_off, ns, ng, _, keys = _points(rng, n, flat=False, thr=False)
    lc = _lights(np.random.default_rng(9), True, False)
    pick = rng.random(n)
    prim = rng.integers(0, M, n).astype(np.int32)
    freq = (1.0 / (1.0 - 0.5 * rng.random(M))).astype(F32)
    freq[:10] = 1.0                                          # no offset on those
    geo = np.zeros((15, M), F32)
    base = shading.next_event(lc, P, P_off, ns, ng, None, keys, 1, 2, pick=pick, prim=prim, shorten=SHORTEN)
    got = shading.next_event(lc, P, P_off, ns, ng, None, keys, 1, 2, pick=pick, prim=prim, shorten=SHORTEN,
                             terminator=(geo, None, None, freq, None, None))
    send = base[3]
    wi = base[2]['dir'].astype(np.float64)
    c = (ns[:, send].T.astype(np.float64) * wi).sum(1)
    f = freq[prim[send]].astype(np.float64)
    factor = np.where(f > 1, _shift(c, f), 1.0)
    vb, vg = base[0][:, send].astype(np.float64), got[0][:, send].astype(np.float64)
    ok = vb.max(axis=0) > 0
    # (float32 acos near c = 1 loses digits: Cycles itself uses a fast approximation; and
    # where the stretched angle lands next to 90 deg its cosine is all cancellation, so a
    # float32 ulp of the direction moves it by percents: those few are not compared)
    ok &= np.abs(np.arccos(np.clip(c, -1, 1)) * f - np.pi / 2) > 1e-3
    assert np.allclose(vg[:, ok], vb[:, ok] * factor[ok], rtol=2e-3, atol=1e-30)
    assert (factor[ok] < 0.9).mean() > 0.3
    # a stretched angle past 90 deg: that sample can no longer contribute
    assert np.array_equal(got[1][send], base[1][send] & (factor > 0))


def test_terminator_outside_0_1_is_refused():
    scene = tilted_plane([low_sun()], terminator=(0.1, 0.0))
    scene.geometry.terminator[0, 1] = 1.5
    with pytest.raises(ValueError, match='terminator'):
        render(scene)
