"""Rays lying, within rounding, in the plane of a triangle. The triangle's projection along such
a ray is a sliver that rounding can move over the ray, and t from the plane can then lie far
from the triangle. Whether the ray reached that triangle's leaf used to depend on the node
boxes the filter tested it against, so the hit changed with the ISA, thread count, leaf size,
partition mode and kept top. Checked here: bit-identical results in every configuration, every
hit on the segment the box filter keeps (the leaf's rule, verified in float64), and agreement
with the float64 reference."""

import itertools

import dacrt
import numpy as np
import pytest

from . import agreement, harness, reference

ISAS = dacrt.supported_isas()
HIT_BOX_TOL = 2.0 ** -20  # leaf.h kHitBoxTol; the filter pads node boxes by twice that


def axis_soup(rng, m):
    """m triangles with integer vertices in [-3, 3]^3: many shared planes, edges and vertices."""
    v = rng.integers(-3, 4, (3 * m, 3)).astype(np.float32)
    return v, np.arange(3 * m).reshape(m, 3)


def inplane_rays(rng, v, n):
    """Rays starting in the plane of a random triangle, outside it, and running inside that
    plane towards it (in float64; rounding to float32 tilts them slightly out of it)."""
    k = rng.integers(0, len(v) // 3, n)
    a, b, c = (v[3 * k + i].astype(np.float64) for i in range(3))
    w = rng.dirichlet([1, 1, 1], n)
    o = a * w[:, :1] + b * w[:, 1:2] + c * w[:, 2:] + (b - a) * rng.uniform(-2, -1, (n, 1))
    d = (b - a) * rng.uniform(0.5, 1, (n, 1)) + (c - a) * rng.uniform(0, 0.5, (n, 1))
    o, d = o.astype(np.float32), d.astype(np.float32)
    d[~np.any(d != 0, axis=1), 0] = 1  # a degenerate triangle's edge
    return o, d


def _case(seed, n_inplane=5000, n_random=1000):
    rng = np.random.default_rng(seed)
    v, t = axis_soup(rng, 600)
    o, d = inplane_rays(rng, v, n_inplane)
    o2 = rng.uniform(-4, 4, (n_random, 3)).astype(np.float32)
    d2 = rng.normal(size=(n_random, 3)).astype(np.float32)
    org, dirs = np.concatenate([o, o2]), np.concatenate([d, d2])
    tfar = np.where(rng.uniform(size=len(org)) < 0.3, rng.uniform(0.5, 3, len(org)),
                    np.inf).astype(np.float32)
    return v, t, org, dirs, tfar


def _trace(monkeypatch, v, t, org, dirs, tfar, isa, threads, warm=None, **kw):
    monkeypatch.setenv("DACRT_ISA", isa)
    scene = dacrt.Scene(v, t, **kw)
    if warm is not None:  # an earlier batch of the frame sets the kept top
        scene.intersect(dacrt.make_rays(org[:warm], dirs[:warm]), threads=threads)
    return (harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads),
            harness.occluded(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads + 5))


def _configs():
    for isa, threads, (ls, lr), mode in itertools.product(ISAS, [1, 2], [(16, 32), (1, 1)],
                                                          ["adaptive", "median"]):
        yield f"{isa} {threads}t leaf {ls}/{lr} {mode}", isa, threads, None, \
            dict(leaf_size=ls, leaf_rays=lr, partition=mode)
    for isa in ISAS:
        yield f"{isa} kept top", isa, 2, 700, dict(keep_top=True)
        yield f"{isa} spatial order, chunks of 500", isa, 2, None, dict(spatial_order=True, chunk_rays=500)
        yield f"{isa} sah", isa, 1, None, dict(partition="sah")


@pytest.mark.parametrize("seed", [0, 1])
def test_identical_in_every_configuration(monkeypatch, seed):
    case = _case(seed)
    base = None
    for what, isa, threads, warm, kw in _configs():
        hits, occ = _trace(monkeypatch, *case, isa, threads, warm, **kw)
        if base is None:
            base = (hits, occ, what)
            assert (hits["prim"][:5000] >= 0).sum() > 1000  # many in-plane rays hit something
            continue
        diff = np.flatnonzero(np.any(hits.view(np.uint32).reshape(-1, 4) !=
                                     base[0].view(np.uint32).reshape(-1, 4), axis=1))
        assert len(diff) == 0, (f"seed {seed}: {what} differs from {base[2]} on {len(diff)} rays, "
                                f"e.g. id {diff[0]}: {hits[diff[0]]} vs {base[0][diff[0]]}")
        assert np.array_equal(occ, base[1]), f"seed {seed}: occluded of {what} differs from {base[2]}"


def segment_meets_padded_box(v, t, org, dirs, hits, slack=2.0 ** -20):
    """Per hit ray: whether o + s d for some s in [0, t] lies in the hit triangle's box padded
    by HIT_BOX_TOL (largest |box coordinate| + largest |origin coordinate|), in float64 (t
    may sit one float rounding short of the padded box: `slack`, relative)."""
    sel = np.flatnonzero(hits["prim"] >= 0)
    tri = v[t[hits["prim"][sel]]].astype(np.float64)
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    o = org[sel].astype(np.float64)
    d = dirs[sel].astype(np.float64)
    tol = HIT_BOX_TOL * (np.maximum(np.abs(lo), np.abs(hi)).max(axis=1) + np.abs(o).max(axis=1))
    lo, hi = lo - tol[:, None] - o, hi + tol[:, None] - o
    with np.errstate(divide="ignore", invalid="ignore"):
        e0, e1 = lo / d, hi / d
    inside = (lo <= 0) & (hi >= 0)  # for d = 0: the whole line or nothing
    s_in = np.where(d == 0, np.where(inside, -np.inf, np.inf), np.minimum(e0, e1)).max(axis=1)
    s_out = np.where(d == 0, np.where(inside, np.inf, -np.inf), np.maximum(e0, e1)).min(axis=1)
    th = hits["t"][sel].astype(np.float64) * (1 + slack)
    return sel, np.maximum(s_in, 0.0) <= np.minimum(s_out, th)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hits_lie_on_the_filtered_segment_and_agree_with_the_reference(seed):
    v, t, org, dirs, tfar = _case(seed)
    scene = dacrt.Scene(v, t)
    hits = harness.intersect(scene, org, dirs, tfar, threads=1)
    sel, ok = segment_meets_padded_box(v, t, org, dirs, hits)
    bad = sel[~ok]
    assert len(bad) == 0, (f"seed {seed}: {len(bad)} hits lie off the segment [0, t] the filter "
                           f"keeps, e.g. ray {bad[0]}: org={org[bad[0]].tolist()} "
                           f"dir={dirs[bad[0]].tolist()} hit={hits[bad[0]]}")
    ref = reference.trace(v, t, org, dirs, tfar)
    agreement.check_hits(v, t, org, dirs, tfar, hits, ref, context=f"in-plane seed {seed}")
    agreement.check_occluded(org, dirs, tfar, harness.occluded(scene, org, dirs, tfar, threads=1),
                             ref, context=f"in-plane seed {seed}")


def test_a_ray_in_a_triangles_plane_misses_it_in_every_configuration():
    """Ray 0 lies in triangle B's plane (sine of the angle 2e-8) and passes B; exactly, it meets
    B's plane at t = 1.32414 outside B and its box, and hits A at t = 1.85592 (u 0.0882, v
    0.1997). It used to report B (t 1.324, u and v of a point 4 units from o + t d) whenever
    its leaf held both triangles. The other 63 rays, aimed at A, make the node big enough to
    split."""
    v = np.array([[3, -2, -3], [0, -1, -1], [3, -2, 1], [2, -2, -1], [-1, -2, 3], [-1, 0, 2]],
                 np.float32)
    t = np.array([[0, 1, 2], [3, 4, 5]], np.int32)
    o0 = [5.623873233795166, -1.963364839553833, -5.850148677825928]
    d0 = [-1.5562994480133057, 0.027765613049268723, 2.061183214187622]
    rng = np.random.default_rng(0)
    o = np.vstack([o0, np.tile(o0, (63, 1))]).astype(np.float32)
    d = np.vstack([d0, np.array([2, -1.5, -1]) - o0 + rng.normal(scale=0.05, size=(63, 3))]
                  ).astype(np.float32)
    for ls in (16, 1):
        for mode in ("adaptive", "median"):
            h = dacrt.Scene(v, t, leaf_size=ls, leaf_rays=ls, partition=mode).intersect(
                dacrt.make_rays(o, d))[0]
            assert h["prim"] == 0 and abs(h["t"] - 1.85592) < 1e-5, (ls, mode, h)
            assert abs(h["u"] - 0.0882) < 1e-3 and abs(h["v"] - 0.1997) < 1e-3, (ls, mode, h)
