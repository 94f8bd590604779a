"""The native lamp kernels (dacrt.lamps) against the Python lamp classes (addon/lights/), which
define them: light samples (lamp_sample) for every lamp kind and variant, and what camera and
BSDF rays collect from lamps (lamp_gather) against the integrator's formula (intersect /
eval_miss, throughput, power-heuristic MIS); the record layout; argument checks.

Agreement is to float32 rounding: both sides run the same float32 formulas, but numpy and libm
differ in sin/cos by an ULP or so (most results are bit-identical). Where a formula amplifies
that (the spot smoothstep's steep slope, 1/cos at grazing emission) the tolerance says so."""
import dacrt
import numpy as np
import pytest

from addon.lights import BackgroundLight, lamp_records, make_lamp
from addon.lights.base import RECORD_FIELDS, RECORD_WIDTH

from .scenes import light, rotation_x, translation

F32 = np.float32
N_SAMPLES = 20_000


def rotation_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def scale(x, y, z):
    return np.diag([x, y, z, 1.0])


CENTRE = (0.3, -0.7, 1.2)
TILT = translation(*CENTRE) @ rotation_z(0.7) @ rotation_x(2.3)        # light -Z points down-ish, rotated
SQUASH = TILT @ scale(1.0, 2.5, 0.4)                                   # non-uniform scale
RGB = (120.0, 60.0, 15.0)

VARIANTS = {
    'point_delta': light('POINT', RGB, translation(*CENTRE)),
    'point_delta_unnormalized': light('POINT', RGB, translation(*CENTRE), normalize=False),
    'point_sphere': light('POINT', RGB, translation(*CENTRE), radius=0.5, soft_falloff=False),
    'point_disk': light('POINT', RGB, translation(*CENTRE), radius=0.5, soft_falloff=True),
    'point_disk_unnormalized': light('POINT', RGB, translation(*CENTRE), radius=0.3, normalize=False),
    'spot_hard': light('SPOT', RGB, TILT, spot_size=np.radians(70.0), spot_blend=0.0),
    'spot_smooth': light('SPOT', RGB, TILT, spot_size=np.radians(70.0), spot_blend=0.4),
    'spot_smooth_disk': light('SPOT', RGB, TILT, radius=0.4, spot_size=np.radians(90.0), spot_blend=0.7),
    'spot_sphere_hard': light('SPOT', RGB, TILT, radius=0.4, soft_falloff=False, spot_size=np.radians(60.0)),
    'spot_scaled': light('SPOT', RGB, SQUASH, spot_size=np.radians(50.0), spot_blend=0.5),
    'spot_scaled_disk': light('SPOT', RGB, SQUASH, radius=0.3, spot_size=np.radians(120.0), spot_blend=1.0),
    'sun_delta': light('SUN', RGB, TILT),
    'sun_angle': light('SUN', RGB, TILT, angle=np.radians(10.0)),
    'sun_wide_unnormalized': light('SUN', RGB, TILT, angle=np.radians(150.0), normalize=False),
    'area_square': light('AREA', RGB, TILT, shape='SQUARE', size_x=1.5),
    'area_rectangle': light('AREA', RGB, SQUASH, shape='RECTANGLE', size_x=1.0, size_y=0.6),
    'area_disk': light('AREA', RGB, TILT, shape='DISK', size_x=1.2),
    'area_ellipse': light('AREA', RGB, SQUASH, shape='ELLIPSE', size_x=0.8, size_y=1.4),
    'area_square_spread': light('AREA', RGB, TILT, shape='SQUARE', size_x=1.5, spread=np.radians(60.0)),
    'area_ellipse_spread': light('AREA', RGB, SQUASH, shape='ELLIPSE', size_x=0.8, size_y=1.4,
                                 spread=np.radians(120.0)),
    'area_disk_narrow_spread': light('AREA', RGB, TILT, shape='DISK', size_x=1.2, spread=0.08),  # 3/h^3 branch
    'area_rectangle_narrow_spread': light('AREA', RGB, SQUASH, shape='RECTANGLE', size_x=1.0, size_y=0.6,
                                          spread=np.radians(2.0)),
    'area_rectangle_unnormalized': light('AREA', RGB, TILT, shape='RECTANGLE', size_x=2.0, size_y=0.5,
                                         normalize=False),
    # a Light Falloff feeding the emission (Linear, Constant; Smooth) at each ray's length
    'point_delta_linear': light('POINT', RGB, translation(*CENTRE), falloff=(1, 0.0)),
    'point_sphere_constant_smooth': light('POINT', RGB, translation(*CENTRE), radius=0.5, soft_falloff=False,
                                          falloff=(2, 0.7)),
    'point_disk_smooth': light('POINT', RGB, translation(*CENTRE), radius=0.3, falloff=(0, 2.0)),
    'spot_smooth_disk_linear': light('SPOT', RGB, TILT, radius=0.4, spot_size=np.radians(90.0), spot_blend=0.7,
                                     falloff=(1, 0.5)),
    'area_square_constant': light('AREA', RGB, TILT, shape='SQUARE', size_x=1.5, falloff=(2, 0.0)),
    'area_ellipse_spread_linear_smooth': light('AREA', RGB, SQUASH, shape='ELLIPSE', size_x=0.8, size_y=1.4,
                                               spread=np.radians(120.0), falloff=(1, 1.5)),
}


def make(name):
    if name == 'background':
        return BackgroundLight(np.asarray((0.2, 0.5, 1.5), F32))
    return make_lamp(VARIANTS[name])


NAMES = list(VARIANTS) + ['background']


def points(rng, n):
    """Shading points all around the lamps: some inside point-light radii, some behind area lights."""
    return (np.asarray(CENTRE)[:, None] + rng.normal(size=(3, n)) * 1.5).astype(F32)


def uniforms(rng, n):
    u = rng.random((2, n), np.float32)
    u[:, :4] = [[0.0, 0.5, 0.999999, 0.25], [0.0, 0.5, 0.999999, 0.75]]     # corners and centre
    return u[0], u[1]


def close(native, python, rel=1e-5, abs_scale=1e-5, what='', spread=0.0):
    """native ~ python: equal infinities, exact zeros where python is zero, else within
    rel x |python| + abs_scale x (largest finite |python|) + spread; rel and spread may be per
    sample (n,)."""
    native, python = np.asarray(native, np.float64), np.asarray(python, np.float64)
    assert native.shape == python.shape
    rel = np.broadcast_to(np.asarray(rel, np.float64), python.shape[-1:]) * np.ones_like(python)
    inf = np.isinf(python)
    np.testing.assert_array_equal(native[inf], python[inf], err_msg=f'{what}: infinities')
    zero = python == 0
    assert (native[zero] == 0).all(), f'{what}: {np.count_nonzero(native[zero])} values non-zero where Python gives 0'
    fin = ~inf & ~zero
    big = np.abs(python[~inf]).max() if (~inf).any() else 0.0
    err = np.abs(native[fin] - python[fin])
    spread = np.broadcast_to(np.asarray(spread, np.float64), python.shape[-1:]) * np.ones_like(python)
    tol = rel[fin] * np.abs(python[fin]) + abs_scale * big + spread[fin]
    bad = np.flatnonzero(err > tol)
    assert not len(bad), (f'{what}: {len(bad)} of {fin.sum()} differ beyond tolerance, e.g. native '
                          f'{native[fin][bad[:3]]} vs python {python[fin][bad[:3]]}')


def emission_cosine(lamp, P, wi):
    """Cosine at the lamp of the sampled directions wi for lamps sampled by area (area lights,
    soft-falloff disks), else 1. pdf and value go as 1/cos there, and near grazing cos is known
    only to an absolute ~1e-7 (it comes from a unit vector), so their relative agreement is
    ~1e-7 / cos."""
    if hasattr(lamp, 'normal'):
        return -(lamp.normal @ wi)
    if getattr(lamp, 'radius', 0) > 0 and not lamp.sphere:
        axis = lamp.center[:, None] - P
        return np.einsum('ij,ij->j', wi, axis / np.linalg.norm(axis, axis=0))
    return np.ones(P.shape[1])


def warp_sensitivity(lamp, P, u1, u2, ref):
    """How far a rectangle's solid-angle samples move (dist, wi, value: largest absolute change)
    when the warp's angle phi = u1 S - (d2 + d3) moves by 4 float32 ULPs. numpy's and libm's
    sin/cos differ by about one ULP, and where the rectangle is seen low over P's horizon the
    warp amplifies that (measured up to ~1e-4 of dist at the elevation limit); 0 for samples
    drawn by area."""
    n = P.shape[1]
    if not getattr(lamp, 'solid_angle', False):
        return np.zeros(n), np.zeros(n), np.zeros(n)
    box = lamp._spread_box(P)[:4] if lamp.tan_half_spread is not None else (-0.5, 0.5, -0.5, 0.5)
    r = lamp._sph_rect(P, *box)
    with np.errstate(divide='ignore', invalid='ignore'):
        du = 4 * np.finfo(F32).eps * np.maximum(np.abs(r['d23']), np.abs(u1 * r['S'])) / r['S']
    du = np.where(r['use'], du, 0.0).astype(F32)
    moved = [lamp.sample(P, np.clip(u1 + sign * du, 0, 1).astype(F32), u2) for sign in (-1, 1)]
    d_dist = np.max([np.abs(m.dist - ref.dist) for m in moved], axis=0)
    d_wi = np.max([np.abs(m.wi - ref.wi).max(axis=0) for m in moved], axis=0)
    d_value = np.max([np.abs(m.value - ref.value).max(axis=0) for m in moved], axis=0)
    return d_dist, d_wi, d_value


def sample_both(lamp, P, u1, u2):
    rec = lamp_records([lamp])
    n = P.shape[1]
    wi, dist, value, pdf = dacrt.lamps.lamp_sample(rec, np.zeros(n, np.int32), P, u1, u2)
    return (wi, dist, value, pdf), lamp.sample(P, u1, u2)


@pytest.mark.parametrize('name', NAMES)
def test_sample_matches_python(name):
    rng = np.random.default_rng(NAMES.index(name))
    lamp = make(name)
    P = points(rng, N_SAMPLES)
    u1, u2 = uniforms(rng, N_SAMPLES)
    (wi, dist, value, pdf), ref = sample_both(lamp, P, u1, u2)
    d_dist, d_wi, d_value = warp_sensitivity(lamp, P, u1, u2, ref)
    close(dist, ref.dist, abs_scale=1e-6, what='dist', spread=2 * d_dist)
    close(wi, ref.wi, abs_scale=2e-6, what='wi', spread=2 * d_wi)
    rel = 2e-5 + 1e-6 / np.maximum(np.abs(emission_cosine(lamp, P, ref.wi)), 1e-12)
    close(pdf, ref.pdf, rel=rel, what='pdf')
    # the spot smoothstep's slope (inv_smooth, up to ~20 here) amplifies an ULP of the cone cosine
    close(value, ref.value, rel=rel, abs_scale=1e-4 if 'spot' in name else 1e-6, what='value', spread=2 * d_value)
    # the variants really exercise their cases: some samples reach the point, and where a lamp
    # cannot reach every point, some do not
    lit = ref.value.max(axis=0) > 0
    assert lit.any()
    if name.startswith(('area', 'spot')):
        assert not lit.all(), 'expected some points behind / outside the lamp'
    if name.startswith(('point_sphere', 'point_disk')):
        # as in Cycles, points within the radius are lit too (a sphere all round, the disk facing them)
        d = np.linalg.norm(P - np.asarray(CENTRE, F32)[:, None], axis=0)
        assert (d < lamp.radius).any() and (value[:, d < lamp.radius].max(axis=0) > 0).all()


def test_sample_entries_select_records_and_leave_others_untouched():
    rng = np.random.default_rng(7)
    lamps = [make(name) for name in NAMES]
    rec = lamp_records(lamps)
    R, n = len(lamps), 50_000
    entry = rng.integers(-3, R + 3, n).astype(np.int32)
    P = points(rng, n)
    u1, u2 = uniforms(rng, n)
    out = (np.full((3, n), 7.0, F32), np.full(n, 8.0, F32), np.full((3, n), 9.0, F32), np.full(n, 10.0, F32))
    res = dacrt.lamps.lamp_sample(rec, entry, P, u1, u2, out=out)
    assert all(a is b for a, b in zip(res, out))
    wi, dist, value, pdf = out
    other = (entry < 0) | (entry >= R)
    assert other.any()
    assert (wi[:, other] == 7).all() and (dist[other] == 8).all() and (value[:, other] == 9).all()
    assert (pdf[other] == 10).all()
    for j, lamp in enumerate(lamps):
        idx = np.flatnonzero(entry == j)
        ref = lamp.sample(P[:, idx], u1[idx], u2[idx])
        close(value[:, idx], ref.value, rel=2e-5, abs_scale=1e-4, what=f'value of {NAMES[j]}')
        close(pdf[idx], ref.pdf, rel=2e-5, what=f'pdf of {NAMES[j]}')
    # a wider integer entry array: values that do not fit int32 are other samplers', not wrapped
    wide = entry.astype(np.int64)
    wide[:10] = 2**32                                # would be 0 if wrapped to int32
    out2 = (np.full((3, n), 7.0, F32), np.full(n, 8.0, F32), np.full((3, n), 9.0, F32), np.full(n, 10.0, F32))
    dacrt.lamps.lamp_sample(rec, wide, P, u1, u2, out=out2)
    assert (out2[1][:10] == 8).all()


def gather_reference(lamps, listed, O, D, t_surf, miss, pid, N, thr, pdf_bsdf, lamp_prob):
    """What the numpy lamp classes define a ray collects, lamp by lamp (the reference lamp_gather must match)."""
    L = np.zeros((3, N), F32)
    miss_idx = np.flatnonzero(miss)
    for j in listed:
        lamp = lamps[j]
        if lamp.at_infinity:
            idx, Le, pdf_l = lamp.eval_miss(np.take(D, miss_idx, axis=1))
            idx = np.take(miss_idx, idx)
        else:
            idx, Le, pdf_l = lamp.intersect(O, D, t_surf)
        if thr is not None:
            Le = Le * np.take(thr, idx, axis=1)
        if lamp_prob is not None:
            with np.errstate(divide='ignore', invalid='ignore'):
                r = lamp_prob[j] * pdf_l / np.take(pdf_bsdf, idx)
                r *= r
                r += F32(1.0)
                Le *= F32(1.0) / r
        L[:, pid[idx]] += Le
    return L


def gather_rays(rng, lamps, n):
    """Rays from all around: a third aimed near the lamps' centre, a third in random directions,
    a third along a lamp's axis (toward a sun, or head-on at an area light's emitting face, so
    narrow cones and spreads are met too); a random surface distance (some rays stop short of
    the lamps) and random misses."""
    O = points(rng, n)
    target = np.asarray(CENTRE)[:, None] + rng.normal(size=(3, n)) * 0.5
    D = np.where(rng.random(n) < 0.5, target - O, rng.normal(size=(3, n)))
    axial = np.flatnonzero(rng.random(n) < 1 / 3)
    which = rng.integers(0, len(lamps), len(axial))
    for j, lamp in enumerate(lamps):
        k = axial[which == j]
        jitter = rng.normal(size=(3, len(k))) * 0.02
        if hasattr(lamp, 'to_sun'):
            D[:, k] = lamp.to_sun[:, None] + jitter
        elif hasattr(lamp, 'normal'):
            side = rng.normal(size=(2, len(k))) * 0.4
            O[:, k] = (lamp.center[:, None] + lamp.normal[:, None] * rng.uniform(0.1, 3.0, len(k))
                       + lamp.axis_x[:, None] * side[0] + lamp.axis_y[:, None] * side[1])
            D[:, k] = -lamp.normal[:, None] + jitter
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    t_surf = np.where(rng.random(n) < 0.3, rng.uniform(0.0, 3.0, n), np.inf).astype(F32)
    miss = rng.random(n) < 0.6
    return O.astype(F32), D, t_surf, miss


@pytest.mark.parametrize('mode', ['camera', 'camera_thr', 'bsdf', 'bsdf_no_thr'])
def test_gather_matches_integrator_formula(mode):
    rng = np.random.default_rng(11)
    lamps = [make(name) for name in NAMES]
    rec = lamp_records(lamps)
    n, N = 40_000, 60_000
    O, D, t_surf, miss = gather_rays(rng, lamps, n)
    pid = rng.permutation(N)[:n]
    thr = rng.uniform(0.1, 2.0, (3, n)).astype(F32) if mode in ('camera_thr', 'bsdf') else None
    bsdf = mode.startswith('bsdf')
    pdf_bsdf = rng.uniform(0.01, 1.0, n).astype(F32) if bsdf else None
    lamp_prob = rng.uniform(0.05, 1.0, len(lamps)).astype(F32) if bsdf else None
    listed = [j for j in range(len(lamps)) if j % 5 != 3]        # a subset, as the integrator lists
    L = rng.uniform(0.0, 1.0, (3, N)).astype(F32)                 # accumulated onto existing values
    expected = L + gather_reference(lamps, listed, O, D, t_surf, miss, pid, N, thr, pdf_bsdf, lamp_prob)
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L, thr=thr, pdf_bsdf=pdf_bsdf,
                            lamp_prob=lamp_prob)
    # the rays see finite lamps, lamps at infinity and several lamps at once
    seen = np.zeros(n, int)
    for j in listed:
        lamp = lamps[j]
        if lamp.at_infinity:
            seen[np.flatnonzero(miss)[lamp.eval_miss(D[:, miss])[0]]] += 1
        else:
            seen[lamp.intersect(O, D, t_surf)[0]] += 1
    assert (seen >= 2).sum() > 100 and (seen == 0).sum() > 100
    np.testing.assert_allclose(L, expected, rtol=2e-5, atol=2e-5 * np.abs(expected).max())


@pytest.mark.parametrize('name', [n for n in NAMES if not make(n).delta])
def test_gather_each_lamp(name):
    """Per lamp (finite ones seen from both sides, up to t_surf; lamps at infinity where missed)."""
    rng = np.random.default_rng(NAMES.index(name) + 100)
    lamp = make(name)
    n = 30_000
    O, D, t_surf, miss = gather_rays(rng, [lamp], n)
    pdf_bsdf = rng.uniform(0.01, 1.0, n).astype(F32)
    lamp_prob = np.asarray([0.3], F32)
    pid = np.arange(n)
    expected = gather_reference([lamp], [0], O, D, t_surf, miss, pid, n, None, pdf_bsdf, lamp_prob)
    assert (expected.max(axis=0) > 0).sum() > 50, 'too few rays see the lamp to test it'
    L = np.zeros((3, n), F32)
    dacrt.lamps.lamp_gather(lamp_records([lamp]), [0], O, D, t_surf, miss, pid, L, pdf_bsdf=pdf_bsdf,
                            lamp_prob=lamp_prob)
    close(L, expected, rel=2e-5, abs_scale=1e-4 if 'spot' in name else 1e-6, what=name)


@pytest.mark.parametrize('name', [n for n in NAMES if 'spread' in n])
def test_gather_pdf_equals_sample_pdf(name):
    """MIS with spread: the native sample's pdf (clamped to the spread's square about the shading
    point) is the pdf lamp_gather weighs a BSDF ray along that sample with. With lamp_prob 1 and
    pdf_bsdf = the sample's pdf the power heuristic is exactly 1/2 where they agree; the gathered
    radiance (camera mode) is the sample's value x pdf."""
    rng = np.random.default_rng(NAMES.index(name) + 200)
    lamp = make(name)
    rec = lamp_records([lamp])
    n = 40_000
    # points in front of the lamp at heights where the spread's square is clamped by the lamp's
    # edges, lies inside it or (wide spreads, far points) covers it whole
    side = rng.uniform(-0.8, 0.8, (2, n))
    h = rng.uniform(0.05, 4.0, n)
    P = (lamp.center[:, None] + lamp.normal[:, None] * h + lamp.axis_x[:, None] * side[0]
         + lamp.axis_y[:, None] * side[1]).astype(F32)
    u1, u2 = rng.random((2, n), np.float32)
    wi, dist, value, pdf = dacrt.lamps.lamp_sample(rec, np.zeros(n, np.int32), P, u1, u2)
    good = np.flatnonzero(value.max(axis=0) > 0)
    assert len(good) > n // 10
    m = len(good)
    O, D = np.ascontiguousarray(P[:, good]), np.ascontiguousarray(wi[:, good])
    t_surf, miss, pid = np.full(m, np.inf, F32), np.zeros(m, bool), np.arange(m)
    Le = np.zeros((3, m), F32)
    dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, Le)
    Lw = np.zeros((3, m), F32)
    dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, Lw, pdf_bsdf=np.ascontiguousarray(pdf[good]),
                            lamp_prob=np.ones(1, F32))
    seen = Le.max(axis=0) > 0
    assert seen.mean() >= 0.999                       # (a few at the square's edge round outside it)
    np.testing.assert_allclose(Le[:, seen], (value * pdf)[:, good][:, seen], rtol=2e-3)
    w = Lw[0, seen].astype(np.float64) / Le[0, seen]
    pdf_gather = pdf[good][seen] * np.sqrt(1.0 / w - 1.0)    # w = 1 / (1 + (pdf_l / pdf_bsdf)^2)
    np.testing.assert_allclose(pdf_gather, pdf[good][seen], rtol=2e-3)


def many_lamps(rng, count, spread=20.0):
    """count lamps of every variant (delta ones, suns and the background among them) scattered
    over a spread-metre box, turned and scaled at random, some repeated (a list may name a
    record twice)."""
    lamps = []
    for j in range(count):
        kind = VARIANTS[NAMES[j % (len(NAMES) - 1)]]
        pose = (translation(*rng.uniform(-spread / 2, spread / 2, 3)) @ rotation_z(rng.uniform(0, 6.3))
                @ rotation_x(rng.uniform(0, 6.3)) @ scale(*rng.uniform(0.1, 1.5, 3)))
        lamps.append(make_lamp(light(kind.kind, RGB, pose, radius=kind.radius * rng.uniform(0.2, 2.0),
                                     soft_falloff=kind.soft_falloff, spot_size=kind.spot_size,
                                     spot_blend=kind.spot_blend, angle=kind.angle, shape=kind.shape,
                                     size_x=kind.size_x, size_y=kind.size_y, spread=kind.spread)))
    lamps.append(make('background'))
    return lamps


def rays_at_lamps(rng, lamps, n, far=1.0):
    """Rays that meet lamps, graze them and pass them: origins around the box (far x its size)
    and on lamp centres; directions at lamp centres with jitter, along the axes (zero
    components), at random and at lamps' rims; surfaces at random distances, just beyond the
    aim, or none."""
    centres = np.array([lamp.center for lamp in lamps if hasattr(lamp, 'center')]).T
    pick = lambda m: centres[:, rng.integers(0, centres.shape[1], m)]
    O = rng.uniform(-12, 12, (3, n)) * far
    on = rng.random(n) < 0.15
    O[:, on] = pick(on.sum()) + rng.normal(size=(3, on.sum())) * 1e-4
    target = pick(n) + rng.normal(size=(3, n)) * rng.choice([0.02, 0.3, 1.0], n)
    D = target - O
    kind = rng.random(n)
    D[:, kind < 0.15] = rng.normal(size=(3, (kind < 0.15).sum()))
    axis = (kind >= 0.15) & (kind < 0.3)
    D[:, axis] = np.eye(3)[:, rng.integers(0, 3, axis.sum())] * rng.choice([-1, 1], axis.sum())
    # a quarter aimed at the rims, where float32 rounding decides a meeting: a sphere's or
    # disk's edge, an area light's corners and sides, from its emitting side
    rim = np.flatnonzero(rng.random(n) < 0.25)
    finite = [lamp for lamp in lamps if hasattr(lamp, 'center') and not lamp.delta]
    for i, j in zip(rim, rng.integers(0, len(finite), len(rim))):
        lamp = finite[j]
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if hasattr(lamp, 'normal'):
            d = d if d @ lamp.normal < 0 else -d
            sx, sy = rng.choice([-0.5, 0.5], 2) * (1 + rng.normal(size=2) * 1e-6)
            if rng.random() < 0.5:
                sx = rng.uniform(-0.5, 0.5)
            B = lamp.center + sx * lamp.axis_x + sy * lamp.axis_y
        else:
            u = rng.normal(size=3)
            u -= (u @ d) * d
            B = lamp.center + lamp.radius * (1 + rng.normal() * 1e-6) * u / np.linalg.norm(u)
        O[:, i] = B - d * rng.uniform(0.5, 20) * far
        D[:, i] = d
        target[:, i] = B
    t_centre = np.linalg.norm(target - O, axis=0)
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    t_surf = np.select([kind < 0.5, kind < 0.7], [np.inf, t_centre * 1.0001], rng.uniform(0, 30 * far, n))
    miss = ~np.isfinite(t_surf) & (rng.random(n) < 0.8)
    return O.astype(F32), D, t_surf.astype(F32), miss


@pytest.mark.parametrize('mode', ['camera', 'bsdf', 'far'])
def test_gather_many_lamps_equals_lamp_by_lamp(mode):
    """With many lamps listed, lamp_gather tests each ray only against the lamps a BVH finds
    near it (lamps.cpp). Its sums must be bit for bit those of gathering one lamp at a time in
    list order (each call the plain lamp-by-lamp loop): the same additions in the same order,
    and no lamp a ray meets left out, also for rays from 1000x farther than the lamps' spread
    (the boxes' rounding margin) and along the axes."""
    rng = np.random.default_rng(['camera', 'bsdf', 'far'].index(mode) + 40)
    lamps = many_lamps(rng, 300)
    rec = lamp_records(lamps)
    listed = np.concatenate([np.arange(len(lamps)), rng.integers(0, len(lamps), 20)]).astype(np.int32)
    rng.shuffle(listed)                                     # any order, duplicates included
    n, N = 30_000, 40_000
    O, D, t_surf, miss = rays_at_lamps(rng, lamps, n, far=1000.0 if mode == 'far' else 1.0)
    pid = rng.permutation(N)[:n]
    bsdf = mode == 'bsdf'
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=rng.uniform(0.05, 1.0, len(lamps)).astype(F32))
    L0 = rng.uniform(0.0, 1.0, (3, N)).astype(F32)
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L, **kw)
    one_by_one = L0.copy()
    for j in listed:
        dacrt.lamps.lamp_gather(rec, [j], O, D, t_surf, miss, pid, one_by_one, **kw)
    changed = (one_by_one != L0).any(axis=0)[pid]
    assert changed.sum() > (300 if mode == 'far' else 2000), 'too few rays see a lamp to test it'
    np.testing.assert_array_equal(L, one_by_one)


@pytest.mark.parametrize('name', ['area_square', 'area_rectangle', 'area_disk', 'area_ellipse',
                                  'area_rectangle_unnormalized'])
@pytest.mark.parametrize('bsdf', [False, True])
def test_gather_area_lanes_equal_ray_by_ray(name, bsdf):
    """lamp_gather meets an area lamp without spread eight rays at a time (lamps.cpp
    gather_area_lanes); a call of fewer rays than that goes ray by ray (gather_one). The sums
    must be bit for bit the same, for rays that meet the lamp from in front, from behind,
    edge-on, stopped short by a surface, and near it (its solid-angle pdf)."""
    rng = np.random.default_rng(len(name) + bsdf)
    lamp = make(name)
    rec = lamp_records([lamp])
    n = 3001
    O, D, t_surf, miss = gather_rays(rng, [lamp], n)
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=np.asarray([0.4], F32), clamp=30.0)
    pid = np.arange(n)
    L = np.zeros((3, n), F32)
    dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, L, **kw)
    by_ray = np.zeros((3, n), F32)
    for i in range(n):
        sub = {k: (v[..., i:i + 1] if k in ('thr', 'pdf_bsdf') else v) for k, v in kw.items()}
        dacrt.lamps.lamp_gather(rec, [0], O[:, i:i + 1], D[:, i:i + 1], t_surf[i:i + 1], miss[i:i + 1],
                                np.array([i]), by_ray, **sub)
    assert (L.max(axis=0) > 0).sum() > 100, 'too few rays meet the lamp to test it'
    np.testing.assert_array_equal(L.view(np.uint32), by_ray.view(np.uint32))


def test_delta_lamps_are_never_gathered():
    rng = np.random.default_rng(3)
    lamps = [make('point_delta'), make('spot_hard'), make('sun_delta')]
    n = 5000
    O, D, t_surf, _ = gather_rays(rng, lamps, n)
    L = np.zeros((3, n), F32)
    dacrt.lamps.lamp_gather(lamp_records(lamps), [0, 1, 2], O, D, t_surf, np.ones(n, bool), np.arange(n), L)
    assert not L.any()


def test_empty_inputs():
    rec = lamp_records([make('area_square')])
    wi, dist, value, pdf = dacrt.lamps.lamp_sample(rec, [], np.zeros((3, 0), F32), [], [])
    assert wi.shape == (3, 0) and dist.shape == (0,) and value.shape == (3, 0) and pdf.shape == (0,)
    L = np.ones((3, 4), F32)
    rng = np.random.default_rng(2)
    O, D, t_surf, miss = gather_rays(rng, [make('area_square')], 4)
    dacrt.lamps.lamp_gather(rec, [], O, D, t_surf, miss, np.arange(4), L)          # no lamps listed
    dacrt.lamps.lamp_gather(np.zeros((0, RECORD_WIDTH), F32), [], O, D, t_surf, miss, np.arange(4), L)
    assert (L == 1).all()


def test_record_layout_matches_native():
    assert RECORD_WIDTH == dacrt.lamps.RECORD_WIDTH
    assert RECORD_FIELDS == dacrt.lamps.record_layout()
    rec = lamp_records([make(name) for name in NAMES])
    assert rec.shape == (len(NAMES), RECORD_WIDTH) and rec.dtype == F32 and np.isfinite(rec).all()
    assert lamp_records([]).shape == (0, RECORD_WIDTH)


def test_bad_arguments():
    rng = np.random.default_rng(5)
    rec = lamp_records([make('area_square'), make('background')])
    n = 10
    P = points(rng, n)
    u = np.full(n, 0.5, F32)
    e = np.zeros(n, np.int32)
    sample = dacrt.lamps.lamp_sample
    with pytest.raises(ValueError, match=r'records must have shape \(R, 52\)'):
        sample(rec[:, :39], e, P, u, u)
    with pytest.raises(ValueError, match=r'P must have shape \(3, n\)'):
        sample(rec, e, P[:2], u, u)
    with pytest.raises(ValueError, match=r'u2 must have shape \(10,\)'):
        sample(rec, e, P, u, u[:9])
    with pytest.raises(ValueError, match=r'entry must have shape'):
        sample(rec, e[:5], P, u, u)
    with pytest.raises(ValueError, match='entry must be an integer array'):
        sample(rec, e.astype(F32), P, u, u)
    with pytest.raises(ValueError, match='value must be a writeable C-contiguous float32'):
        sample(rec, e, P, u, u, out=(np.zeros((3, n), F32), np.zeros(n, F32), np.zeros((3, n)), np.zeros(n, F32)))
    with pytest.raises(ValueError, match=r'dist must have shape \(10,\)'):
        sample(rec, e, P, u, u, out=(np.zeros((3, n), F32), np.zeros(n + 1, F32), np.zeros((3, n), F32),
                                     np.zeros(n, F32)))
    bad = rec.copy()
    bad[1, 0] = 9
    with pytest.raises(ValueError, match=r'records\[1\]: kind 9'):
        sample(bad, e, P, u, u)
    bad = rec.copy()
    bad[0, 1] = 3
    with pytest.raises(ValueError, match=r'records\[0\]: shape 3'):
        sample(bad, e, P, u, u)
    bad = rec.copy()
    bad[0, 15] = np.nan
    with pytest.raises(ValueError, match=r'records\[0\]: field 15 is not finite'):
        sample(bad, e, P, u, u)

    D = np.tile(np.asarray([[0.0], [0.0], [1.0]], F32), n)
    t = np.full(n, np.inf, F32)
    miss = np.ones(n, bool)
    L = np.zeros((3, n), F32)
    pid = np.arange(n)
    gather = dacrt.lamps.lamp_gather
    with pytest.raises(ValueError, match=r'lamps must be record indices 0..1'):
        gather(rec, [0, 2], P, D, t, miss, pid, L)
    with pytest.raises(ValueError, match=r'D must have shape \(3, 10\)'):
        gather(rec, [0], P, D[:, :9], t, miss, pid, L)
    with pytest.raises(ValueError, match=r'miss must be a bool array'):
        gather(rec, [0], P, D, t, miss.astype(np.int8), pid, L)
    with pytest.raises(ValueError, match=r'thr must have shape \(3, 10\)'):
        gather(rec, [0], P, D, t, miss, pid, L, thr=np.ones((3, 9), F32))
    with pytest.raises(ValueError, match=r'lamp_prob and pdf_bsdf go together'):
        gather(rec, [0], P, D, t, miss, pid, L, lamp_prob=np.ones(2, F32))
    with pytest.raises(ValueError, match=r'lamp_prob must have shape \(2,\)'):
        gather(rec, [0], P, D, t, miss, pid, L, lamp_prob=np.ones(3, F32), pdf_bsdf=np.ones(n, F32))
    with pytest.raises(ValueError, match=r'L must be a C-contiguous \(3, N\) float32'):
        gather(rec, [0], P, D, t, miss, pid, L.astype(np.float64))
    with pytest.raises(ValueError, match=r'pid\[9\] = 10 is outside 0..9'):
        gather(rec, [0], P, D, t, miss, pid + 1, L)
    with pytest.raises(ValueError, match=r'pid\[3\] = 2 repeats an earlier pid'):
        gather(rec, [0], P, D, t, miss, np.asarray([0, 1, 2, 2, 4, 5, 6, 7, 8, 9]), L)
    assert not L.any()                                # nothing was added by the failed calls


def test_lamp_gather_checks_pids_at_every_place_and_length():
    """The gathers' pid check (one pass for ascending pids within range, else the full check)
    refuses a repeat, a negative or an out-of-range pid wherever it sits in arrays of every
    length around the vector widths, takes a step down (distinct and in range: the full check)
    and ascending pids with gaps: the world is then added to exactly their columns."""
    rng = np.random.default_rng(11)
    rec = lamp_records([make('background')])
    gather = dacrt.lamps.lamp_gather
    for n in list(range(1, 40)) + [63, 64, 65, 127, 128, 129, 1000]:
        P = points(rng, n)
        D = np.tile(np.asarray([[0.0], [0.0], [1.0]], F32), n)
        t = np.full(n, np.inf, F32)
        miss = np.ones(n, bool)
        pid = np.cumsum(rng.integers(1, 3, n)) - 1          # ascending, with gaps
        N = int(pid[-1]) + 1
        L = np.zeros((3, N), F32)
        gather(rec, [0], P, D, t, miss, pid, L)
        added = L.any(axis=0)
        assert np.array_equal(np.flatnonzero(added), pid)
        for at in sorted({0, n // 2, n - 1}):
            bad = pid.copy()
            bad[at] = N if at == n - 1 else -1 if at == 0 else bad[at - 1]
            L2 = np.zeros((3, N), F32)
            with pytest.raises(ValueError, match=rf'pid\[{at}\] = {bad[at]} (is outside|repeats)'):
                gather(rec, [0], P, D, t, miss, bad, L2)
            assert not L2.any()
            if at:                                      # a step down: distinct and in range, taken
                down = pid.copy()
                down[at - 1], down[at] = pid[at], pid[at - 1]
                L3 = np.zeros((3, N), F32)
                gather(rec, [0], P, D, t, miss, down, L3)
                assert np.array_equal(L3, L)


def _gather_inputs(rng, n, N, count, bsdf):
    """lamp_gather's other inputs for n rays and count listed lamps: distinct columns pid of an
    (3, N) film L0 at random, the BSDF rays' thr, pdf_bsdf and lamp_prob (bsdf) or none, and the
    list 0..count."""
    pid = rng.permutation(N)[:n]
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=rng.uniform(0.05, 1.0, count).astype(F32))
    return pid, kw, rng.uniform(0.0, 1.0, (3, N)).astype(F32), np.arange(count, dtype=np.int32)


@pytest.mark.parametrize('count', [1, 40, 100])
@pytest.mark.parametrize('bsdf', [False, True])
def test_gather_without_miss_flags_where_no_lamp_is_at_infinity(count, bsdf):
    """miss is read for the lamps at infinity alone, so a list without any may go without it
    (None: the integrator then makes no flags from its hit records): every sum bit for bit the
    one with flags given, through each of the gather's forms (one area lamp's lanes, boxes of
    up to 64 lamps, the BVH beyond). A list with a sun or the world still needs them: a
    clear error, the film untouched."""
    rng = np.random.default_rng(count + 7 * bsdf)
    lamps = [lamp for lamp in many_lamps(rng, 3 * count) if not lamp.at_infinity][:count]
    if count == 1:                            # (an area lamp: the lanes)
        lamps = [make('area_rectangle')]
    assert len(lamps) == count
    rec = lamp_records(lamps)
    n, N = 20_000, 25_000
    O, D, t_surf, miss = rays_at_lamps(rng, lamps, n)
    pid, kw, L0, listed = _gather_inputs(rng, n, N, count, bsdf)
    given, flagless = L0.copy(), L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, given, **kw)
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, None, pid, flagless, **kw)
    assert (given != L0).any(axis=0).sum() > 50, 'too few rays see a lamp to test it'
    assert given.tobytes() == flagless.tobytes()
    for far in ('sun_angle', 'background'):
        with_far = lamp_records(lamps + [make(far)])
        if bsdf:
            kw['lamp_prob'] = rng.uniform(0.05, 1.0, count + 1).astype(F32)
        L = L0.copy()
        with pytest.raises(ValueError, match=rf'miss is None, but lamps\[{count}\] = {count} is at infinity'):
            dacrt.lamps.lamp_gather(with_far, np.arange(count + 1), O, D, t_surf, None, pid, L, **kw)
        assert L.tobytes() == L0.tobytes()


def _records_missing(rng, miss):
    """The tracer's hit records (dacrt.HIT_DTYPE) of rays whose misses are miss: prim -1 there,
    a triangle index (0 among them) elsewhere, and t, u, v at random."""
    hits = np.empty(len(miss), dacrt.HIT_DTYPE)
    hits['t'] = rng.uniform(0.0, 30.0, len(miss))
    hits['prim'] = np.where(miss, -1, rng.integers(0, 1 << 30, len(miss)))
    hits['prim'][np.flatnonzero(~miss)[:5]] = 0
    hits['u'], hits['v'] = rng.random(len(miss)), rng.random(len(miss))
    return hits


@pytest.mark.parametrize('count', [2, 12, 100])
@pytest.mark.parametrize('bsdf', [False, True])
def test_gather_reads_the_misses_from_the_hit_records(count, bsdf):
    """Given the tracer's hit records as miss, lamp_gather reads which rays missed from them in
    place (prim < 0), so the integrator makes no flags: every sum bit for bit the one with the
    flags given, for a list of the sun and the world alone, and lists mixing them with finite
    lamps through the boxes (up to 64 lamps) and the BVH beyond. Any other structured array is
    refused with a clear error, the film untouched."""
    rng = np.random.default_rng(count + 11 * bsdf)
    if count == 2:                            # (lamps at infinity only: gather_infinite's lists)
        lamps = [make('sun_angle'), make('background')]
    else:
        lamps = [lamp for lamp in many_lamps(rng, 3 * count) if not lamp.at_infinity][:count - 2]
        lamps[count // 3:count // 3] = [make('sun_angle')]
        lamps.append(make('background'))
    assert len(lamps) == count
    rec = lamp_records(lamps)
    n, N = 20_000, 25_000
    O, D, t_surf, miss = rays_at_lamps(rng, [lamp for lamp in lamps if not lamp.at_infinity] or
                                       [make('area_rectangle')], n)
    sun = lamps[count // 3 if count > 2 else 0]
    D[:, rng.random(n) < 0.3] = np.asarray(sun.to_sun, F32)[:, None]     # (in the sun's disk)
    hits = _records_missing(rng, miss)
    pid, kw, L0, listed = _gather_inputs(rng, n, N, count, bsdf)
    given, read = L0.copy(), L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, given, **kw)
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, hits, pid, read, **kw)
    # (the sun's and the world's: a gather with no ray missed differs)
    unseen = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, np.zeros(n, bool), pid, unseen, **kw)
    assert (given != unseen).any(axis=0).sum() > 1000, 'too few rays see the lamps at infinity to test it'
    assert given.tobytes() == read.tobytes()
    other = np.zeros(n, [('t', '<f4'), ('prim', '<i8'), ('u', '<f4')])
    for bad in (other, hits[::2], np.zeros(n, [('a', '<f8'), ('b', '<f8')])):
        L = L0.copy()
        with pytest.raises(ValueError, match=r"miss must be bool flags or .*hit records"):
            dacrt.lamps._core.lamp_gather(rec, listed, kw.get('lamp_prob'), O, D, t_surf, bad, kw.get('thr'),
                                          kw.get('pdf_bsdf'), pid.astype(np.int64), L)
        assert L.tobytes() == L0.tobytes()
