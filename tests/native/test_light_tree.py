"""The light tree (dacrt.lamps.LightTree, native/cpp/lighttree.h): at every point its pick is a
probability distribution over its lights, sampling follows the pdf it reports (the MIS weights
of BSDF rays rely on that), two lights split by the importance written out here in float64,
lights that cannot face a point are never picked, delta lights always can be, and bad input is
refused with a message naming the light."""

import numpy as np
import pytest
from dacrt import lamps

F32 = np.float32
EVERY = -1.0      # cos_o of a light that emits in every direction


def tree_of(centers, half, energy, axis=None, cos_o=None, cos_e=None, keys=None):
    c = np.asarray(centers, F32).reshape(3, -1)
    m = c.shape[1]
    h = np.asarray(half, F32)
    h = np.broadcast_to(h.reshape(3, 1) if h.shape == (3,) and m != 3 else h, (3, m))
    axis = np.tile([[0.0], [0.0], [1.0]], (1, m)) if axis is None else np.asarray(axis).reshape(3, m)
    cos_o = np.full(m, EVERY) if cos_o is None else np.asarray(cos_o)
    cos_e = np.zeros(m) if cos_e is None else np.asarray(cos_e)
    keys = np.arange(m) if keys is None else np.asarray(keys)
    return lamps.light_tree(c - h, c + h, axis, cos_o, cos_e, np.asarray(energy, np.float64), keys)


def random_tree(rng, m, one_sided=0.5, scale=1.0):
    """Area-like lights (a hemisphere), spot-like ones (a cone, no falloff), point lamps (alike
    every way: cos_e -1) and two-sided emitters (every direction, cos_e 0): the smallest
    importance > 0 at some points for all but the last."""
    c = rng.uniform(-5, 5, (3, m)) * scale
    axis = rng.normal(size=(3, m))
    axis /= np.linalg.norm(axis, axis=0)
    kind = np.where(rng.random(m) < one_sided, rng.integers(0, 2, m), rng.integers(2, 4, m))
    cos_o = np.choose(kind, [1.0, rng.uniform(0.3, 0.95, m), EVERY, EVERY])
    # (spot-like: a falloff of 8 degrees, not a spot's none: at cos_e 1 the float path's culling
    # margin of 1e-5 in the cosine is 0.26 degrees wide, where float64 culls and float does not)
    cos_e = np.choose(kind, [0.0, 0.99, -1.0, 0.0])
    return tree_of(c, rng.uniform(0.0, 0.3, (3, m)) * scale, rng.uniform(0.1, 10.0, m), axis, cos_o, cos_e,
                   keys=np.arange(m) + 7)


def random_normals(rng, n):
    N = rng.normal(size=(3, n))
    return (N / np.linalg.norm(N, axis=0)).astype(F32)


@pytest.mark.parametrize("scale", [1.0, 1e17, 1e-17])
@pytest.mark.parametrize("with_normal", [False, True])
def test_pdf_is_a_distribution_and_sampling_follows_it(scale, with_normal):
    """At every scale (1: the float path; 1e17, 1e-17: squared distances beyond float's safe
    range, the float64 path) and with or without a receiving normal."""
    rng = np.random.default_rng(3)
    m = 40
    tree = random_tree(rng, m, scale=scale)
    assert tree.members == m and tree.nodes == 2 * m - 1
    keys = np.arange(m) + 7
    for P in (rng.uniform(-6, 6, (5, 3, 1)) * scale).astype(F32):
        N = np.repeat(random_normals(rng, 1), m, 1) if with_normal else None
        pdf = tree.pdf(np.repeat(P, m, 1), keys, N)
        assert pdf.sum() == pytest.approx(1.0, abs=1e-12)
        n = 400_000
        got, prob = tree.sample(np.repeat(P, n, 1), rng.random(n), None if N is None else N[:, :1].repeat(n, 1))
        assert np.isin(got, keys).all()
        # the probability sample() reports is the pdf of what it picked
        np.testing.assert_allclose(prob, pdf[got - 7], rtol=1e-12)
        freq = np.bincount(got - 7, minlength=m) / n
        sigma = np.sqrt(pdf * (1 - pdf) / n)
        assert np.all(np.abs(freq - pdf) <= 5 * sigma + 1e-9)
        assert np.all(freq[pdf == 0] == 0)
    assert tree.pdf(np.zeros((3, 2), F32), np.array([0, 10_000])).tolist() == [0.0, 0.0]   # not members


def test_the_float_path_weighs_as_the_float64_path():
    """Scaling a scene scales every importance by the same factor, so the pdf is the same;
    at scale 1 it is weighed in float, at 1e17 and 1e-17 in float64: they agree to float's
    precision, so the float path neither culls nor misweighs what float64 would not."""
    rng = np.random.default_rng(11)
    m = 60
    P = rng.uniform(-6, 6, (3, 300))
    N = random_normals(rng, 300)
    keys = np.arange(m) + 7
    pdfs = {}
    for scale in (1.0, 1e17, 1e-17):
        tree = random_tree(np.random.default_rng(5), m, scale=scale)
        Q = (P * scale).astype(F32)
        pdfs[scale] = np.stack([tree.pdf(np.repeat(Q[:, i:i + 1], m, 1), keys, np.repeat(N[:, i:i + 1], m, 1))
                                for i in range(P.shape[1])])
    assert (pdfs[1.0] > 0).sum() > 0.3 * pdfs[1.0].size         # (a test of weighing, not of culling alone)
    for scale in (1e17, 1e-17):
        np.testing.assert_array_equal(pdfs[scale] > 0, pdfs[1.0] > 0)
        # float's sines near a cosine of 1 carry ~sqrt(float eps) = 3e-4 of the pdf's factor
        np.testing.assert_allclose(pdfs[scale], pdfs[1.0], rtol=1e-3, atol=1e-12)


def importance(center, radius, energy, P, axis=None, one_sided=False):
    """lighttree.h's importance in float64: energy x cos(smallest emission angle) / d^2."""
    v = np.asarray(center, np.float64) - P
    d2 = v @ v
    if d2 <= radius ** 2:
        return energy / max(d2, radius ** 2 / 4)
    f = 1.0
    if one_sided:            # theta_o = 0, theta_e = pi/2
        d = np.sqrt(d2)
        theta = np.arccos(np.clip(-(np.asarray(axis) @ v) / d, -1, 1))
        theta_u = np.arcsin(radius / d)
        rest = max(theta - theta_u, 0.0)
        if rest >= np.pi / 2:
            return 0.0
        f = np.cos(rest)
    return energy * f / d2


def smallest_importance(center, radius, energy, P, axis=None, one_sided=False, alike=False):
    """Cycles' min_importance (kernel/light/tree.h) in float64, as lighttree.cpp's weigh() takes
    it without a normal: 0 inside the sphere; a light alike every way (a point lamp) energy x
    cos(theta_u) / d^2, as Cycles orients a point light's disk toward P; a one-sided light
    (theta_o = 0, theta_e = pi/2) energy x cos(theta + theta_u) / d^2 where theta + theta_u <=
    pi/2 (and theta <= pi/2), else 0; a light of every direction otherwise (a two-sided
    emitter) 0: it may give nothing."""
    v = np.asarray(center, np.float64) - P
    d2 = v @ v
    if d2 <= radius ** 2 or not (alike or one_sided):
        return 0.0
    d = np.sqrt(d2)
    theta_u = np.arcsin(radius / d)
    if alike:
        return energy * np.cos(theta_u) / d2
    theta = np.arccos(np.clip(-(np.asarray(axis) @ v) / d, -1, 1))
    if theta > np.pi / 2 or theta + theta_u > np.pi / 2:
        return 0.0
    return energy * np.cos(theta + theta_u) / d2


def cycles_split(imax, imin):
    """Cycles' get_left_probability for each light of a split: the mean of the shares by the
    largest and by the smallest importances; where the smallest sum to 0, the share by the
    largest alone (Cycles' even share there is not taken: README)."""
    imax, imin = np.asarray(imax, np.float64), np.asarray(imin, np.float64)
    return 0.5 * (imax / imax.sum() + imin / imin.sum()) if imin.sum() > 0 else imax / imax.sum()


@pytest.mark.parametrize("alike", [False, True])
def test_two_lights_split_by_importance(alike):
    """Two lights, one of every direction (a two-sided emitter, or alike every way: a point
    lamp, cos_e -1) and one one-sided: the pick is Cycles' mean of the shares by their largest
    and smallest importances, computed independently here (the smallest matters at most points:
    the one-sided light's is > 0 wherever the point lies well within its hemisphere)."""
    rng = np.random.default_rng(5)
    seen = 0
    for _ in range(50):
        c = rng.uniform(-3, 3, (3, 2))
        E = rng.uniform(0.5, 20.0, 2)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        half = 0.1
        tree = tree_of(c, half, E, axis=np.stack([[0, 0, 1.0], axis], 1), cos_o=[EVERY, 1.0],
                       cos_e=[-1.0 if alike else 0.0, 0.0])
        P = rng.uniform(-4, 4, 3).astype(F32)
        r = np.sqrt(3) * half
        # the stored bounds: the boxes' float32 centres and their half-diagonals
        c32 = ((c - half).astype(F32).astype(np.float64) + (c + half).astype(F32).astype(np.float64)) / 2
        Q = P.astype(np.float64)
        ia = importance(c32[:, 0], r, E[0], Q)
        ib = importance(c32[:, 1], r, E[1], Q, axis=axis, one_sided=True)
        ma = smallest_importance(c32[:, 0], r, E[0], Q, alike=alike)
        mb = smallest_importance(c32[:, 1], r, E[1], Q, axis=axis, one_sided=True)
        seen += mb > 0
        pdf = tree.pdf(np.repeat(P[:, None], 2, 1), np.array([0, 1]))
        assert pdf[1] == pytest.approx(cycles_split([ia, ib], [ma, mb])[1], rel=1e-4, abs=1e-12)
    assert seen > 5


def test_a_faint_light_that_surely_reaches_keeps_half_the_samples():
    """Fuzz seed 10's case (README, the light tree): a faint narrow spot over the point beside a
    tilted area light ~3000x brighter whose Spread may or may not reach it. By the largest
    importances alone the spot got ~1e-3 of the samples; by Cycles' rule (the area light's
    smallest importance is 0 there, the spot's > 0) about half, and sampling follows the pdf."""
    # spot 2 m above the point aiming down (cone 30 degrees); area light 1.8 m off to the side
    # (its sphere 22 degrees wide from there), facing 70 degrees off the point's direction:
    # within its 80-degree reach (Spread 160 degrees), but not surely (70 + 22 > 80)
    spot_c, area_c = np.array([0.0, 0.0, 2.0]), np.array([1.5, 0.0, 1.0])
    to_p = -area_c / np.linalg.norm(area_c)
    a = np.radians(70.0)
    area_axis = np.array([to_p[0] * np.cos(a) + to_p[2] * np.sin(a), 0.0, -to_p[0] * np.sin(a) + to_p[2] * np.cos(a)])
    assert np.degrees(np.arccos(area_axis @ to_p)) == pytest.approx(70.0)
    c = np.stack([spot_c, area_c], 1)
    h = np.array([[0.02, 0.4], [0.02, 0.4], [0.02, 0.4]])
    axis = np.stack([[0.0, 0.0, -1.0], area_axis], 1)
    cos_o = np.array([np.cos(np.radians(30.0)), 1.0])
    cos_e = np.array([1.0, np.cos(np.radians(80.0))])
    E = np.array([1.0, 3000.0])
    tree = lamps.light_tree((c - h).astype(F32), (c + h).astype(F32), axis, cos_o, cos_e, E, np.arange(2))
    P = np.zeros((3, 1), F32)
    pdf = tree.pdf(np.repeat(P, 2, 1), np.arange(2))
    assert pdf.sum() == pytest.approx(1.0, abs=1e-12)
    assert 0.45 < pdf[0] < 0.55
    n = 200_000
    got, prob = tree.sample(np.repeat(P, n, 1), np.random.default_rng(1).random(n))
    np.testing.assert_allclose(prob, pdf[got], rtol=1e-12)
    freq = np.bincount(got, minlength=2) / n
    assert np.all(np.abs(freq - pdf) <= 5 * np.sqrt(pdf * (1 - pdf) / n))


@pytest.mark.parametrize("case", ["subnormal_smallest", "subnormal_largest"])
def test_energies_at_the_floor_far_away_keep_finite_probabilities(case):
    """addon/lights/tree.py floors energies at 1e-300 so that a faint light stays reachable. Far
    away, a sum of importances can then be subnormal, and its inverse overflows: the shares were
    inf and NaN (the emitter never picked, the lamp's samples weighing 1/inf = 0). Now such a sum
    counts as none (the largest alone, or the energies), on every path: pdf, sample, rows."""
    if case == "subnormal_smallest":     # a two-sided emitter (smallest 0) and a point lamp (cos_e -1)
        c = np.array([[1e5, 1e5], [0.0, 30.0], [0.0, 0.0]])
        cos_e, E = np.array([0.0, -1.0]), np.array([1e-290, 1e-300])
    else:                                # two point lamps at the floor, 1e6 m away
        c = np.array([[1e6, 1e6 + 3.0], [0.0, 0.0], [0.0, 0.0]])
        cos_e, E = np.array([-1.0, -1.0]), np.array([1e-300, 3e-300])
    h = 0.01
    tree = lamps.light_tree((c - h).astype(F32), (c + h).astype(F32), np.tile([[0.0], [0.0], [1.0]], (1, 2)),
                            np.full(2, EVERY), cos_e, E, np.arange(2))
    P = np.zeros((3, 1), F32)
    pdf = tree.pdf(np.repeat(P, 2, 1), np.arange(2))
    assert np.all(np.isfinite(pdf)) and np.all(pdf > 0.0), pdf
    assert pdf.sum() == pytest.approx(1.0, abs=1e-12)
    u = np.linspace(0.01, 0.99, 64)
    for rows in (False, True):
        got, prob = tree.sample(np.repeat(P, len(u), 1), u, rows=rows)
        assert np.all(np.isfinite(prob)) and np.all(prob > 0.0), (rows, prob)
        np.testing.assert_allclose(prob, pdf[got], rtol=1e-12)


@pytest.mark.parametrize("far", [2.0, 1e6, 1e15])
def test_the_smallest_energy_accepted_keeps_finite_probabilities(far):
    """The smallest normal double is the least energy a light may have: alone or beside lights of
    energy 1, near or far, every pick's probability is finite in (0, 1] and the pdf's. (A denormal
    one, 5e-324 or 1e-310, had been accepted and every pick made with probability inf.)"""
    tiny = np.finfo(np.float64).tiny
    rng = np.random.default_rng(1)
    c = rng.uniform(-1.0, 1.0, (3, 8))
    P = (rng.normal(size=(3, 500)) * far).astype(F32)
    u = rng.random(500)
    for E in ([tiny] * 8, [tiny, 1.0] * 4):
        tree = tree_of(c, 0.0, E)
        for rows in (False, True):
            got, prob = tree.sample(P, u, rows=rows)
            assert np.all(np.isfinite(prob) & (prob > 0.0) & (prob <= 1.0)), (E[:2], rows, prob[:4])
            np.testing.assert_allclose(tree.pdf(P, got), prob, rtol=1e-12)


def test_a_light_facing_away_is_never_picked_and_delta_lights_always_can_be():
    """A one-sided light whose back faces the point gets probability 0 (a light sample there
    would be wasted); a point light, however faint and far, keeps a probability > 0 beside a
    bright near one (light sampling is its only estimator: 0 would lose its light)."""
    P = np.zeros((3, 1), F32)
    # area-like light above the point, emitting upward (away), and one below emitting up at it
    tree = tree_of([[0, 0], [0, 0], [2, -2]], [0.2, 0.2, 0.0], [5.0, 5.0],
                   axis=[[0, 0], [0, 0], [1, 1]], cos_o=[1.0, 1.0])
    np.testing.assert_allclose(tree.pdf(np.repeat(P, 2, 1), np.array([0, 1])), [0.0, 1.0])
    # a point below both faces neither: the split falls back to energy, never 0/0
    below = np.array([[0.0], [0.0], [-10.0]], F32)
    np.testing.assert_allclose(tree.pdf(np.repeat(below, 2, 1), np.array([0, 1])), [0.5, 0.5])
    m = 200
    rng = np.random.default_rng(9)
    c = np.concatenate([[[0.0], [0.0], [0.5]], rng.uniform(1e3, 2e3, (3, m - 1))], axis=1)
    E = np.concatenate([[1e6], np.full(m - 1, 1e-6)])
    faint = tree_of(c, 0.0, E)
    pdf = faint.pdf(np.repeat(P, m, 1), np.arange(m))
    assert (pdf > 0).all() and pdf.sum() == pytest.approx(1.0)


def test_one_light_and_coincident_lights():
    one = tree_of([[1.0], [2.0], [3.0]], 0.0, [4.0], keys=[5])
    assert one.members == 1 and one.nodes == 1
    key, prob = one.sample(np.zeros((3, 3), F32), np.array([0.0, 0.5, 1.0]))
    assert key.tolist() == [5, 5, 5] and prob.tolist() == [1.0, 1.0, 1.0]
    # the same place, energies 1 : 3: a point anywhere splits them 1 : 3 (P on them too), by the
    # largest importances alone (the smallest are 0: two-sided emitters may give nothing), and
    # as lights alike every way (cos_e -1) by the mean of 1 : 3 and 1 : 3
    same = tree_of(np.zeros((3, 2)), 0.0, [1.0, 3.0])
    alike = tree_of(np.zeros((3, 2)), 0.0, [1.0, 3.0], cos_e=[-1.0, -1.0])
    for P in (np.zeros((3, 1), F32), np.ones((3, 1), F32)):
        np.testing.assert_allclose(same.pdf(np.repeat(P, 2, 1), np.array([0, 1])), [0.25, 0.75])
        np.testing.assert_allclose(alike.pdf(np.repeat(P, 2, 1), np.array([0, 1])), [0.25, 0.75])


@pytest.mark.parametrize('bad, message', [
    (dict(lo_nan=True), 'light 1: bounds must be finite'),
    (dict(energy=[1.0, 0.0]), r'light 1: energy must lie in \[2.2250738585072014e-308 \(the smallest normal double\), 1e200\]'),
    (dict(energy=[1.0, np.inf]), 'light 1: energy must lie in'),
    (dict(energy=[5e-324, 1.0]), 'light 0: energy must lie in'),       # denormal: its probability was inf
    (dict(energy=[1.0, 2.2e-308]), 'light 1: energy must lie in'),
    (dict(keys=[3, 3]), 'light 1: key 3 is not unique'),
    (dict(keys=[0, -2]), 'light 1: key must lie in'),
    (dict(cos_o=[1.0, 2.0]), 'light 1: cos_o and cos_e must lie in'),
    (dict(m=0), 'at least one light'),
    (dict(radius=[1.0, -0.5]), 'light 1: radius must be >= 0'),
    (dict(radius=[np.nan, 1.0]), 'light 0: radius must be >= 0'),
])
def test_bad_input_is_refused_naming_the_light(bad, message):
    m = bad.get('m', 2)
    lo = np.zeros((3, m), F32)
    if bad.get('lo_nan'):
        lo[1, 1] = np.nan
    with pytest.raises(ValueError, match=message):
        lamps.light_tree(lo, np.ones((3, m), F32), np.tile([[0.0], [0.0], [1.0]], (1, m)),
                         bad.get('cos_o', np.full(m, EVERY)), np.zeros(m), bad.get('energy', np.ones(m)),
                         bad.get('keys', np.arange(m)), radius=bad.get('radius'))


def test_a_lone_lights_own_sphere_narrows_its_cone_test():
    """A flat light 1 m wide, tilted in its box (half extents 0.5 each way: a box sphere of
    0.87 m) emitting within 48 degrees of +z, and a far point light: at a point seen 62 degrees
    off the axis from 3 m, its box's sphere (17 degrees) keeps it, its own of 0.5 m (10 degrees)
    culls it. A radius of inf is the box's, as none."""
    c = np.array([[0.0, 20.0], [0.0, 20.0], [0.0, 20.0]], F32)
    h = np.array([[0.5, 0.0], [0.5, 0.0], [0.5, 0.0]], F32)
    axis = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]])
    args = (c - h, c + h, axis, np.array([1.0, EVERY]), np.array([np.cos(np.radians(48.0)), 0.0]),
            np.array([1.0, 1e-3]), np.arange(2))
    a = np.radians(62.0)
    P = np.array([[3.0 * np.sin(a)], [0.0], [3.0 * np.cos(a)]], F32)
    box, none = lamps.light_tree(*args, radius=[np.inf, np.inf]), lamps.light_tree(*args)
    own = lamps.light_tree(*args, radius=[0.5, 0.0])
    assert box.pdf(P, np.array([0]))[0] > 0.5
    assert box.pdf(P, np.array([0]))[0] == none.pdf(P, np.array([0]))[0]
    assert own.pdf(P, np.array([0]))[0] == 0.0
    np.testing.assert_allclose(own.pdf(P, np.array([1]))[0], 1.0)


def test_groups_are_leaves_split_by_energy():
    """Lights of one group (e.g. the triangles of one emissive object) form one leaf: a point
    picks the group by importance, then a light of it by energy alone; pdf and sampling agree."""
    rng = np.random.default_rng(21)
    m = 30
    c = rng.uniform(-5, 5, (3, m))
    E = rng.uniform(0.5, 4.0, m)
    group = rng.integers(0, 6, m)
    f32 = lambda a: np.asarray(a, F32)
    tree = lamps.light_tree(f32(c - 0.1), f32(c + 0.1), np.tile([[0.0], [0.0], [1.0]], (1, m)), np.full(m, EVERY),
                            np.zeros(m), E, np.arange(m), group)
    assert tree.members == m and tree.nodes == 2 * len(np.unique(group)) - 1
    P = np.array([[1.0], [-2.0], [0.5]], F32)
    pdf = tree.pdf(np.repeat(P, m, 1), np.arange(m))
    assert pdf.sum() == pytest.approx(1.0, abs=1e-12)
    for g in np.unique(group):          # within a group: proportional to energy
        at = group == g
        np.testing.assert_allclose(pdf[at] / pdf[at].sum(), E[at] / E[at].sum(), rtol=1e-12)
    n = 400_000
    got, prob = tree.sample(np.repeat(P, n, 1), rng.random(n))
    np.testing.assert_allclose(prob, pdf[got], rtol=1e-12)
    freq = np.bincount(got, minlength=m) / n
    assert np.all(np.abs(freq - pdf) <= 5 * np.sqrt(pdf * (1 - pdf) / n) + 1e-9)
    with pytest.raises(ValueError, match='light 3: group must be >= 0'):
        lamps.light_tree(f32(c - 0.1), f32(c + 0.1), np.tile([[0.0], [0.0], [1.0]], (1, m)), np.full(m, EVERY),
                         np.zeros(m), E, np.arange(m), np.where(np.arange(m) == 3, -1, group))


def test_lights_below_the_receivers_horizon_are_not_picked():
    """With the receiving point's normal, a node wholly below its horizon gets probability 0 (a
    diffuse surface gets nothing from there); lights below share only what reaches a node that
    straddles the horizon with both children below it (split by energy there). Sampling and
    pdf agree with the normal as without."""
    rng = np.random.default_rng(2)
    m = 24
    c = rng.uniform(-4, 4, (3, m))
    c[2] = np.where(np.arange(m) % 2, 2.0, -2.0)        # half above the point, half below
    tree = tree_of(c, 0.05, rng.uniform(1.0, 5.0, m))
    P = np.zeros((3, 1), F32)
    N = np.array([[0.0], [0.0], [1.0]], F32)
    pdf = tree.pdf(np.repeat(P, m, 1), np.arange(m), N=np.repeat(N, m, 1))
    assert pdf.sum() == pytest.approx(1.0, abs=1e-12)
    assert np.all(pdf[1::2] > 0) and pdf[::2].sum() < 0.05
    flat = tree.pdf(np.repeat(P, m, 1), np.arange(m))
    assert flat[::2].sum() > 0.3                         # without the normal: by distance alone
    n = 300_000
    got, prob = tree.sample(np.repeat(P, n, 1), rng.random(n), N=np.repeat(N, n, 1))
    np.testing.assert_allclose(prob, pdf[got], rtol=1e-12)
    # a light straddling the horizon (its sphere crosses the tangent plane) keeps a share
    straddle = tree_of([[3.0, -3.0], [0.0, 0.0], [-0.1, 1.0]], 0.3, [1.0, 1.0])
    p = straddle.pdf(np.repeat(P, 2, 1), np.array([0, 1]), N=np.repeat(N, 2, 1))
    assert p[0] > 0 and p.sum() == pytest.approx(1.0)


@pytest.mark.parametrize("m", [1, 2, 3, 7, 8, 9, 64, 121, 1000])
def test_group_member_pick_is_the_cdf_upper_bound(m):
    """Within a group leaf a walk takes the first member whose cumulative energy share exceeds
    t = (u - lo) / w (std::upper_bound; the last one where rounding leaves t past them all),
    found by a branch-free search (lighttree.cpp upper_slot): at u exactly on every share's
    bound, one ULP either side, 0, NaN, negative and just below 1, with repeated energies (runs
    of equal bounds) and faint ones, one group at the root (lo = 0, w = 1: t = u), walked
    singly and stop by stop."""
    rng = np.random.default_rng(m)
    E = rng.uniform(0.5, 4.0, m)
    E[rng.random(m) < 0.3] = 2.0                    # runs of equal shares
    E[rng.random(m) < 0.1] = 1e-30                  # shares too small to move the bound
    total = 0.0
    for e in E:                                     # the tree's own sums, in member order
        total += e
    cdf = np.cumsum(E) / total
    cdf[-1] = 1.0
    f32 = lambda a: np.asarray(a, F32)
    c = rng.uniform(-1, 1, (3, m))
    tree = lamps.light_tree(f32(c - 0.1), f32(c + 0.1), np.tile([[0.0], [0.0], [1.0]], (1, m)), np.full(m, EVERY),
                            np.zeros(m), E, np.arange(m), np.zeros(m, np.int64))
    u = np.concatenate([cdf, np.nextafter(cdf, 0.0), np.nextafter(cdf, 2.0),
                        [0.0, np.nan, -0.5, np.nextafter(1.0, 0.0), 1.0]])
    want = np.minimum(np.searchsorted(cdf, np.where(u >= 0.0, np.minimum(u, 1.0), 0.0), side='right'), m - 1)
    P = np.zeros((3, len(u)), F32)
    for rows in (False, True):
        key, prob = tree.sample(P, u, rows=rows)
        assert key.tolist() == want.tolist()
        share = E[want] / total if m > 1 else np.ones(len(u))
        assert prob.view(np.uint64).tolist() == share.view(np.uint64).tolist()
