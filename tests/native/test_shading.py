"""The shading-side helper kernels (dacrt.shading) against float64 numpy references: ray
packing, hit-point reconstruction, random numbers, cosine-weighted directions, next-event
weights, shadow rays and accumulation; and their argument checks (emissive triangles as lights:
test_triangle_light.py)."""

import os
import tempfile
import warnings

import dacrt
import numpy as np

import pytest
from dacrt import shading

from tests.native.isaruns import outputs_per_isa

F32 = np.float32


def _geo(rng, m, scale=1.0):
    """A (15, m) table of random triangles as the renderer builds it (rows v0, e1, e2, unit
    normal, offset) and their areas."""
    return _table(rng.normal(size=(m, 3, 3)) * scale, scale)


def _table(v, scale=1.0):
    """The (15, m) table and areas of triangles v (m, 3 corners, 3) (float64)."""
    e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    n = np.cross(e1, e2)
    area = 0.5 * np.linalg.norm(n, axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    off = n * 1e-5 * scale
    geo = np.concatenate([v[:, 0].T, e1.T, e2.T, n.T, off.T]).astype(F32)
    return np.ascontiguousarray(geo), area.astype(F32)


def _edge_margin(g):
    """The hit point's margin from its triangle's edges (pathvertex.h edge_margin): 8 ULPs of
    the largest |coordinate| of v0, v0 + e1, v0 + e2 in float32 (g: the table's columns)."""
    g = g.astype(F32)
    top = np.maximum(np.abs(g[0:3]), np.maximum(np.abs(g[0:3] + g[3:6]), np.abs(g[0:3] + g[6:9]))).max(axis=0)
    return 8.0 * np.spacing(np.maximum(top, F32(2.0 ** -100))).astype(np.float64)


def _unit(rng, n):
    d = rng.normal(size=(3, n))
    return (d / np.linalg.norm(d, axis=0)).astype(F32)


def test_pack_rays_fields_and_ids():
    rng = np.random.default_rng(1)
    n = 70_001                                  # more than one thread's share
    O, D = rng.normal(size=(3, n)).astype(F32), _unit(rng, n)
    tfar = rng.uniform(0, 10, n).astype(F32)
    rays = shading.pack_rays(O, D, tfar)
    assert rays.dtype == dacrt.RAY_DTYPE
    np.testing.assert_array_equal(rays["org"], O.T)
    np.testing.assert_array_equal(rays["dir"], D.T)
    np.testing.assert_array_equal(rays["tfar"], tfar)
    np.testing.assert_array_equal(rays["id"], np.arange(n))
    # broadcast length and a reused output buffer
    out = np.empty(n, dacrt.RAY_DTYPE)
    assert shading.pack_rays(O, D, np.inf, out=out) is out
    assert np.isinf(out["tfar"]).all()
    with pytest.raises(ValueError, match="O must have shape"):
        shading.pack_rays(O[:2], D, tfar)
    with pytest.raises(ValueError, match="out must be"):
        shading.pack_rays(O, D, tfar, out=np.empty(n - 1, dacrt.RAY_DTYPE))



# A pinhole camera frame (camera_rays): rotation, position, orthographic base, raster map, tan(fov / 2),
# clip start and range, then an aperture of 0 and the lens parameters it leaves unread.
_FRAME = [1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, -2, 3, 0, 0, 0, -1, 2 / 160, -1, 2 / 120, 0.5, 0.1, 100, 0, 1, 0, 0, 1]


def test_ray_records_are_the_same_on_every_instruction_set():
    """The records are written 8 at a time from the columns (native/cpp/raylanes.cpp: a copy per
    instruction set, DACRT_ISA picks one in a new process) and one at a time for the rest: every
    field moved as it is (NaN payloads, -0 and infinities included), ids the indices, from
    pack_rays (per-ray tfar, split over threads at odd places), camera_rays and the bounce rays of
    cosine_scatter (constant tfar, chunks of the sample words), on lengths around 8's multiples."""
    code = ("import sys, numpy as np, dacrt; from dacrt import shading; "
            "O, D, t, keys, rx, ry = (np.load(f) for f in sys.argv[1:7]); out = []\n"
            "for n in (1, 7, 8, 9, 15, 16, 17, 517, 131079, O.shape[1]):\n"
            "    out.append(shading.pack_rays(np.ascontiguousarray(O[:, :n]), np.ascontiguousarray(D[:, :n]), t[:n]))\n"
            "ns = D / np.linalg.norm(D, axis=0)\n"
            "out.append(shading.cosine_scatter(keys, 5, 6, ns.astype(np.float32), origins=O)[3])\n"
            "cam = shading.camera_rays(False, np.float32(%r), rx, ry, records=True)\n"
            "out.append(cam[3]); out.append(shading.pack_rays(cam[0], cam[1], cam[2]))\n"
            "np.save(sys.argv[7], np.concatenate(out).view(np.uint8))") % (_FRAME,)
    rng = np.random.default_rng(21)
    n = 131_083                                 # past pack_rays' 2^17 split, not a multiple of 8
    O, D = rng.normal(size=(3, n)).astype(F32), _unit(rng, n)
    O[0, 3], O[1, 5], O[2, 11] = np.nan, -0.0, np.inf
    O.view(np.uint32)[1, 9] = 0x7FC01234        # a NaN with a payload: moved, not computed
    tfar = rng.uniform(0, 10, n).astype(F32)
    tfar[[2, 13, 130_000]] = np.inf, 0.0, np.nan
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    rx, ry = rng.uniform(0, 160, n).astype(F32), rng.uniform(0, 120, n).astype(F32)
    out = outputs_per_isa(code, O, D, tfar, keys, rx, ry)
    first = out['portable']
    rays = first.view(dacrt.RAY_DTYPE)
    start = sum((1, 7, 8, 9, 15, 16, 17, 517, 131079))
    packed = rays[start:start + n]
    assert packed.tobytes() == shading.pack_rays(O, D, tfar).tobytes()
    assert (np.ascontiguousarray(packed["org"].T).view(np.uint32) == O.view(np.uint32)).all()
    np.testing.assert_array_equal(packed["dir"], D.T)
    assert packed["tfar"].view(np.uint32).tobytes() == tfar.view(np.uint32).tobytes()
    np.testing.assert_array_equal(packed["id"], np.arange(n))
    cam = rays[-2 * n:]                         # camera records, then pack_rays of their columns
    assert cam[:n].tobytes() == cam[n:].tobytes()
    assert np.isfinite(cam["dir"]).all()
    for isa, v in out.items():
        assert v.tobytes() == first.tobytes(), isa


@pytest.mark.parametrize("smooth", [False, True])
@pytest.mark.parametrize("select", [False, True])
def test_surface_matches_float64(smooth, select):
    rng = np.random.default_rng(2)
    m, n = 50, 40_000
    geo, _ = _geo(rng, m)
    normals = None
    if smooth:
        c = _unit(rng, 3 * m).reshape(3, 3, m)          # corner normals (axis, corner, tri)
        normals = np.concatenate([c[:, 0], c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]]).astype(F32)
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(0, m, n)
    su = np.sqrt(rng.random(n))
    hits["u"], hits["v"] = rng.random(n) * su, 1 - su
    edge = rng.random(n) < 0.1                           # a tenth within the margin of an edge
    hits["v"] = np.where(edge, rng.random(n) * 1e-6, hits["v"])
    # distances from far off to next to the plane (a tenth of the rays: within the step)
    hits["t"] = np.where(rng.random(n) < 0.1, rng.random(n) * 1e-6, rng.random(n) * 10)
    D = _unit(rng, n)
    idx = np.sort(rng.choice(n, n // 3, replace=False)) if select else None
    P, ng, ns, P_off = shading.surface(geo, normals, hits, idx, D)
    sel = np.arange(n) if idx is None else idx
    p, u, v = hits["prim"][sel], hits["u"][sel].astype(float), hits["v"][sel].astype(float)
    g = geo.astype(float)[:, p]
    exact = g[0:3] + g[3:6] * u + g[6:9] * v
    # points nearer an edge than the margin move inside by at most 2 margins (pathvertex.h inside_edges)
    step = _edge_margin(g)
    area2 = np.linalg.norm(np.cross(g[3:6].T, g[6:9].T), axis=1)
    edges = (g[6:9] - g[3:6], g[6:9], g[3:6])
    near = np.zeros(len(p), bool)
    for w, e in zip((1 - u - v, u, v), edges):
        near |= w * area2 / np.linalg.norm(e, axis=0) < step * 1.001
    assert near.any()
    np.testing.assert_allclose(P[:, ~near], exact[:, ~near], atol=2e-6 * np.abs(g).max())
    assert (np.linalg.norm(P - exact, axis=0)[near] <= 2 * step[near] + 2e-6 * np.abs(g).max()).all()
    flip = np.where(np.einsum("ij,ij->j", g[9:12], D[:, sel]) > 0, -1.0, 1.0)
    np.testing.assert_array_equal(ng, (g[9:12] * flip).astype(F32))
    # the step off the surface, at most half the way back to the plane's distance of the origin
    dn = np.abs(np.einsum("ij,ij->j", g[9:12], D[:, sel]))
    step = np.linalg.norm(g[12:15], axis=0)
    scale = np.minimum(1.0, 0.5 * hits["t"][sel] * dn / step)
    assert (scale < 1).mean() > 0.05
    np.testing.assert_allclose(P_off - P, g[12:15] * flip * scale, atol=1e-6)
    back = np.abs(np.einsum("ij,ij->j", ng.astype(float), P_off.astype(float) - P))
    assert (back <= 0.5 * hits["t"][sel] * dn * (1 + 1e-5) + 1e-6 * np.abs(g).max()).all()
    if smooth:
        nn = normals.astype(float)[:, p]
        s = nn[0:3] + nn[3:6] * u + nn[6:9] * v
        s /= np.linalg.norm(s, axis=0)
        np.testing.assert_allclose(ns[:, ~near], (s * flip)[:, ~near], atol=1e-5)   # (near: at the moved point)
    else:
        assert ns is ng


def test_surface_zero_shading_normal_falls_back_to_ng():
    geo, _ = _geo(np.random.default_rng(3), 1)
    normals = np.zeros((9, 1), F32)                   # opposite corner normals cancel: length 0
    hits = np.zeros(4, dacrt.HIT_DTYPE)
    D = np.tile(np.array([[0.0], [0.0], [1.0]], F32), 4)
    P, ng, ns, _ = shading.surface(geo, normals, hits, None, D)
    np.testing.assert_array_equal(ns, ng)


def test_surface_rejects_misses_and_bad_indices():
    geo, _ = _geo(np.random.default_rng(4), 3)
    hits = np.zeros(5, dacrt.HIT_DTYPE)
    hits["prim"][2] = -1
    D = np.ones((3, 5), F32)
    with pytest.raises(ValueError, match="1 selected hit"):
        shading.surface(geo, None, hits, None, D)
    shading.surface(geo, None, hits, np.array([0, 1, 3]), D)   # the miss is not selected
    with pytest.raises(ValueError, match=r"idx\[1\] = 5 is outside 0..4"):
        shading.surface(geo, None, hits, np.array([0, 5]), D)
    with pytest.raises(ValueError, match="geo must have shape"):
        shading.surface(geo[:14], None, hits, None, D)
    with pytest.raises(ValueError, match="hits must be a HIT_DTYPE"):
        shading.surface(geo, None, np.zeros(5, np.float32), None, D)


M32 = 0xFFFFFFFF


def _fmix32(x):
    x ^= x >> 16
    x = (x * 0x85EBCA6B) & M32
    x ^= x >> 13
    x = (x * 0xC2B2AE35) & M32
    return x ^ (x >> 16)


def _rev(x):
    return int(f"{x:032b}"[::-1], 2)


def _owen(x, seed):
    """Burley's nested uniform scramble, written from the paper with Python ints."""
    x = _rev(x)
    x = (x + seed) & M32
    for c in (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6):
        x ^= (x * c) & M32
    return _rev(x)


def _sobol1(i):
    r, v = 0, 1 << 31
    while i:
        if i & 1:
            r ^= v
        i >>= 1
        v ^= v >> 1
    return r


def _words(pixel, sample, ka, kb):
    seed = _fmix32(_fmix32(pixel ^ ka) ^ kb)
    j = _owen(sample, seed)
    return _owen(_rev(j), _fmix32(seed ^ 0x9E3779B9)), _owen(_sobol1(j), _fmix32(seed ^ 0x7F4A7C15))


def test_uniform2_is_the_documented_owen_scrambled_sobol():
    rng = np.random.default_rng(5)
    keys = np.stack([rng.integers(0, 2 ** 32, 3000, dtype=np.uint64).astype(np.uint32),
                     rng.integers(0, 5000, 3000).astype(np.uint32)])
    ka, kb = 0x12345678, 0x9ABCDEF0
    u1, u2 = shading.uniform2(keys, ka, kb)
    pick, u = shading.uniform_pick(keys, ka, kb)
    for i in range(keys.shape[1]):
        a, b = _words(int(keys[0, i]), int(keys[1, i]), ka, kb)
        assert (u1[i], u2[i]) == ((a >> 8) / 2 ** 24, (b >> 8) / 2 ** 24)
        assert (pick[i], u[i]) == (a / 2 ** 32, (b >> 8) / 2 ** 24)


def test_sample_words_are_the_same_on_every_instruction_set():
    """The words come from a GFNI/AVX-512 version where the CPU has one and from the compiler's
    per-ISA versions otherwise (native/cpp/random.cpp); DACRT_ISA picks them in a new process."""
    code = ("import sys, numpy as np; from dacrt import shading; "
            "k = np.load(sys.argv[1]); u1, u2 = shading.uniform2(k, 0xDEADBEEF, 77); "
            "p, u = shading.uniform_pick(k, 3, 0xFFFFFFFF); np.save(sys.argv[2], np.stack([u1, u2, p, u]))")
    rng = np.random.default_rng(8)
    keys = np.stack([rng.integers(0, 2 ** 32, 1037, dtype=np.uint64).astype(np.uint32),
                     rng.integers(0, 2 ** 32, 1037, dtype=np.uint64).astype(np.uint32)])
    out = outputs_per_isa(code, keys)
    first = out[dacrt.supported_isas()[0]]
    for isa, words in out.items():
        assert words.tobytes() == first.tobytes(), isa


@pytest.mark.parametrize("m", [4, 8, 10])
def test_a_pixels_first_2_to_the_m_samples_are_a_0_m_2_net(m):
    """Every elementary box of area 2^-m (2^i x 2^(m-i) cells) holds exactly one of a pixel's
    first 2^m samples of a dimension pair: stratified in both dimensions at once."""
    n = 1 << m
    for pixel, (ka, kb) in ((7, (1, 2)), (123456, (99, 1000)), (2 ** 31 + 5, (5, 5))):
        keys = np.stack([np.full(n, pixel, np.uint32), np.arange(n, dtype=np.uint32)])
        u1, u2 = shading.uniform2(keys, ka, kb)
        for i in range(m + 1):
            cx = (u1 * 2 ** i).astype(np.int64)
            cy = (u2 * 2 ** (m - i)).astype(np.int64)
            counts = np.bincount(cx * 2 ** (m - i) + cy, minlength=n)
            assert (counts == 1).all(), (pixel, i)


def test_pixels_and_pairs_get_independent_sequences():
    n = 4096
    idx = np.arange(n, dtype=np.uint32)
    a = shading.uniform2(np.stack([np.full(n, 1, np.uint32), idx]), 3, 4)
    b = shading.uniform2(np.stack([np.full(n, 2, np.uint32), idx]), 3, 4)      # another pixel
    c = shading.uniform2(np.stack([np.full(n, 1, np.uint32), idx]), 5, 6)      # another pair
    for x, y in ((a[0], b[0]), (a[1], b[1]), (a[0], c[0]), (a[0], c[1]), (a[0], a[1])):
        assert abs(np.corrcoef(x, y)[0, 1]) < 0.06           # ~4 standard errors at n = 4096


def test_cosine_scatter_distribution_and_checks():
    rng = np.random.default_rng(6)
    n = 400_000
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    ns = _unit(rng, n)
    wi, pdf, ok = shading.cosine_scatter(keys, 7, 11, ns)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=0), 1.0, atol=3e-6)
    cos = np.einsum("ij,ij->j", wi.astype(float), ns.astype(float))
    np.testing.assert_allclose(pdf, cos / np.pi, atol=1e-6)
    assert ok.mean() > 0.999 and (cos[ok] > 0).all()
    # cosine-weighted: E[cos] = 2/3, E[cos^2] = 1/2 (standard error ~4e-4)
    assert abs(cos.mean() - 2 / 3) < 2e-3 and abs((cos ** 2).mean() - 0.5) < 2e-3
    # azimuth uniform around the normal: the tangential part averages to zero
    tang = wi - ns * cos.astype(F32)
    assert np.abs(tang.mean(axis=1)).max() < 3e-3
    # geometric normal tilted away from ns: directions below it are refused
    ng = _unit(rng, n)
    wi2, _, ok2 = shading.cosine_scatter(keys, 7, 11, ns, ng)
    np.testing.assert_array_equal(wi2, wi)
    below = np.einsum("ij,ij->j", wi2, ng) <= 0
    assert not ok2[below].any() and ok2[~below & ok].all()


def test_nee_weight_matches_formula():
    rng = np.random.default_rng(8)
    n = 100_000
    ns, ng, wi = _unit(rng, n), _unit(rng, n), _unit(rng, n)
    pdf = rng.uniform(0.01, 10, n).astype(F32)
    pdf[::7] = np.inf                                 # delta lights: MIS weight 1
    p_sel = rng.uniform(0.1, 1, n).astype(F32)
    thr = rng.random((3, n)).astype(F32)
    value = rng.random((3, n)).astype(F32)
    expect = value.astype(float) * thr
    ok = shading.nee_weight(ns, ng, wi, pdf, p_sel, thr, value)
    cos = np.einsum("ij,ij->j", ns.astype(float), wi)
    bsdf = cos / np.pi
    w = 1.0 / (1.0 + (bsdf / (p_sel * pdf.astype(float))) ** 2)
    expect *= bsdf * w / p_sel
    np.testing.assert_allclose(value, expect, rtol=2e-5, atol=1e-6)   # float32 cos of near-perpendicular pairs
    below_g = np.einsum("ij,ij->j", ng, wi) <= 0
    np.testing.assert_array_equal(ok, (cos > 0) & ~below_g & (expect.max(axis=0) > 0))
    # NaN radiance never counts as a contribution
    value = np.full((3, 1), np.nan, F32)
    assert not shading.nee_weight(ns[:, :1], None, ns[:, :1], pdf[1:2], p_sel[:1], None, value)[0]
    with pytest.raises(ValueError, match="value must be a C-contiguous"):
        shading.nee_weight(ns, None, wi, pdf, p_sel, None, value.astype(np.float64))


def test_shadow_rays_toward_targets_and_along_directions():
    rng = np.random.default_rng(9)
    n = 50_000
    O = rng.normal(size=(3, n)).astype(F32)
    wi, dist = _unit(rng, n), rng.uniform(0.5, 5, n).astype(F32)
    target = (rng.normal(size=(3, n)) * 4).astype(F32)
    target[:, ::3] = np.nan                           # these follow wi / dist
    target[:, 1] = O[:, 1]                            # zero length: invalid
    idx = np.sort(rng.choice(n, n // 2, replace=False))
    idx[0] = 1
    idx.sort()
    rays, valid = shading.shadow_rays(O, wi, dist, target, idx, 0.5)
    np.testing.assert_array_equal(rays["id"], np.arange(len(idx)))
    np.testing.assert_array_equal(rays["org"], O[:, idx].T)
    aim = ~np.isnan(target[0, idx])
    d = (target[:, idx] - O[:, idx]).astype(float)
    length = np.linalg.norm(d, axis=0)
    good = aim & (length > 0)
    np.testing.assert_allclose(rays["dir"][good], (d[:, good] / length[good]).T, atol=1e-6)
    np.testing.assert_allclose(rays["tfar"][good], 0.5 * length[good], rtol=1e-6)
    np.testing.assert_array_equal(rays["dir"][~aim], wi[:, idx[~aim]].T)
    np.testing.assert_array_equal(rays["tfar"][~aim], dist[idx[~aim]])
    np.testing.assert_array_equal(valid, ~aim | (length > 0))
    assert not valid[0] and rays["tfar"][0] == 0
    with pytest.raises(ValueError, match="idx"):
        shading.shadow_rays(O, wi, dist, None, np.array([n]), 1.0)


@pytest.mark.parametrize("roulette", [False, True])
@pytest.mark.parametrize("with_thr", [False, True])
def test_continue_paths_matches_numpy(roulette, with_thr):
    rng = np.random.default_rng(11)
    n, m = 100_000, 40
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(-1, m, n)
    hit = (hits["prim"] >= 0) & (rng.random(n) < 0.9)              # some hits are masked (holdout)
    live = rng.random(m) < 0.8
    albedo = rng.random((3, m)).astype(F32)
    thr = rng.random((3, n)).astype(F32) ** 3 if with_thr else None
    u_rr = rng.random(n).astype(F32) if roulette else None
    idx, out, black, dead = shading.continue_paths(hits, hit, live, albedo, thr, u_rr)
    p = np.maximum(hits["prim"], 0)
    keep = hit & live[p]
    assert black == np.count_nonzero(hit & ~live[p])
    t = np.ones((3, n), F32) if thr is None else thr
    if roulette:
        q = np.minimum(np.sqrt(t.max(axis=0)), F32(1))
        survive = keep & (u_rr < q)
        assert dead == np.count_nonzero(keep & ~survive)
        keep = survive
        t = t * np.where(q > 0, F32(1) / q, F32(1))
    else:
        assert dead == 0
    np.testing.assert_array_equal(idx, np.flatnonzero(keep))
    np.testing.assert_allclose(out, albedo[:, p[idx]] * t[:, idx], rtol=1e-6)
    with pytest.raises(ValueError, match="albedo must have shape"):
        shading.continue_paths(hits, hit, live, albedo[:, :-1])


@pytest.mark.parametrize("n", [0, 1, 8191, 16384, 16385, 100_001])
@pytest.mark.parametrize("dead", ["none", "first_half", "second_half", "all", "random"])
def test_survivors_are_listed_in_order_across_the_threads_ranges(n, dead):
    """The survivors in ascending order, whichever thread's range holds none or all of them, at
    sizes around the two-thread split (2 x 8192 paths) and odd ones, against numpy."""
    rng = np.random.default_rng(n + len(dead))
    m = 30
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(0, m, n)
    on = {"none": np.ones(n, bool), "all": np.zeros(n, bool), "random": rng.random(n) < 0.5,
          "first_half": np.arange(n) >= n // 2, "second_half": np.arange(n) < n // 2}[dead]
    hits["prim"][~on] = -1
    live = np.ones(m, bool)
    live[3] = False
    albedo = rng.random((3, m)).astype(F32)
    idx, out, black, rr = shading.continue_paths(hits, hits["prim"] >= 0, live, albedo, None, None)
    keep = on & live[np.maximum(hits["prim"], 0)]
    np.testing.assert_array_equal(idx, np.flatnonzero(keep))
    assert (black, rr) == (np.count_nonzero(on & ~keep), 0)
    np.testing.assert_array_equal(out, albedo[:, hits["prim"][idx]])


@pytest.mark.parametrize("smooth", [False, True])
def test_continue_paths_gives_survivors_surface_and_columns_in_one_pass(smooth):
    """surface= and take= give exactly what surface() and take_columns() give for the
    survivors (the integrator relies on the same bits), and the plain return is unchanged."""
    rng = np.random.default_rng(13)
    n, m = 50_000, 40
    geo, _ = _geo(rng, m)
    normals = None
    if smooth:
        c = _unit(rng, 3 * m).reshape(3, 3, m)
        normals = np.concatenate([c[:, 0], c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]]).astype(F32)
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(-1, m, n)
    su = np.sqrt(rng.random(n))
    hits["u"], hits["v"] = rng.random(n) * su, 1 - su
    hit = hits["prim"] >= 0
    live = rng.random(m) < 0.8
    albedo = rng.random((3, m)).astype(F32)
    thr = rng.random((3, n)).astype(F32)
    u_rr = rng.random(n).astype(F32)
    D = _unit(rng, n)
    pid = rng.permutation(n)
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint32)
    pick = rng.random(n)
    idx, out, black, dead = shading.continue_paths(hits, hit, live, albedo, thr, u_rr)
    idx2, out2, black2, dead2, points, prim, taken = shading.continue_paths(
        hits, hit, live, albedo, thr, u_rr, surface=(geo, normals, D), take=(pid, None, keys, pick))
    np.testing.assert_array_equal(idx2, idx)
    np.testing.assert_array_equal(out2, out)
    assert (black2, dead2) == (black, dead) and 0 < len(idx) < n
    for got, want in zip(points, shading.surface(geo, normals, hits, idx, D)):
        np.testing.assert_array_equal(got, want)
    assert (points[2] is points[1]) == (normals is None)     # flat: ns is ng, as surface()
    np.testing.assert_array_equal(prim, hits["prim"][idx])
    assert taken[1] is None
    for got, want in zip([taken[0], taken[2], taken[3]], [pid[idx], keys[:, idx], pick[idx]]):
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)
    with pytest.raises(ValueError, match="take: arrays have"):
        shading.continue_paths(hits, hit, live, albedo, thr, u_rr, take=(pid[:-1],))


def test_triangle_table_matches_float64():
    rng = np.random.default_rng(12)
    v = (rng.normal(size=(500, 3)) * 10.0 ** rng.uniform(-3, 3, (500, 1))).astype(F32)
    t = rng.integers(0, 500, (2000, 3)).astype(np.int32)
    t[0] = (3, 3, 7)                                             # zero area
    geo, area = shading.triangle_table(v, t, 8.0)
    p = v.astype(np.float64)[t]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    n = np.cross(e1, e2)
    length = np.linalg.norm(n, axis=1)
    np.testing.assert_allclose(area, 0.5 * length, rtol=1e-12)
    assert area[0] == 0 and not geo[9:15, 0].any()
    good = length > 0
    np.testing.assert_array_equal(geo[0:3], v[t[:, 0]].T)
    np.testing.assert_array_equal(geo[3:6], e1.T.astype(F32))
    np.testing.assert_array_equal(geo[6:9], e2.T.astype(F32))
    np.testing.assert_allclose(geo[9:12][:, good], (n[good] / length[good, None]).T, atol=1e-7)
    mag = np.abs(v[t]).max(axis=(1, 2))
    ulp = 2.0 ** (np.floor(np.log2(mag)) - 23)
    # along the normal the share P's error there needs: sum_a |n_a| ulp(largest |coordinate a|)
    axis_ulp = 2.0 ** (np.floor(np.log2(np.abs(v[t]).max(axis=1))) - 23)        # (M, 3)
    unit = np.abs(n) / np.where(length > 0, length, 1.0)[:, None]
    share = np.minimum(1.0, (unit * axis_ulp).sum(axis=1) / ulp)
    assert (share[good] < 0.9).mean() > 0.2
    np.testing.assert_allclose(np.linalg.norm(geo[12:15], axis=0)[good], (8 * ulp * share)[good], rtol=1e-6)
    # a triangle marked `full` (one with a coincident twin) keeps all 8 ULPs
    whole, _ = shading.triangle_table(v, t, 8.0, full=np.ones(len(t), bool))
    np.testing.assert_allclose(np.linalg.norm(whole[12:15], axis=0)[good], 8 * ulp[good], rtol=1e-6)
    with pytest.raises(ValueError, match="refers to vertex 500"):
        shading.triangle_table(v, np.array([[0, 1, 500]]), 8.0)


def test_camera_rays_checks_its_frame():
    rx = ry = np.zeros(4, F32)
    with pytest.raises(ValueError, match="27 floats"):
        shading.camera_rays(False, np.zeros(22, F32), rx, ry)
    frame = np.zeros(27, F32)
    with pytest.raises(ValueError, match="ry"):
        shading.camera_rays(False, frame, rx, np.zeros(3, F32))
    lens = (np.zeros(4, F32), np.zeros(4, F32))
    with pytest.raises(ValueError, match="lu"):
        shading.camera_rays(False, frame, rx, ry, lens=(np.zeros(3, F32), lens[1]))
    for k, value, message in ((22, -1.0, "aperture >= 0"), (23, 0.0, "positive focal"),
                              (26, 0.0, "positive focal"), (24, np.nan, "finite")):
        bad = frame.copy()
        bad[22], bad[23], bad[26] = 0.1, 2.0, 1.0           # an open, valid lens ...
        bad[k] = value                                       # ... but for one value
        with pytest.raises(ValueError, match=message):
            shading.camera_rays(False, bad, rx, ry, lens=lens)


def test_take_columns_gathers_every_dtype_and_checks():
    rng = np.random.default_rng(22)
    n, k = 3000, 1700
    idx = rng.integers(0, n, k)
    arrays = [rng.random((3, n)).astype(F32), rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32),
              rng.integers(-5, 5, n), rng.random(n), rng.random(n) < 0.5, rng.integers(0, 9, n).astype(np.int16)]
    out = shading.take_columns(idx, *arrays[:3], None, *arrays[3:])
    assert out[3] is None
    for a, b in zip(arrays, out[:3] + out[4:]):
        assert b.dtype == a.dtype
        np.testing.assert_array_equal(b, np.take(a, idx, axis=a.ndim - 1))
    with pytest.raises(ValueError, match="idx"):
        shading.take_columns(np.array([0, n]), arrays[0])
    with pytest.raises(ValueError, match="columns"):
        shading.take_columns(idx, arrays[0], np.zeros(n + 1))


def test_sample_sums_are_sequential_float64_sums_over_the_last_axis():
    rng = np.random.default_rng(23)
    # wide exponent range: a float32 sum, or one that skipped the weights, would be off
    v = (rng.normal(size=(4, 30_001, 25)) * 10.0 ** rng.integers(-6, 7, (4, 30_001, 25))).astype(F32)
    w = (np.arange(25) % 2 == 1).astype(np.float64) * 2.0
    ref = np.zeros(v.shape[:2])
    ref_w = np.zeros(v.shape[:2])
    for j in range(v.shape[2]):                       # the order the film documents: sample 0 first
        ref += v[:, :, j].astype(np.float64)
        ref_w += v[:, :, j].astype(np.float64) * w[j]
    np.testing.assert_array_equal(shading.sample_sums(v), ref)
    np.testing.assert_array_equal(shading.sample_sums(v, w), ref_w)
    assert shading.sample_sums(np.zeros((3, 5, 0), F32)).tolist() == np.zeros((3, 5)).tolist()
    with pytest.raises(ValueError, match="weights"):
        shading.sample_sums(v, np.ones(3))


@pytest.mark.parametrize("c", [2, 3])
def test_corner_rows_are_corner_0_and_differences(c):
    rng = np.random.default_rng(24 + c)
    m = 70_001                                         # more than one thread's share
    per = rng.normal(size=(m, 3, c)).astype(F32)
    rows = shading.corner_rows(per)
    assert rows.dtype == F32 and rows.shape == (3 * c, m) and rows.flags.c_contiguous
    np.testing.assert_array_equal(rows[:c], per[:, 0].T)
    np.testing.assert_array_equal(rows[c:2 * c], per[:, 1].T - per[:, 0].T)    # float32 differences
    np.testing.assert_array_equal(rows[2 * c:], per[:, 2].T - per[:, 0].T)
    assert shading.corner_rows(np.zeros((0, 3, c), F32)).shape == (3 * c, 0)
    with pytest.raises(ValueError, match="per_corner"):
        shading.corner_rows(np.zeros((4, 2, c), F32))


def test_face_normals_and_flatness():
    rng = np.random.default_rng(23)
    v = rng.normal(size=(50, 3)) * 1e3 + 1e5             # float64 far from the origin
    t = rng.integers(0, 50, (200, 3)).astype(np.int32)
    t[0] = (3, 3, 7)                                       # degenerate
    n, good = shading.face_normals(v, t)
    cross = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    length = np.linalg.norm(cross, axis=1)
    np.testing.assert_array_equal(good, length > 0)
    np.testing.assert_allclose(n[good], cross[good] / length[good, None], atol=1e-6)
    assert not n[0].any()
    geo, _ = _geo(rng, 40)
    flat = np.repeat(geo[9:12].T[:, None, :], 3, axis=1).copy()
    assert shading.normals_flat(flat, geo, 1e-6)
    flat[17, 2, 1] += 1e-4
    assert not shading.normals_flat(flat, geo, 1e-6)
    with pytest.raises(ValueError, match="vertex"):
        shading.face_normals(v, t + 50)


def test_cosine_scatter_packs_the_bounce_rays():
    rng = np.random.default_rng(24)
    n = 5000
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    ns, O = _unit(rng, n), rng.normal(size=(3, n)).astype(F32)
    wi, pdf, ok = shading.cosine_scatter(keys, 3, 4, ns)
    wi2, pdf2, ok2, rays = shading.cosine_scatter(keys, 3, 4, ns, origins=O)
    np.testing.assert_array_equal(wi2, wi)
    np.testing.assert_array_equal(rays, shading.pack_rays(O, wi, np.full(n, np.inf, F32)))
    with pytest.raises(ValueError, match="origins"):
        shading.cosine_scatter(keys, 3, 4, ns, origins=O[:, :10])


@pytest.mark.parametrize("n", [1, 5000, 2 * 2 ** 15 + 77])
def test_cosine_scatter_records_with_a_shading_offset(n):
    """The bounce rays' records and the offset's throughputs written in one pass, on one thread
    and past the pass's two-thread split (from 2^15 paths), with a last chunk of the word loop
    cut short: the same records as packing (origins, wi) and the same throughputs as without
    records."""
    rng = np.random.default_rng(27 + n)
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    ns, ng, O = _unit(rng, n), _unit(rng, n), rng.normal(size=(3, n)).astype(F32)
    freq = np.array([1.0, 1.25, 2.0], F32)
    prim = rng.integers(0, 3, n).astype(np.int32)
    thr = rng.random((3, n)).astype(F32)
    thr2 = thr.copy()
    wi, pdf, ok = shading.cosine_scatter(keys, 5, 9, ns, ng, shading_offset=(freq, prim, thr))
    wi2, pdf2, ok2, rays = shading.cosine_scatter(keys, 5, 9, ns, ng, origins=O, shading_offset=(freq, prim, thr2))
    for a, b in ((wi2, wi), (pdf2, pdf), (ok2, ok), (thr2, thr)):
        assert a.tobytes() == b.tobytes()
    assert rays.tobytes() == shading.pack_rays(O, wi, np.full(n, np.inf, F32)).tobytes()


def test_cosine_scatter_shading_offset_scales_throughput():
    """Cycles' shading offset on BSDF rays (closure/bsdf.h shift_cos_in), in the scatter pass:
    kept directions leaving a triangle with freq > 1 have thr scaled by cos(acos(c) f) / c
    (clamped at 0), against float64; other rays and the directions are untouched."""
    rng = np.random.default_rng(26)
    n = 20000
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    ns, ng = _unit(rng, n), _unit(rng, n)
    freq = np.array([1.0, 1.25, 2.0, 1.0 / (1.0 - 0.5 * 0.9)], F32)      # triangle 0: no offset
    prim = rng.integers(0, 4, n).astype(np.int32)
    thr = rng.random((3, n)).astype(F32)
    before = thr.copy()
    wi, pdf, ok = shading.cosine_scatter(keys, 5, 9, ns, ng)
    wi2, pdf2, ok2 = shading.cosine_scatter(keys, 5, 9, ns, ng, shading_offset=(freq, prim, thr))
    np.testing.assert_array_equal(wi2, wi)
    np.testing.assert_array_equal(ok2, ok)
    c = np.minimum(np.einsum("ij,ij->j", ns.astype(float), wi.astype(float)), 1.0)
    f = freq[prim].astype(float)
    scale = np.where(c > 0, np.maximum(np.cos(np.arccos(np.clip(c, -1, 1)) * f), 0.0) / np.where(c > 0, c, 1), 0)
    scale = np.where(ok & (f > 1), scale, 1.0)
    np.testing.assert_allclose(thr, before * scale, rtol=2e-5, atol=2e-6)
    assert (scale[ok & (f > 1)] < 1).mean() > 0.99 and (scale == 0).any()   # dimmed, some to 0
    with pytest.raises(ValueError, match="thr"):
        shading.cosine_scatter(keys, 5, 9, ns, ng, shading_offset=(freq, prim, thr[:, :10]))
    with pytest.raises(ValueError, match="thr"):
        shading.cosine_scatter(keys, 5, 9, ns, ng, shading_offset=(freq, prim, thr.astype(np.float64)))


def test_camera_rays_records_match_packing():
    rng = np.random.default_rng(25)
    frame = np.zeros(27, F32)
    frame[[0, 4, 8]] = 1.0                                  # identity rotation
    frame[15:27] = (-1.0, 0.02, -0.75, 0.02, 0.4, 0.1, 99.9, 0.0, 1.0, 0.0, 0.0, 1.0)
    lensed = frame.copy()
    lensed[22:27] = (0.05, 3.0, 6.0, 0.2, 0.8)              # depth of field, hexagonal aperture
    rx, ry = (rng.random(777) * 100).astype(F32), (rng.random(777) * 75).astype(F32)
    lens = rng.random((2, 777), dtype=F32)
    for ortho in (False, True):
        for f in (frame, lensed):
            O, D, tmax, rays = shading.camera_rays(ortho, f, rx, ry, records=True, lens=lens)
            np.testing.assert_array_equal(rays, shading.pack_rays(O, D, tmax))


@pytest.mark.parametrize("k,n", [(1, 5000), (3, 10), (5, 20_001), (7, 300_000), (2000, 700)])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_transform_points_is_the_float64_affine_map_rounded_once(k, n, dtype):
    """The export's object-to-world transform: per component ((l0 x + l1 y) + l2 z) + o in
    float64, rounded once to out's dtype, for one instance, a few, instance blocks (7 x 300K)
    and many small ones; non-finite points stay so, without a warning (the export drops them)."""
    rng = np.random.default_rng(k)
    p = (rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-4, 6, (n, 1))).astype(np.float32)
    p[n // 2] = [np.inf, 0.0, np.nan]
    lin = rng.normal(size=(k, 3, 3))
    off = rng.normal(size=(k, 3)) * 1e5 if dtype == np.float64 else None
    out = np.empty((k, n, 3), dtype)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert shading.transform_points(p, lin, off, out) is out
    assert np.isnan(out[:, n // 2]).all()
    x = p.astype(np.float64)
    with np.errstate(invalid="ignore"):
        for c in range(3):
            v = lin[:, c, 0, None] * x[:, 0]
            v = v + lin[:, c, 1, None] * x[:, 1]
            v = v + lin[:, c, 2, None] * x[:, 2]
            if off is not None:
                v = v + off[:, c, None]
            np.testing.assert_array_equal(out[:, :, c], v.astype(dtype))
    with pytest.raises(ValueError, match="out must be a writeable C-contiguous"):
        shading.transform_points(p, lin, off, np.empty((k, n, 3), np.float16))
    with pytest.raises(ValueError, match="out must be"):
        shading.transform_points(p, lin, off, np.empty((k, n + 1, 3), dtype))
    with pytest.raises(ValueError, match="offset must be None or have shape"):
        shading.transform_points(p, lin, np.zeros((k + 1, 3)), np.empty((k, n, 3), dtype))


def test_ray_outputs_must_be_writeable():
    """A read-only ray array handed to a kernel that writes rays is refused and left as it was
    (an array over immutable bytes had been overwritten; a read-only memory map crashed the
    process)."""
    n = 4
    O, D, tfar = np.zeros((3, n), F32), np.ones((3, n), F32), np.ones(n, F32)
    buf = bytes(32 * n)
    out = np.frombuffer(buf, dacrt.RAY_DTYPE)
    with pytest.raises(ValueError, match="out must be writeable"):
        shading.pack_rays(O, D, tfar, out=out)
    assert buf == bytes(32 * n)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "rays.bin")
        with open(path, "wb") as f:
            f.write(bytes(32 * n))
        mapped = np.memmap(path, dtype=dacrt.RAY_DTYPE, mode='r', shape=(n,))
        with pytest.raises(ValueError, match="out must be writeable"):
            shading.pack_rays(O, D, tfar, out=mapped)
        del mapped


def test_triangle_indices_out_of_range_are_refused():
    """prim arrays (the shading offset's, next_event's with a terminator) name their first
    index outside the triangle table instead of reading another triangle's data, and an int64
    index beyond int32 is refused rather than wrapped."""
    rng = np.random.default_rng(4)
    n = 50
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    ns = _unit(rng, n)
    freq, thr = np.array([1.0, 1.5], F32), np.ones((3, n), F32)
    for bad, where in ((7, "= 7 is outside 0..1"), (-1, "= -1 is outside"), (2 ** 31 - 1, "= 2147483647 is outside")):
        prim = np.zeros(n, np.int32)
        prim[3] = bad
        with pytest.raises(ValueError, match=r"shading_offset prim\[3\] " + where):
            shading.cosine_scatter(keys, 5, 9, ns, ns, shading_offset=(freq, prim, thr))
    prim = np.zeros(n, np.int64)
    prim[5] = 2 ** 32
    with pytest.raises(ValueError, match=r"shading_offset prim\[5\] = 4294967296 is not a triangle index"):
        shading.cosine_scatter(keys, 5, 9, ns, ns, shading_offset=(freq, prim, thr))
    with pytest.raises(ValueError, match="must be an integer array"):
        shading.cosine_scatter(keys, 5, 9, ns, ns, shading_offset=(freq, np.zeros(n), thr))
    # next_event: a terminator reads the triangle of each point
    geo, _ = _geo(rng, 3)
    rec = np.zeros((1, dacrt._core.LAMP_RECORD_WIDTH), F32)
    rec[0, 0], rec[0, 2:5], rec[0, 5:8] = 0, 1.0, (0.0, 0.0, 5.0)        # a point lamp
    one = shading.LightChoice(rec, [1.0], [1.0], [False], [True])
    P = rng.random((3, n)).astype(F32)
    prim = np.zeros(n, np.int32)
    prim[9] = 3
    with pytest.raises(ValueError, match=r"prim\[9\] = 3 is outside 0..2"):
        shading.next_event(one, P, P, ns, None, None, keys, 1, 2, prim=prim,
                           terminator=(geo, None, None, np.full(3, 1.5, F32), None, None))
    ok = shading.next_event(one, P, P, ns, None, None, keys, 1, 2, prim=np.minimum(prim, 2),
                            terminator=(geo, None, None, np.full(3, 1.5, F32), None, None))
    assert ok[0].shape == (3, n)


def test_byte_texels_round_as_numpys_rint_everywhere():
    """The bytes are clip(rint(255 v)) (ties to even) for any float, not only bytes' floats: a
    dense sweep over [-0.1, 1.1], every half-byte tie and its neighbours, infinities and NaN
    (clamped to 0). (The rounding is an add-subtract of 2^23, not libm's nearbyint.)"""
    ties = (np.arange(511) / 2 / 255).astype(F32)
    v = np.concatenate([np.linspace(-0.1, 1.1, 1_000_003, dtype=F32), ties, np.nextafter(ties, F32(2)),
                        np.nextafter(ties, F32(-1)), np.array([np.nan, np.inf, -np.inf, -0.0, 0.0, 1.0], F32)])
    v = np.concatenate([v, np.zeros((-len(v)) % 4, F32)]).reshape(-1, 4)
    k8 = shading.byte_texels(v, np.arange(256, dtype=F32) / F32(255))[1]
    x = v * F32(255)
    expect = np.where(np.isnan(x), 0, np.clip(np.rint(x), 0, 255)).astype(np.uint8)
    assert (np.rint(x) != np.floor(x + F32(0.5))).any()      # the sweep has ties rounding down
    np.testing.assert_array_equal(k8, expect)


@pytest.mark.parametrize("ch", [1, 2, 3, 4])
def test_byte_texels_are_numpys_bytes_association_and_exactness(ch):
    """byte_texels against numpy: RGBA with grey and alpha expanded, rint(255 v) as bytes,
    Cycles' integer association c a / 255 (rounded down), and whether every colour value is the
    table's float for its byte; byte_lookup is the table per colour byte, alpha untouched."""
    rng = np.random.default_rng(ch)
    k = rng.integers(0, 256, (37, 53, ch)).astype(np.uint8)
    k[0, 0, :] = 0
    k[0, 1, :] = 255
    table = np.arange(256, dtype=F32) * F32(1.0 / 255.0)
    buf = table[k]
    rgba, k8, assoc, exact = shading.byte_texels(buf, table, associate=True)
    expect = np.empty((37, 53, 4), F32)
    if ch >= 3:
        expect[..., :3] = buf[..., :3]
        expect[..., 3] = buf[..., 3] if ch == 4 else 1.0
    else:
        expect[..., :3] = buf[..., :1]
        expect[..., 3] = buf[..., 1] if ch == 2 else 1.0
    np.testing.assert_array_equal(rgba, expect)
    np.testing.assert_array_equal(k8, np.rint(expect * 255.0).astype(np.uint8))
    c = k8[..., :3].astype(np.int64) * k8[..., 3:4]
    np.testing.assert_array_equal(assoc[..., :3], c // 255)
    np.testing.assert_array_equal(assoc[..., 3], k8[..., 3])
    assert exact
    assert shading.byte_texels(buf, table, associate=False)[2] is None
    off = buf.copy()
    off[5, 7, 0] = np.nextafter(off[5, 7, 0], F32(2))      # one value not a byte's float
    assert not shading.byte_texels(off, table)[3]
    nan = buf.copy()
    nan[3, 2, 0] = np.nan
    r = shading.byte_texels(nan, table)
    assert not r[3] and r[1][3, 2, 0] == 0                   # (clamped, not undefined)
    lut = (np.arange(256, dtype=F32) / F32(255)) ** F32(2.2)
    out = rgba.copy()
    shading.byte_lookup(k8, lut, out)
    np.testing.assert_array_equal(out[..., :3], lut[k8[..., :3]])
    np.testing.assert_array_equal(out[..., 3], rgba[..., 3])
    with pytest.raises(ValueError, match="rgba must have k8's shape"):
        shading.byte_lookup(k8, lut, out[:-1])
    with pytest.raises(ValueError, match="byte_floats must have shape"):
        shading.byte_texels(buf, table[:5])
