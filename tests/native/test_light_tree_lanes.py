"""The light tree's lane kernel (native/cpp/treelanes.cpp): a walk weighs a stop's eight lanes
side by side in float, one copy per instruction set. Properties: every copy gives the same bits
(DACRT_ISA picks one in a new process), the float lanes agree with the float64 weigh() to
float's precision and cull exactly what it culls, and the walk's probabilities stay a
distribution whose samples report their own pdf, also at the edges: one light, 100K lights,
every light behind the point, lights too faint to weigh in float."""

import numpy as np

import pytest
from dacrt import lamps

from tests.native.isaruns import outputs_per_isa

F32 = np.float32
EVERY = -1.0      # cos_o of a light that emits in every direction


def lights(rng, m, one_sided=0.5, scale=1.0):
    """m random lights: (lo, hi, axis, cos_o, cos_e, energy); area-like (a cone within a
    hemisphere) or point-like (every direction: half of them alike every way, cos_e -1, whose
    smallest importance counts), some very faint."""
    c = rng.uniform(-5, 5, (3, m)) * scale
    h = rng.uniform(0.0, 0.3, (3, m)) * scale
    axis = rng.normal(size=(3, m))
    axis /= np.linalg.norm(axis, axis=0)
    cos_o = np.where(rng.random(m) < one_sided, rng.uniform(0.0, 1.0, m), EVERY)
    energy = rng.uniform(0.1, 10.0, m)
    energy[rng.random(m) < 0.1] = 1e-30
    cos_e = rng.uniform(0.0, 1.0, m)
    cos_e[(cos_o == EVERY) & (np.arange(m) % 2 == 0)] = -1.0    # (drawing nothing more from rng)
    return (c - h).astype(F32), (c + h).astype(F32), axis, cos_o, cos_e, energy


def tree_of(lo, hi, axis, cos_o, cos_e, energy):
    return lamps.light_tree(lo, hi, axis, cos_o, cos_e, energy, np.arange(lo.shape[1]))


def unit(rng, n):
    N = rng.normal(size=(3, n))
    return (N / np.linalg.norm(N, axis=0)).astype(F32)


_ISA_RUN = r"""
import sys
import numpy as np
from tests.native.test_light_tree_lanes import walks
np.save(sys.argv[1], walks())
"""


def walks():
    """Keys, probabilities and pdfs of random walks in trees of 1, 14, 300 and 3000 lights, at
    scales in and out of float's range, with and without normals, as one float64 array."""
    rng = np.random.default_rng(7)
    out = []
    for m, scale in ((1, 1.0), (14, 1.0), (300, 1.0), (3000, 1.0), (200, 1e17), (200, 1e-17)):
        tree = tree_of(*lights(rng, m, scale=scale))
        n = 4000
        P = (rng.uniform(-7, 7, (3, n)) * scale).astype(F32)
        N = unit(rng, n)
        u = rng.random(n)
        for normals in (N, None):
            key, prob = tree.sample(P, u, normals)
            rkey, rprob = tree.sample(P, u, normals, rows=True)
            out += [key.astype(np.float64), prob, tree.pdf(P, rng.integers(0, m, n), normals),
                    rkey.astype(np.float64), rprob]
    return np.concatenate(out)


def test_every_instruction_set_gives_the_same_bits():
    out = outputs_per_isa(_ISA_RUN)
    first = out['portable']
    assert first.size > 0 and np.isfinite(first).all()
    for isa, v in out.items():
        assert v.tobytes() == first.tobytes(), isa


def _walk_cases(rng, linked):
    """(tree, P, u, N, receivers) of trees of 1 to 3000 lights whose walks end at different
    depths, at scales whose distances leave float's range (a four redone in float64 at some
    points and not others, also a four with an empty lane that repeats lane 0's bounds), with
    and without normals, with NaN and negative uniforms, point counts that leave last chunks
    of 1-3 (and rows past 512 points) and, with light linking, receiver masks."""
    for m, scale in ((1, 1.0), (2, 1.0), (3, 1.0), (14, 1.0), (300, 1.0), (3000, 1.0), (200, 1e17), (200, 1e-17),
                     (60, 1e15), (5, 1e15)):
        lo, hi, axis, cos_o, cos_e, energy = lights(rng, m, scale=scale)
        sets = rng.integers(0, 4, m).astype(np.uint8) if linked else None
        tree = lamps.light_tree(lo, hi, axis, cos_o, cos_e, energy, np.arange(m), set=sets)
        for n in (4001, 4002, 4003, 4004, 1, 513):
            P = (rng.uniform(-7, 7, (3, n)) * scale).astype(F32)
            if scale == 1e15:      # some points near (in range), some far (redone)
                P[:, rng.random(n) < 0.5] *= F32(1e-15)
            u = rng.random(n)
            u[rng.integers(0, n, 20)] = np.nan
            u[rng.integers(0, n, 20)] = -0.5
            recv = rng.integers(1, 16, n).astype(np.uint64) if linked else None
            for N in (unit(rng, n), None):
                yield m, tree, P, u, N, recv


@pytest.mark.parametrize("linked", [False, True])
def test_walks_stop_by_stop_pick_as_one_walk(linked):
    """Light sampling walks a chunk's points stop by stop, the points at a stop weighed side by
    side one lane at a time, the empty lanes skipped (LightTree::sample_rows): each point gets
    bit for bit the key and probability of its own walk (sample), in every case of
    _walk_cases."""
    far = 0
    for m, tree, P, u, N, recv in _walk_cases(np.random.default_rng(31), linked):
        key, prob = tree.sample(P, u, N, receivers=recv)
        rkey, rprob = tree.sample(P, u, N, rows=True, receivers=recv)
        assert np.array_equal(rkey, key)
        assert rprob.view(np.uint64).tolist() == prob.view(np.uint64).tolist()
        far += m > 1 and np.abs(P).max() > 1e15
    assert far > 0


@pytest.mark.parametrize("with_normal", [True, False])
def test_lanes_weigh_as_float64(with_normal):
    """Each lane as the float64 weigh(): never 0 where float64 is not (the culling tests keep a
    margin of float's rounding the other way), within float's precision where both are > 0
    (near a cut, where a cosine is tiny, relative to its stop's largest), and some lanes culled
    by both."""
    rng = np.random.default_rng(17)
    tree = tree_of(*lights(rng, 400))
    kept = culled = 0
    for P, N in zip(rng.uniform(-7, 7, (300, 3)).astype(F32), unit(rng, 300).T):
        lanes, exact = tree.stop_weighs(P, N if with_normal else None)
        assert lanes.shape == exact.shape and lanes.shape[1] == 8
        assert np.all(lanes >= 0) and np.isfinite(lanes).all()
        assert np.all(exact[lanes == 0] == 0)
        big = np.maximum(exact.max(axis=1, keepdims=True), 1e-300)
        np.testing.assert_allclose(lanes / big, exact / big, rtol=1e-4, atol=1e-4)
        kept += (lanes > 0).sum()
        culled += (exact == 0).sum()
    assert kept > 0 and culled > 0


@pytest.mark.parametrize("with_normal", [True, False])
def test_lanes_smallest_weigh_as_float64(with_normal):
    """Each lane's smallest importance (Cycles' min_importance) as the float64 weigh()'s: 0
    wherever the largest is, never above it (beyond float's rounding), within float's
    precision of float64's relative to its stop's largest, except at the few points where
    theta + theta_u + theta_s rounds to the other side of a cone's theta_b; > 0 and 0 both
    seen."""
    rng = np.random.default_rng(19)
    tree = tree_of(*lights(rng, 400))
    some = none = off = total = 0
    for P, N in zip(rng.uniform(-7, 7, (300, 3)).astype(F32), unit(rng, 300).T):
        nv = N if with_normal else None
        lanes, exact = tree.stop_weighs(P, nv)
        lmin, emin = tree.stop_weighs(P, nv, smallest=True)
        assert np.all(lmin >= 0) and np.isfinite(lmin).all()
        assert np.all(lmin[lanes == 0] == 0) and np.all(emin[exact == 0] == 0)
        big = np.maximum(exact.max(axis=1, keepdims=True), 1e-300)
        assert np.all(lmin / big <= lanes / big + 1e-4) and np.all(emin <= exact * (1 + 1e-12))
        near = np.isclose(lmin / big, emin / big, rtol=1e-4, atol=1e-4)
        off += (~near).sum()
        total += near.size
        some += (emin > 0).sum()
        none += ((emin == 0) & (exact > 0)).sum()
    assert some > 0 and none > 0
    assert off <= 1e-3 * total


def _is_distribution(tree, m, P, N, rng, n=4000):
    """At each point of P (3, k): the pdf over all m keys sums to 1, and sample() reports the
    pdf of what it picks."""
    for i in range(P.shape[1]):
        Q = np.repeat(P[:, i:i + 1], m, 1)
        Nm = None if N is None else np.repeat(N[:, i:i + 1], m, 1)
        pdf = tree.pdf(Q, np.arange(m), Nm)
        assert np.all(pdf >= 0)
        assert pdf.sum() == pytest.approx(1.0, abs=1e-9)
        Qn = np.repeat(P[:, i:i + 1], n, 1)
        Nn = None if N is None else np.repeat(N[:, i:i + 1], n, 1)
        key, prob = tree.sample(Qn, rng.random(n), Nn)
        np.testing.assert_allclose(prob, pdf[key], rtol=1e-12)
        assert np.all(pdf[key] > 0)


def test_one_light():
    rng = np.random.default_rng(1)
    tree = tree_of(*lights(rng, 1))
    P = rng.uniform(-7, 7, (3, 50)).astype(F32)
    key, prob = tree.sample(P, rng.random(50), unit(rng, 50))
    assert key.tolist() == [0] * 50 and prob.tolist() == [1.0] * 50
    assert tree.pdf(P, np.zeros(50, np.int64), unit(rng, 50)).tolist() == [1.0] * 50


def test_100k_lights():
    rng = np.random.default_rng(2)
    m = 100_000
    tree = tree_of(*lights(rng, m))
    P = rng.uniform(-7, 7, (3, 3)).astype(F32)
    _is_distribution(tree, m, P, unit(rng, 3), rng, n=20_000)
    _is_distribution(tree, m, P, None, rng, n=20_000)


def test_every_light_behind_the_point():
    """One-sided lights on the plane z = 0 all facing down, points above them: every lane weighs
    0, and the walk splits by energy (still a distribution, no light impossible)."""
    rng = np.random.default_rng(3)
    m = 64
    c = np.stack([rng.uniform(-5, 5, m), rng.uniform(-5, 5, m), np.zeros(m)]).astype(F32)
    h = np.array([[0.1], [0.1], [0.0]], F32)
    axis = np.tile([[0.0], [0.0], [-1.0]], (1, m))
    energy = rng.uniform(0.1, 10.0, m)
    tree = tree_of(c - h, c + h, axis, np.ones(m), np.zeros(m), energy)
    P = np.stack([rng.uniform(-5, 5, 20), rng.uniform(-5, 5, 20), rng.uniform(0.5, 3, 20)]).astype(F32)
    for i in range(P.shape[1]):
        lanes, exact = tree.stop_weighs(P[:, i])
        assert np.all(lanes == 0) and np.all(exact == 0)
    _is_distribution(tree, m, P, unit(rng, 20), rng)
    pdf = tree.pdf(np.repeat(P[:, :1], m, 1), np.arange(m))
    np.testing.assert_allclose(pdf, energy / energy.sum(), rtol=1e-12)


def test_faint_lights():
    """Lights of 1e-30 and 1e-200 W among bright ones are picked with a probability > 0 (never
    rounded away), and one of no power at all is refused, naming it."""
    rng = np.random.default_rng(4)
    lo, hi, axis, cos_o, cos_e, energy = lights(rng, 40, one_sided=0.0)
    energy[::3] = 1e-200
    tree = tree_of(lo, hi, axis, cos_o, cos_e, energy)
    P = rng.uniform(-7, 7, (3, 10)).astype(F32)
    _is_distribution(tree, 40, P, None, rng)
    for i in range(10):
        assert np.all(tree.pdf(np.repeat(P[:, i:i + 1], 40, 1), np.arange(40)) > 0)
    energy[5] = 0.0
    with pytest.raises(ValueError, match="light 5: energy"):
        tree_of(lo, hi, axis, cos_o, cos_e, energy)
