"""Hit points on an edge are reconstructed inside their triangle, off the neighbour's plane.

Rays from inside a closed box aimed at points of its 12 edges hit one of the two walls meeting
there with barycentrics on the edge; P = v0 + e1 u + e2 v then rounded up to an ULP past the
other wall's plane (2.3% of these hits), and the step off the surface along the hit wall's
normal, parallel to that other wall, left it there: the path vertex lay outside the room.
shading.surface now keeps P at least 8 ULPs of the triangle's largest coordinate (the whole
self-intersection step, pathvertex.h edge_margin) from every edge of its triangle; points farther in are unchanged bit for bit.
"""
from __future__ import annotations

import dacrt
import numpy as np
import pytest
from dacrt import shading

F32 = np.float32


def _room(scale, offset):
    lo, hi = np.array([-3.0, -3.0, -0.001]) * scale + offset, np.array([3.0, 3.0, 3.0]) * scale + offset
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
                  (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)])
    quads = [(1, 2, 3, 0), (7, 6, 5, 4), (4, 5, 1, 0), (5, 6, 2, 1), (6, 7, 3, 2), (7, 4, 0, 3)]   # inward
    t = [tri for q in quads for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
    return v.astype(F32), np.array(t, np.int32)


def _edge_hits(scale, offset, n=200_000, seed=0):
    v, t = _room(scale, offset)
    geo, _ = shading.triangle_table(v, t, F32(8.0), F32(2.0 ** -100))
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    rng = np.random.default_rng(seed)
    O = lo + (hi - lo) * rng.uniform(0.05, 0.95, (n, 3))
    axis, s = rng.integers(0, 3, n), rng.random(n)
    target = np.where(rng.random((n, 3)) < 0.5, lo, hi)           # a point on one of the 12 edges
    target[np.arange(n), axis] = lo[axis] + (hi - lo)[axis] * s
    D = target - O
    D = np.ascontiguousarray((D / np.linalg.norm(D, axis=1, keepdims=True)).T, F32)
    O = np.ascontiguousarray(O.T, F32)
    hits = dacrt.Scene(v, t).intersect(shading.pack_rays(O, D, np.inf))
    assert (hits["prim"] >= 0).all()
    return v, geo, hits, D


@pytest.mark.parametrize("scale, offset", [(1.0, 0.0), (1e-3, 0.0), (1e3, 0.0), (1e4, 0.0), (1.0, 1e4)])
def test_edge_hits_stay_inside_the_room(scale, offset):
    v, geo, hits, D = _edge_hits(scale, offset)
    lo, hi = v.min(0), v.max(0)
    P, _, _, P_off = shading.surface(geo, None, hits, None, D)
    for name, X in (("P", P), ("P_off", P_off)):
        out = ((X.T < lo) | (X.T > hi)).any(axis=1)
        assert not out.any(), f"{out.sum()} of {len(out)} {name} outside the room"
    # ... and no farther from the ray's own hit than the promised 2 margins (+ rounding): the
    # margin is 8 ULPs of the triangle's largest coordinate (pathvertex.h edge_margin)
    g = geo.astype(np.float64)[:, hits["prim"]]
    exact = g[0:3] + g[3:6] * hits["u"] + g[6:9] * hits["v"]
    t = _room(scale, offset)[1][hits["prim"]]
    step = 8.0 * np.spacing(np.abs(v[t]).max(axis=(1, 2))).astype(np.float64)
    assert (np.linalg.norm(P - exact, axis=0) <= 2.0 * step * (1 + 1e-3) + 4 * np.spacing(np.abs(g[0:3]).max(0).astype(F32))).all()


def test_points_off_the_edges_are_unchanged():
    """Interior hit points reconstruct as v0 + e1 u + e2 v in float32, bit for bit."""
    v, t = _room(1.0, 0.0)
    geo, _ = shading.triangle_table(v, t, F32(8.0), F32(2.0 ** -100))
    rng = np.random.default_rng(3)
    n = 50_000
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(0, len(t), n)
    su = np.sqrt(rng.uniform(0.01, 0.99, n))
    hits["u"], hits["v"] = (rng.uniform(0.01, 0.99, n) * su).astype(F32), (1 - su).astype(F32)
    hits["t"] = 1.0
    D = -geo[9:12, hits["prim"]].copy()
    P, _, _, _ = shading.surface(geo, None, hits, None, np.ascontiguousarray(D))
    g = geo[:, hits["prim"]]
    want = g[3:6] * hits["u"]
    want += g[6:9] * hits["v"]
    want += g[0:3]
    np.testing.assert_array_equal(P, want)
