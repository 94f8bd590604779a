"""The overlap check's sparse plane groups, all swept in one set of numpy passes
(overlappingfaces._sparse_pairs), give each group the pairs it gets swept alone: the reference
below is the one-group-at-a-time sweep they replaced (bmw27: ~700 such groups a frame, ~0.5 s of
CPU in per-group numpy calls). Groups share vertex indices here, so a piece joined only through
another group's triangles would show; budgets and caps are lowered to be reached. And the
short-axis min / max chains are numpy's reductions, NaN included."""
import numpy as np
import pytest

import dacrt
from addon import overlappingfaces as of


def _one_group(c, t, rows):
    """The pairs (global rows) one group under the area bound gets swept alone (the sweep as
    overlappingfaces._sparse_group wrote it before the batching, with each pair's own margin)."""
    verts, local = np.unique(t[rows], return_inverse=True)
    local = local.reshape(-1, 3).astype(np.int32)
    piece = dacrt.shading.island_roots(len(verts), np.r_[local[:, :2], local[:, 1:]])[local[:, 0]]
    if (piece == piece[0]).all():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    tri = c[rows]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    margin = 2 * of._PAIR_ULPS * np.spacing(np.maximum(np.abs(tri).max(axis=(1, 2)), 1e-30).astype(np.float32))
    margin = margin.astype(np.float64)
    spread = np.argsort(hi.max(axis=0) - lo.min(axis=0))[::-1]
    ax = int(spread[0])
    order = np.argsort(lo[:, ax], kind='stable')
    los = lo[order, ax]
    end = np.searchsorted(los, hi[order, ax] - margin[order], side='left')
    count = np.maximum(end - np.arange(len(order)) - 1, 0)
    if count.sum() > 8 * of._BUDGET:
        count = np.minimum(count, 8 * of._BUDGET // len(order))
    a = np.repeat(np.arange(len(order)), count)
    b = a + 1 + (np.arange(len(a)) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[a], order[b]
    near = np.ones(len(a), bool)
    pair = np.maximum(margin[a], margin[b])
    for k, d in enumerate(spread.tolist()):
        depth = np.minimum(hi[a, d], hi[b, d]) - np.maximum(lo[a, d], lo[b, d])
        near &= depth > pair if k < 2 else depth >= -pair
    near &= piece[a] != piece[b]
    a, b = a[near], b[near]
    if len(a) > of._BUDGET:
        mid = 0.5 * (lo + hi)
        a, b = (x[np.argsort(np.square(mid[a] - mid[b]).sum(axis=1), kind='stable')[:of._BUDGET]] for x in (a, b))
    return rows[a], rows[b]


def _scene(rng, groups, pool):
    """Random triangles in a few planes' worth of boxes, corners drawn from a shared vertex
    pool (so triangles of different groups share vertices), and groups of random sizes (some
    of one piece, some with ties in their boxes' starts)."""
    v = rng.normal(size=(pool, 3)).astype(np.float32)
    v[: pool // 4] = np.round(v[: pool // 4] * 4) / 4          # ties along the sweep axis
    sizes = rng.integers(17, 60, groups)
    t = rng.integers(0, pool, (int(sizes.sum()) + 50, 3)).astype(np.int32)
    # one group of a single piece: a fan around one vertex
    t[50:50 + sizes[0], 0] = 7
    t[50:50 + sizes[0], 1] = np.arange(sizes[0]) % pool
    t[50:50 + sizes[0], 2] = (np.arange(sizes[0]) + 1) % pool
    rows = rng.permutation(len(t))[: int(sizes.sum())].astype(np.int64)
    rows[: sizes[0]] = np.arange(50, 50 + sizes[0])
    starts = np.cumsum(sizes) - sizes
    return v, t, rows, starts, sizes


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("budget", [None, 5])
def test_batched_sweep_gives_each_group_its_own_pairs(seed, budget, monkeypatch):
    if budget is not None:      # (the nearest-first budget and the sliver cap reached)
        monkeypatch.setattr(of, "_BUDGET", budget)
    rng = np.random.default_rng(seed)
    v, t, rows, starts, sizes = _scene(rng, groups=12, pool=400 if seed % 2 else 60)
    c = of._Corners(v, t)
    want = [_one_group(c, t, rows[s:s + n]) for s, n in zip(starts, sizes)]
    wa = np.concatenate([a for a, _ in want])
    wb = np.concatenate([b for _, b in want])
    # groups given out of order, as _found_in_groups passes them (sizes ascending); the same
    # pairs (each tested on its own numbers: _test's marks do not depend on their order)
    perm = rng.permutation(len(starts))
    ga, gb = of._sparse_pairs(c, t, rows, starts[perm], sizes[perm])
    assert len(wa) > 0
    assert sorted(zip(ga.tolist(), gb.tolist())) == sorted(zip(wa.tolist(), wb.tolist()))


def test_a_piece_joined_only_through_another_group_stays_two_pieces():
    """Triangles 0 and 1 (group A) share no corner; each shares one with triangle 2 (group B):
    swept alone, A holds two pieces whose overlapping pair is tested."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.1, 0.1, 0], [1.1, 0.1, 0], [0.1, 1.1, 0],
                  [5, 5, 5]], np.float32)
    t = np.array([[0, 1, 2], [3, 4, 5], [0, 3, 6], [1, 4, 6]], np.int32)
    c = of._Corners(v, t)
    rows = np.array([0, 1, 2, 3], np.int64)
    a, b = of._sparse_pairs(c, t, rows, np.array([0, 2]), np.array([2, 2]))
    assert (a.tolist(), b.tolist()) == ([0], [1])
    wa, wb = _one_group(c, t, rows[:2])
    assert (wa.tolist(), wb.tolist()) == ([0], [1])


@pytest.mark.parametrize("shape, axis", [((50, 3, 3), 1), ((50, 6, 3), 2), ((50, 9), 1)])
def test_short_axis_chains_are_numpys_reductions(shape, axis):
    x = np.random.default_rng(1).normal(size=shape)
    x.flat[::37] = np.nan
    x.flat[5::41] = -0.0
    np.testing.assert_array_equal(of._chain(np.minimum, x, axis), x.min(axis=axis))
    np.testing.assert_array_equal(of._chain(np.maximum, x, axis), x.max(axis=axis))


def _one_size(c, rows, g, s):
    """(total, box) of the groups of size s starting at g, as the area bound computed them one
    size at a time before the batching (overlappingfaces._bound_exceeded then)."""
    tri = c[rows[g[:, None] + np.arange(s)].ravel()].reshape(len(g), s, 3, 3)
    box = np.inf
    for k in range(3):
        f = np.roll(tri[:, 0], -k, axis=1)
        o, u, w, n = of._frame(f)
        rel = tri - o[:, None, None, :]
        p = np.stack([np.einsum('gtkd,gd->gtk', rel, u), np.einsum('gtkd,gd->gtk', rel, w)], axis=-1)
        box = np.minimum(box, np.prod(p.max(axis=(1, 2)) - p.min(axis=(1, 2)), axis=1))
    e1, e2 = p[:, :, 1] - p[:, :, 0], p[:, :, 2] - p[:, :, 0]
    return 0.5 * np.abs(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]).sum(axis=1), box


@pytest.mark.parametrize("seed", range(4))
def test_area_bound_of_all_sizes_at_once_is_each_sizes_own(seed):
    """The same floats, bit for bit, as one size at a time: sizes 17 to 700 (numpy's pairwise
    sums over 8- and 128-element blocks), groups in mixed order, scales from 1e-3 to 1e3."""
    rng = np.random.default_rng(seed)
    sizes = rng.choice([17, 18, 25, 130, 700], 15)
    n = int(sizes.sum())
    v = (rng.normal(size=(3 * n, 3)) * 10.0 ** rng.integers(-3, 4, size=(3 * n, 1))).astype(np.float32)
    t = rng.permutation(3 * n).reshape(n, 3).astype(np.int32)
    c = of._Corners(v, t)
    rows = rng.permutation(n).astype(np.int64)
    starts = np.cumsum(sizes) - sizes
    perm = rng.permutation(len(sizes))
    total, box = of._areas_and_box(c, rows, starts[perm], sizes[perm])
    for k, (g, s) in enumerate(zip(starts[perm], sizes[perm])):
        want_total, want_box = _one_size(c, rows, np.array([g]), int(s))
        assert total[k].tobytes() == want_total[0].tobytes() and box[k].tobytes() == want_box[0].tobytes()
    # and together with the other groups of their size, as _found_in_groups had called it
    for s in np.unique(sizes):
        k = np.flatnonzero(sizes[perm] == s)
        want_total, want_box = _one_size(c, rows, starts[perm][k], int(s))
        np.testing.assert_array_equal(total[k], want_total)
        np.testing.assert_array_equal(box[k], want_box)


def _pairs_overlap_reference(a, b, folds):
    """The pair-by-pair test _test ran before it took each triangle's box once: boxes and
    tolerances from each pair's own gathered corners by numpy's reductions, then the in-plane
    test on the pairs whose boxes come within twice the tolerance."""
    big = np.maximum(np.abs(a).max(axis=(1, 2)), np.abs(b).max(axis=(1, 2)))
    tol = of._PAIR_ULPS * np.spacing(np.maximum(big, 1e-30).astype(np.float32)).astype(np.float64)
    lo_a, hi_a, lo_b, hi_b = a.min(axis=1), a.max(axis=1), b.min(axis=1), b.max(axis=1)
    near = ((lo_b <= hi_a + 2 * tol[:, None]) & (lo_a <= hi_b + 2 * tol[:, None])).all(axis=1)
    out = np.zeros(len(a), bool)
    if near.any():
        out[near] = of._overlap_in_plane(a[near], b[near], tol[near], folds[near])
    return out


@pytest.mark.parametrize("extra", [0, 4000])
def test_pairs_tested_on_each_triangles_box_find_what_pairs_found(extra):
    """_test with each triangle's box taken once marks the triangles the pair-by-pair test
    marks: coplanar triangles in a few planes (overlaps, folds, quads), and with `extra`
    triangles that are in no pair (the path for few pairs among many triangles)."""
    rng = np.random.default_rng(3)
    n = 300
    v = (rng.uniform(-1, 1, (n, 1, 3)) + rng.uniform(-0.15, 0.15, (n, 3, 3))).astype(np.float32)
    v[..., 2] = rng.integers(0, 3, (n, 1)) * 0.5              # three planes z = 0, 0.5, 1
    v = v.reshape(-1, 3)
    t = np.arange(3 * n, dtype=np.int32).reshape(n, 3)
    # faces folded back over an edge they share by index (opposite winding, the third corner
    # inside the first face): found; and neighbours across a shared edge (quads): left
    inner = (v[t[:20]].mean(axis=1) + v[t[:20, 2]]) / 2
    mirror = v[t[20:40, 0]] + v[t[20:40, 1]] - v[t[20:40, 2]]
    v = np.concatenate([v, inner, mirror]).astype(np.float32)
    k = np.arange(20)
    t = np.concatenate([t, np.c_[t[k, 1], t[k, 0], 3 * n + k], np.c_[t[20 + k, 1], t[20 + k, 0], 3 * n + 20 + k]])
    m = len(t)
    v = np.concatenate([v, rng.uniform(5, 6, (3 * extra, 3)).astype(np.float32)])
    t = np.concatenate([t, len(v) - 3 * extra + np.arange(3 * extra, dtype=np.int32).reshape(extra, 3)]).astype(np.int32)
    geo, _ = dacrt.shading.triangle_table(v, t, 4.0, 1e-30)
    c = of._Corners(v, t)
    i, j = np.triu_indices(m, 1)
    got = np.zeros(len(t), bool)
    of._test(c, t, geo, i, j, got)
    ok = ~of._quads(t, np.asarray(geo[9:12]), i, j)
    i, j = i[ok], j[ok]
    hit = _pairs_overlap_reference(c[i], c[j], of._folds(t, i, j))
    want = np.zeros(len(t), bool)
    want[i[hit]] = want[j[hit]] = True
    assert 10 < want.sum() < m - 10 and want[300:320].all()
    np.testing.assert_array_equal(got, want)
