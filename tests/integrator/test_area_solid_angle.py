"""Square and rectangle area lights sampled by solid angle (addon/lights/area.py, lamps.h sph_rect):
native and Python samples against closed forms for an axis-aligned light facing down: where the
samples land (each part of the light gets its share of the solid angle), the pdf (1 / the exact
solid angle), the irradiance estimate and its variance, the pdf a ray along a sample meets the
light with, the fall-back to area sampling (the same choice on both sides), and degenerate points
and sizes."""
import dacrt
import numpy as np
import pytest

from addon.lights import area as area_module
from addon.lights import lamp_records, make_lamp

from .scenes import light, rotation_x, translation

F32 = np.float32
HALF = 2.0            # a size-4 square, 0.5 above the points: the case area sampling was bad at
HEIGHT = 0.5


def solid_angle(x0, x1, y0, y1, h):
    """Exact solid angle of [x0, x1] x [y0, y1] at depth h below the point (float64)."""
    F = lambda x, y: np.arctan(x * y / (h * np.sqrt(x * x + y * y + h * h)))   # noqa: E731
    return F(x1, y1) - F(x0, y1) - F(x1, y0) + F(x0, y0)


def irradiance(L, x0, x1, y0, y1, h):
    """Irradiance on an upward-facing receiver h below [x0, x1] x [y0, y1] (radiance L): the
    signed sum of the corner rectangles' closed form."""
    def corner(x, y):
        a, b = np.abs(x), np.abs(y)
        A, B = a / np.hypot(a, h), b / np.hypot(b, h)
        return np.sign(x) * np.sign(y) * 0.5 * L * (A * np.arctan(b / np.hypot(a, h)) + B * np.arctan(a / np.hypot(b, h)))
    return corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)


def square(half=HALF, z=HEIGHT, **kw):
    """An axis-aligned square (or rectangle: size_y) facing down, centred at (0, 0, z)."""
    kw.setdefault('shape', 'SQUARE')
    return make_lamp(light('AREA', 100.0, translation(z=z), size_x=2 * half, **kw))


def draw(lamp, P, n, native, seed=0):
    """n light samples at the single point P: wi, dist, value (red), pdf as float64."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random((2, n), np.float32)
    Pn = np.repeat(np.asarray(P, F32)[:, None], n, axis=1)
    if native:
        wi, dist, value, pdf = dacrt.lamps.lamp_sample(lamp_records([lamp]), np.zeros(n, np.int32), Pn, u1, u2)
    else:
        s = lamp.sample(Pn, u1, u2)
        wi, dist, value, pdf = s.wi, s.dist, s.value, s.pdf
    return wi.astype(np.float64), dist.astype(np.float64), value[0].astype(np.float64), pdf.astype(np.float64)


SIDES = [('native', True), ('python', False)]


@pytest.mark.parametrize('side,native', SIDES)
@pytest.mark.parametrize('foot', [(0.0, 0.0), (1.3, -0.6), (2.6, 0.4)])
def test_samples_fill_the_light_by_solid_angle(side, native, foot):
    """Chi-square of where 200k samples meet the light, over a 6 x 6 grid of cells: each cell's
    share is its solid angle over the light's (area sampling gives its area share: chi^2 in the
    tens of thousands here), and every sample's pdf is 1 / the exact solid angle."""
    lamp = square()
    P = (foot[0], foot[1], 0.0)
    n = 200_000
    wi, dist, value, pdf = draw(lamp, P, n, native)
    q = np.asarray(P)[:, None] + wi * dist                 # on the light's plane z = HEIGHT
    assert np.abs(q[2] - HEIGHT).max() < 1e-5
    edges = np.linspace(-HALF, HALF, 7)
    counts, _, _ = np.histogram2d(q[0], q[1], bins=[edges, edges])
    assert counts.sum() == n
    x0, y0 = np.meshgrid(edges[:-1] - foot[0], edges[:-1] - foot[1], indexing='ij')
    cells = solid_angle(x0, x0 + edges[1] - edges[0], y0, y0 + edges[1] - edges[0], HEIGHT)
    S = solid_angle(-HALF - foot[0], HALF - foot[0], -HALF - foot[1], HALF - foot[1], HEIGHT)
    assert cells.sum() == pytest.approx(S, rel=1e-12)
    expected = n * cells / S
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert chi2 < 80, f'chi^2 {chi2:.0f} for 35 degrees of freedom'  # p ~ 1e-5
    np.testing.assert_allclose(pdf, 1.0 / S, rtol=2e-6)


@pytest.mark.parametrize('side,native', SIDES)
@pytest.mark.parametrize('where', ['centre', 'edge', 'outside', 'far_below', 'far_side', 'rectangle'])
def test_irradiance_estimate_is_the_closed_form(side, native, where):
    """The mean of value x cos_r (receiver facing up) over 400k samples equals the closed-form
    irradiance to 3 standard errors + 1e-4 (no bias from the float32 warp), below the light,
    at its edge, outside its footprint, under a long thin rectangle, and where the rectangle is
    sampled by area: 200 m below (S 4e-4 sr) and 60 m to the side (under 2 degrees)."""
    kw, P = {}, {'centre': (0.3, -0.2, 0.0), 'edge': (HALF, 0.7, 0.0), 'outside': (HALF + 3.0, -1.0, 0.0),
                 'far_below': (0.5, 0.0, -200.0), 'far_side': (60.0, 0.0, -1.5), 'rectangle': (0.1, 0.2, 0.0)}[where]
    half_y = HALF
    if where == 'rectangle':
        kw, half_y = dict(shape='RECTANGLE', size_y=0.1), 0.05
    lamp = square(**kw)
    wi, dist, value, pdf = draw(lamp, P, 400_000, native, seed=3)
    v = value * np.maximum(wi[2], 0.0)
    h = HEIGHT - P[2]
    L = 100.0 / (np.pi * lamp.area)
    E = irradiance(L, -HALF - P[0], HALF - P[0], -half_y - P[1], half_y - P[1], h)
    mean, err = v.mean(), v.std() / np.sqrt(len(v))
    assert abs(mean - E) < 3 * err + 1e-4 * E, f'{mean} +- {err}, closed form {E}'
    S = solid_angle(-HALF - P[0], HALF - P[0], -half_y - P[1], half_y - P[1], h)
    by_angle = lamp._sph_rect(np.asarray(P, F32)[:, None], -0.5, 0.5, -0.5, 0.5)['use'][0]
    assert by_angle == (not where.startswith('far'))
    if by_angle:
        np.testing.assert_allclose(pdf, 1.0 / S, rtol=2e-5)


@pytest.mark.parametrize('side,native', SIDES)
def test_close_to_a_large_light_only_the_cosine_is_noise(side, native):
    """0.5 m below a 4 m square: by solid angle the estimate L S cos_r varies only with the
    receiver's cosine (relative standard deviation 0.37 below the centre); uniform by area it
    also carries t^2 / cos_l, 1 at the foot to ~200 at the corners (2.55): 7x the standard
    deviation, 47x the samples for the same noise. The solid-angle estimate's relative standard
    deviation is exactly that of cos_r over its samples."""
    lamp = square()
    wi, _, value, _ = draw(lamp, (0.0, 0.0, 0.0), 200_000, native, seed=5)
    v = value * np.maximum(wi[2], 0.0)
    rsd = v.std() / v.mean()
    # area sampling, in closed form on the same number of uniform points
    rng = np.random.default_rng(6)
    q = rng.uniform(-HALF, HALF, (2, 200_000))
    t2 = q[0] ** 2 + q[1] ** 2 + HEIGHT ** 2
    cos = HEIGHT / np.sqrt(t2)
    area = (lamp.area * cos * cos / t2)          # L-free: value / L = cos_l cos_r A / t^2
    rsd_area = area.std() / area.mean()
    assert rsd_area > 2.4
    assert rsd < 0.4 and rsd < rsd_area / 6, (rsd, rsd_area)
    c = np.maximum(wi[2], 0.0)
    assert rsd == pytest.approx(c.std() / c.mean(), rel=1e-6)


def mis_pdfs(lamp, P, seed=0):
    """The native sample pdf at each point P, and the pdf lamp_gather weighs a ray along that
    sample with (power heuristic at lamp_prob 1 against pdf_bsdf = the sample's pdf: w = 1/2
    exactly where they agree)."""
    rec = lamp_records([lamp])
    n = P.shape[1]
    u1, u2 = np.random.default_rng(seed).random((2, n), np.float32)
    wi, dist, value, pdf = dacrt.lamps.lamp_sample(rec, np.zeros(n, np.int32), P, u1, u2)
    good = np.flatnonzero(value.max(axis=0) > 0)
    m = len(good)
    O, D = np.ascontiguousarray(P[:, good]), np.ascontiguousarray(wi[:, good])
    t_surf, miss, pid = np.full(m, np.inf, F32), np.zeros(m, bool), np.arange(m)
    Le, Lw = np.zeros((3, m), F32), np.zeros((3, m), F32)
    dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, Le)
    dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, Lw, pdf_bsdf=np.ascontiguousarray(pdf[good]),
                            lamp_prob=np.ones(1, F32))
    seen = Le[0] > 0
    w = Lw[0, seen].astype(np.float64) / Le[0, seen]
    return good, seen, pdf[good][seen].astype(np.float64), w


@pytest.mark.parametrize('spread_deg', [180.0, 120.0])
def test_gather_pdf_is_the_sample_pdf_on_both_sides_of_the_fallback(spread_deg):
    """MIS: at points on both sides of the thresholds where sampling falls back to area (S near
    1e-3 sr, the light's elevation near tan 0.05, through thousands of points spanning them), a
    ray along each native sample meets the light (lamp_gather) with the sample's pdf: the power
    heuristic against that pdf is 1/2. A choice made differently by the two would show as the
    ratio of the area and solid-angle pdfs (0.5% to tens of percents here). The light is large
    (12 x 5) so that it does not look small (SA_SMALL) from these points."""
    lamp = make_lamp(light('AREA', 100.0, translation(0.2, -0.1, 1.5) @ rotation_x(0.3), shape='RECTANGLE',
                           size_x=12.0, size_y=5.0, spread=np.radians(spread_deg)))
    rng = np.random.default_rng(8)
    n = 60_000
    # feet beyond the light's edge at distance d, heights about the elevation threshold 0.05 d;
    # and points straight out at distances where S crosses 1e-3
    d = rng.uniform(0.5, 4.0, n)
    tan_el = rng.uniform(0.03, 0.08, n)
    side = rng.uniform(-0.4, 0.4, n)
    h = np.where(rng.random(n) < 0.5, d * tan_el, rng.uniform(10.0, 40.0, n))
    P = (lamp.center[:, None] + lamp.axis_x[:, None] * (0.5 + d / np.linalg.norm(lamp.axis_x))
         + lamp.axis_y[:, None] * side + lamp.normal[:, None] * h).astype(F32)
    if spread_deg < 180:
        # the spread's box about a foot beyond the light's edge reaching over it by 1e-4 to 1 of
        # its half-width r: the clamped rectangle's S across decades
        h = rng.uniform(0.05, 3.0, n)
        r = h * np.tan(np.radians(spread_deg) / 2) / np.linalg.norm(lamp.axis_x)
        P = (lamp.center[:, None] + lamp.axis_x[:, None] * (0.5 + r * (1 - 10 ** rng.uniform(-4, 0, n)))
             + lamp.axis_y[:, None] * side + lamp.normal[:, None] * h).astype(F32)
    good, seen, pdf, w = mis_pdfs(lamp, P)
    assert seen.mean() > 0.999
    # both samplers are in play: pdfs equal to 1 / S of the (clamped) rectangle and others
    r = lamp._sph_rect(P[:, good][:, seen], *(lamp._spread_box(P[:, good][:, seen])[:4]
                                               if spread_deg < 180 else (-0.5, 0.5, -0.5, 0.5)))
    by_angle = r['use']
    assert 0.05 < by_angle.mean() < 0.95
    # by solid angle both compute 1 / S at the same point with the same float32 operations: equal
    np.testing.assert_array_equal(pdf[by_angle], (F32(1.0) / r['S'][by_angle]).astype(np.float64))
    assert (w[by_angle] == 0.5).all()
    # by area the ray's t and the sample's distance round differently (~1e-5); had the two
    # chosen differently, w would be off by the pdfs' ratio, which here is far from 1
    np.testing.assert_allclose(w[~by_angle], 0.5, rtol=1e-4)
    assert np.median(np.abs(pdf[~by_angle] * r['S'][~by_angle] - 1)) > 2e-3


def test_gather_pdf_is_the_sample_pdf_where_the_light_turns_small():
    """A light whose half-diagonal is under SA_SMALL x its centre's distance is sampled by area
    (7x cheaper per sample, and as good there: the Cornell box's whole image is); sample and
    gather decide it at the same point alike, on both sides (points below and beside the
    light at distances spanning the threshold)."""
    lamp = make_lamp(light('AREA', 100.0, translation(0.2, -0.1, 1.5) @ rotation_x(0.3), shape='RECTANGLE',
                           size_x=1.2, size_y=0.5))
    rng = np.random.default_rng(9)
    n = 40_000
    half_diagonal = 0.5 * np.hypot(1.2, 0.5)
    dist = half_diagonal / area_module.SA_SMALL * rng.uniform(0.6, 1.6, n)
    off = rng.uniform(-0.6, 0.6, (2, n)) * dist
    h = np.sqrt(np.maximum(dist ** 2 - (off ** 2).sum(0), 1e-4))
    P = (lamp.center[:, None] + lamp.axis_x[:, None] * off[0] / np.linalg.norm(lamp.axis_x)
         + lamp.axis_y[:, None] * off[1] / np.linalg.norm(lamp.axis_y) + lamp.normal[:, None] * h).astype(F32)
    good, seen, pdf, w = mis_pdfs(lamp, P)
    assert seen.mean() > 0.999
    r = lamp._sph_rect(P[:, good][:, seen], -0.5, 0.5, -0.5, 0.5)
    by_angle = r['use']
    assert 0.2 < by_angle.mean() < 0.8
    np.testing.assert_array_equal(pdf[by_angle], (F32(1.0) / r['S'][by_angle]).astype(np.float64))
    assert (w[by_angle] == 0.5).all()
    np.testing.assert_allclose(w[~by_angle], 0.5, rtol=1e-4)


EDGE_POINTS = {
    'on_plane_inside': (0.3, 0.2, HEIGHT), 'on_plane_outside': (5.0, 0.2, HEIGHT),
    'just_below_centre': (0.0, 0.0, HEIGHT - 1e-6), 'just_below_corner': (HALF, HALF, HEIGHT - 1e-7),
    'at_corner': (HALF, -HALF, HEIGHT), 'below_corner': (HALF, -HALF, 0.0), 'behind': (0.5, 0.5, HEIGHT + 0.3),
    'grazing': (HALF + 1.0, 0.0, HEIGHT - 1e-5), 'far': (1e6, -2e6, -3e6), 'very_far_below': (0.0, 0.0, -1e9),
}


@pytest.mark.parametrize('side,native', SIDES)
@pytest.mark.parametrize('scale', [1.0, 1e-9, 1e9])
def test_degenerate_points_and_sizes_stay_finite(side, native, scale):
    """Points on the light's plane, just below its centre or a corner, at a corner, behind it,
    grazing it, far away; the whole set-up scaled by 1e-9 and 1e9: finite directions, distances,
    values and pdfs, no light where the light cannot reach, and a ray along each lit sample
    meets the light with a finite pdf."""
    lamp = make_lamp(light('AREA', 100.0, np.diag([scale, scale, scale, 1.0]) @ translation(z=HEIGHT),
                           shape='SQUARE', size_x=2 * HALF))
    names = list(EDGE_POINTS)
    P = (np.array([EDGE_POINTS[k] for k in names], np.float64).T * scale).astype(F32)
    reps = 64
    P = np.repeat(P, reps, axis=1)
    rng = np.random.default_rng(9)
    u1, u2 = rng.random((2, P.shape[1]), np.float32)
    u1[:4], u2[:4] = [0.0, 0.0, 1 - 2 ** -24, 0.5], [0.0, 1 - 2 ** -24, 0.0, 0.5]
    if native:
        wi, dist, value, pdf = dacrt.lamps.lamp_sample(lamp_records([lamp]), np.zeros(P.shape[1], np.int32),
                                                       P, u1, u2)
    else:
        s = lamp.sample(P, u1, u2)
        wi, dist, value, pdf = s.wi, s.dist, s.value, s.pdf
    for what, a in (('wi', wi), ('dist', dist), ('value', value), ('pdf', pdf)):
        bad = ~np.isfinite(a).reshape(-1, P.shape[1]).all(axis=0)
        assert not bad.any(), f'{what} not finite at {sorted({names[i // reps] for i in np.flatnonzero(bad)})}'
    assert (value >= 0).all() and (pdf >= 0).all()
    lit = value.max(axis=0) > 0
    per_point = lit.reshape(len(names), reps).any(axis=1)
    dark = {'on_plane_inside', 'on_plane_outside', 'at_corner', 'behind'}
    assert {k for k, on in zip(names, per_point) if on} == set(names) - dark
    good = np.flatnonzero(lit)
    idx, Le, pdf_hit = lamp.intersect(P[:, good], wi[:, good], np.full(len(good), np.inf, F32))
    assert np.isfinite(pdf_hit).all() and (pdf_hit > 0).all() and np.isfinite(Le).all()
    if native:
        O, D = np.ascontiguousarray(P[:, good]), np.ascontiguousarray(wi[:, good])
        m = len(good)
        L = np.zeros((3, m), F32)
        dacrt.lamps.lamp_gather(lamp_records([lamp]), [0], O, D, np.full(m, np.inf, F32), np.zeros(m, bool),
                                np.arange(m), L, pdf_bsdf=np.ascontiguousarray(pdf[good]), lamp_prob=np.ones(1, F32))
        assert np.isfinite(L).all()
