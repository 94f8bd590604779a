"""Hit points from the per-triangle records (shading.hit_records, native hitrecords.h) are the
rows' hit points bit for bit: P, ng, ns, P_off and the survivors' throughputs and triangles, on
random hits and on the cases the arithmetic branches on (points on and within the edge margin
of edges and corners, degenerate, needle and huge triangles, t NaN / inf / 0, grazing and
opposite directions, flat and smooth normals, opposite corner normals), through surface(),
continue_paths' surface and shade_bounce; records that do not fit the call are refused."""
from __future__ import annotations

import dacrt
import numpy as np
import pytest
from dacrt import shading

F32 = np.float32


def _triangles(rng, m):
    """(m, 3, 3) corners: random triangles at scales 1e-3..1e4 and offsets up to 1e4, with
    degenerate (a repeated corner, collinear), needle and float-overflowing ones among them."""
    v = rng.normal(size=(m, 3, 3)) * 10.0 ** rng.integers(-3, 5, (m, 1, 1))
    v += rng.normal(size=(m, 1, 3)) * 10.0 ** rng.integers(-1, 5, (m, 1, 1))
    k = m // 12
    v[0:k, 2] = v[0:k, 1]                                              # a repeated corner
    v[k:2 * k, 2] = v[k:2 * k, 0] + 2.5 * (v[k:2 * k, 1] - v[k:2 * k, 0])   # collinear
    v[2 * k:3 * k, 2] = v[2 * k:3 * k, 1] + 1e-6 * rng.normal(size=(k, 3))  # needles
    v[3 * k:4 * k] *= 1e35 / np.abs(v[3 * k:4 * k]).max(axis=(1, 2), keepdims=True)  # area2 overflows
    v[4 * k:5 * k] = np.round(v[4 * k:5 * k])                          # axis-aligned-ish, exact corners
    return v.astype(F32)


def _normals(rng, m, opposite):
    """(9, m) corner-normal rows: random unit corners, or with opposite, corner 2 = -corner 0
    (the interpolated normal is zero where they cancel) for a third of the triangles."""
    c = rng.normal(size=(m, 3, 3))
    c /= np.linalg.norm(c, axis=2, keepdims=True)
    if opposite:
        c[: m // 3, 2] = -c[: m // 3, 0]
        c[: m // 3, 1] = c[: m // 3, 0]
    return shading.corner_rows(c.astype(F32))


def _hits(rng, geo, n):
    """n hits on the triangles of geo: u, v anywhere, on edges and corners, within a few edge
    margins of an edge; t random, 0, NaN, +-inf; directions random and in the triangle's plane."""
    M = geo.shape[1]
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    p = rng.integers(0, M, n)
    hits["prim"] = p
    su = np.sqrt(rng.random(n))
    u, v = rng.random(n) * su, 1.0 - su
    kind = rng.integers(0, 8, n)
    u = np.where(kind == 1, 0.0, u)                                     # on edge v0 v2
    v = np.where(kind == 2, 0.0, v)                                     # on edge v0 v1
    v = np.where(kind == 3, 1.0 - u, v)                                 # on edge v1 v2
    corner = rng.integers(0, 3, n)
    u = np.where(kind == 4, corner == 1, u)                             # corners
    v = np.where(kind == 4, corner == 2, v)
    tiny = 10.0 ** rng.uniform(-9, -5, n)                               # near an edge
    u = np.where(kind == 5, tiny, u)
    v = np.where(kind == 6, 1.0 - u - tiny, v)
    u = np.where(kind == 7, -tiny, u)                                   # just outside (float error)
    hits["u"], hits["v"] = u.astype(F32), v.astype(F32)
    t = 10.0 ** rng.uniform(-8, 4, n)
    special = rng.integers(0, 10, n)
    t = np.where(special == 0, np.nan, np.where(special == 1, np.inf, np.where(special == 2, 0.0, t)))
    t = np.where(special == 3, -np.inf, t)
    hits["t"] = t.astype(F32)
    D = rng.normal(size=(3, n))
    D /= np.linalg.norm(D, axis=0)
    ng = geo[9:12, p].astype(np.float64)
    along = D - ng * (ng * D).sum(axis=0)                               # grazing: in the plane
    along /= np.maximum(np.linalg.norm(along, axis=0), 1e-30)
    D = np.where(special == 4, along, D)
    D = np.where(special == 5, -ng, D)
    return hits, np.ascontiguousarray(D, F32)


def _table(rng, m, smooth, opposite=False):
    v = _triangles(rng, m)
    geo, _ = shading.triangle_table(v.reshape(-1, 3), np.arange(3 * m, dtype=np.int32).reshape(m, 3),
                                    F32(8.0), F32(2.0 ** -100))
    return geo, (_normals(rng, m, opposite) if smooth else None)


def _bits(a):
    return np.ascontiguousarray(a, F32).view(np.uint32)


@pytest.mark.parametrize("smooth, opposite", [(False, False), (True, False), (True, True)])
def test_surface_from_records_is_surface_from_rows(smooth, opposite):
    rng = np.random.default_rng(20 + smooth + 2 * opposite)
    geo, normals = _table(rng, 600, smooth, opposite)
    hits, D = _hits(rng, geo, 200_000)
    records = shading.hit_records(geo, normals)
    assert records.shape == (600, 32) and records.dtype == F32
    assert records.ctypes.data % 128 == 0                               # a record is two cache lines
    want = shading.surface(geo, normals, hits, None, D)
    got = shading.surface(geo, normals, hits, None, D, records)
    for w, g in zip(want, got):
        np.testing.assert_array_equal(_bits(g), _bits(w))
    # the cases above happen: points moved off edges, cut steps, full steps, NaN steps
    P = want[0]
    g = geo[:, hits["prim"]]
    plain = g[3:6] * hits["u"]
    plain += g[6:9] * hits["v"]
    plain += g[0:3]
    moved = (P != plain).any(axis=0)
    assert 0.05 < moved.mean() < 0.9
    assert np.isnan(want[3]).any() or np.isinf(want[3]).any() or (hits["t"] == 0).any()
    if opposite:                                                         # zero normals fell back to ng
        assert ((want[2] == want[1]).all(axis=0)).any()


@pytest.mark.parametrize("smooth", [False, True])
def test_survivors_from_records_are_survivors_from_rows(smooth):
    rng = np.random.default_rng(31 + smooth)
    m, n = 300, 100_000
    geo, normals = _table(rng, m, smooth, opposite=smooth)
    hits, D = _hits(rng, geo, n)
    hit = rng.random(n) < 0.9
    live = rng.random(m) < 0.9
    albedo = rng.random((3, m)).astype(F32)
    thr = (rng.random((3, n)) ** 3).astype(F32)
    u_rr = rng.random(n).astype(F32)
    records = shading.hit_records(geo, normals)
    want = shading.continue_paths(hits, hit, live, albedo, thr, u_rr, surface=(geo, normals, D))
    got = shading.continue_paths(hits, hit, live, albedo, thr, u_rr, surface=(geo, normals, D, records))
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(_bits(got[1]), _bits(want[1]))
    assert got[2:4] == want[2:4] and len(want[0]) > n // 2
    for w, g in zip(want[4], got[4]):
        np.testing.assert_array_equal(_bits(g), _bits(w))
    np.testing.assert_array_equal(got[5], want[5])


def test_records_that_do_not_fit_the_call_are_refused():
    rng = np.random.default_rng(5)
    geo, normals = _table(rng, 50, True)
    hits, D = _hits(rng, geo, 100)
    flat = shading.hit_records(geo, None)
    smooth = shading.hit_records(geo, normals)
    with pytest.raises(ValueError, match="without corner normals"):
        shading.surface(geo, normals, hits, None, D, flat)
    with pytest.raises(ValueError, match="with corner normals"):
        shading.surface(geo, None, hits, None, D, smooth)
    with pytest.raises(ValueError, match=r"records must have shape \(50, 32\)"):
        shading.surface(geo, normals, hits, None, D, smooth[:49])
    with pytest.raises(ValueError, match=r"records must have shape \(50, 32\)"):
        shading.continue_paths(hits, np.ones(100, bool), np.ones(50, bool), np.ones((3, 50), F32),
                               surface=(geo, normals, D, smooth[:, :31]))
    assert shading.hit_records(geo[:, :0], None).shape == (0, 32)
