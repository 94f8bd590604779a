"""The environment map's direction <-> (u, v) kernels (native/cpp/equirect.h: atan2 and
sin/cos of pi t as float polynomials, no libm calls; envlanes.cpp: the direction -> (u, v) lane
loop, per instruction set). Property: within a few float ulps of Cycles' formulas evaluated in
float64 (u = 0.5 - atan2(y, x) / 2pi, v = 1 - acos(z / |m|) / pi; theta = pi (1 - v),
phi = pi (1 - 2u)), libm's quadrants and signed zeros (the u = 0 / 1 seam), no direction for a
zero or NaN vector, and the same bits from every instruction set the CPU runs (DACRT_ISA)."""

import numpy as np

import pytest
from dacrt import _core

from tests.native.isaruns import outputs_per_isa

F32 = np.float32
EYE = np.eye(3, dtype=F32).ravel()
TOL = 3e-7          # ~4 float ulps of 1: u, v and the direction's components lie in [-1, 1]


def _directions(rng, n):
    """(3, n) float32 directions: random on the sphere, near and on the poles and the axes,
    signed zeros, tiny and large lengths."""
    d = rng.normal(size=(3, n))
    k = rng.integers(0, 6, n)
    pole = np.stack([rng.normal(size=n) * 10.0 ** rng.uniform(-9, -2, n),
                     rng.normal(size=n) * 10.0 ** rng.uniform(-9, -2, n), np.sign(rng.normal(size=n))])
    axes = np.eye(3)[:, rng.integers(0, 3, n)] * np.sign(rng.normal(size=(1, n)))
    d = np.where(k == 1, pole, d)
    d = np.where(k == 2, axes, d)
    d = np.where(k == 3, d * 10.0 ** rng.uniform(-15, 15, n), d)
    d = d.astype(F32)
    zeros = k == 4                       # an axis with signed zeros beside it
    d[:, zeros] = np.where(rng.random((3, zeros.sum())) < 0.5, F32(-0.0), F32(0.0))
    d[rng.integers(0, 3, zeros.sum()), np.flatnonzero(zeros)] = rng.choice(np.array([1.0, -1.0], F32), zeros.sum())
    return d


def _reference_uv(m):
    """Cycles' direction_to_equirectangular in float64 of the float32 vector m (3, n)."""
    x, y, z = m.astype(np.float64)
    length = np.sqrt(x * x + y * y + z * z)
    # (+0: a -0 pole direction reads u = 0.5 as Cycles' +0 ones do, test_equirect_pole.py)
    u = 0.5 - np.arctan2(y + 0.0, x + 0.0) / (2 * np.pi)
    v = 1.0 - np.arccos(np.clip(z / length, -1, 1)) / np.pi
    return u, v, np.hypot(x, y) / length


def _turn(M, D):
    """M D in float32 in the kernel's order (no fused multiply-add), signed zeros included."""
    return np.stack([(M[r, 0] * D[0] + M[r, 1] * D[1]) + M[r, 2] * D[2] for r in range(3)]).astype(F32)


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q.astype(F32)


def test_uv_matches_float64_formulas():
    rng = np.random.default_rng(5)
    D = _directions(rng, 20011)
    for M in (np.eye(3, dtype=F32), _rotation(rng), np.diag([1, -1, 1]).astype(F32)):
        u, v, s = _core.equirect_uv(np.ascontiguousarray(M.ravel()), np.ascontiguousarray(D))
        m = _turn(M, D)          # the reference starts from the kernel's float32 turned vector
        ru, rv, rs = _reference_uv(m)
        assert np.abs(u - ru).max() <= TOL
        assert np.abs(v - rv).max() <= TOL
        assert np.abs(s - rs).max() <= TOL
        assert (u >= 0).all() and (u <= 1).all() and (v >= 0).all() and (v <= 1).all()


def test_uv_seam_and_quadrants_follow_libm_signs():
    """atan2's signed zeros decide which side of the seam (u = 0 or 1) a direction on it takes,
    as libm's atan2f does for Cycles (of the turned vector: identity x (-1, -0, 0) has +0)."""
    D = np.array([[-1, -1, -1, -1, 1, 1, 0, 0, 0, 0],
                  [0, -0.0, 1e-30, -1e-30, 0, -0.0, 1, -1, 0, -0.0],
                  [0, 0, 0, 0, 0, 0, 0, 0, 1, -1]], F32)
    u, v, s = _core.equirect_uv(EYE, D)
    m = _turn(EYE.reshape(3, 3), D)
    ref = 0.5 - np.arctan2(m[1] + F32(0), m[0] + F32(0)).astype(np.float64) / (2 * np.pi)
    np.testing.assert_allclose(u, ref, atol=TOL, rtol=0)
    assert list(u[:4]) == [0.0, 0.0, 0.0, 1.0]
    assert np.signbit(np.arctan2(F32(-0.0), F32(-1.0))) and u[1] == 0.0   # (the turn's sum made it +0)
    np.testing.assert_array_equal(v[-2:], [1.0, 0.0])       # the poles: v exactly 1 and 0
    np.testing.assert_array_equal(s[-2:], [0.0, 0.0])


def test_no_direction():
    D = np.array([[0, -0.0, np.nan, 1], [0, 0, 0, np.nan], [0, -0.0, 1, 0]], F32)
    _, _, s = _core.equirect_uv(EYE, D)
    np.testing.assert_array_equal(s, [-1, -1, -1, -1])


def test_direction_matches_float64_formulas():
    rng = np.random.default_rng(7)
    n = 50021
    u = rng.random(n).astype(F32)
    v = rng.random(n).astype(F32)
    edges = np.array([0, 0.25, 0.5, 0.75, 1 - 2 ** -24, 2 ** -24, 0.125, 0.375, 0.625, 0.875], F32)
    u[:100] = rng.choice(edges, 100)
    v[100:200] = rng.choice(edges, 100)
    k = np.arange(200, 1200)            # float neighbours of the quadrant edges
    u[k] = np.nextafter(rng.choice(edges, len(k)), rng.choice(np.array([0, 1], F32), len(k)))
    m, s = _core.equirect_direction(u, v)
    theta = np.pi * (1 - v.astype(np.float64))
    phi = np.pi * (1 - 2 * u.astype(np.float64))
    ref = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    assert np.abs(m - ref).max() <= TOL
    assert np.abs(s - np.sin(theta)).max() <= TOL
    assert (s >= 0).all()
    # and back: the round trip returns (u, v) within float rounding away from the poles
    inner = (v > 1e-3) & (v < 1 - 1e-3)
    bu, bv, _ = _core.equirect_uv(EYE, np.ascontiguousarray(m[:, inner]))
    du = np.abs(bu - u[inner])
    du = np.minimum(du, 1 - du)         # the seam: u = 0 and 1 are one meridian
    assert du.max() < 2e-6 and np.abs(bv - v[inner]).max() < 1e-6


_ISA_RUN = """
import sys
import numpy as np
from dacrt import _core
d = np.load(sys.argv[1])
M = np.load(sys.argv[2])
np.save(sys.argv[3], np.stack(_core.equirect_uv(M, d)))
"""


def test_every_isa_gives_the_same_bits():
    rng = np.random.default_rng(3)
    D = _directions(rng, 4099)                      # a short last block of every vector width
    M = _rotation(rng).ravel()
    out = outputs_per_isa(_ISA_RUN, D, M)
    first = out.pop('portable')
    for isa, got in out.items():
        np.testing.assert_array_equal(got.view(np.uint32), first.view(np.uint32), err_msg=isa)


@pytest.mark.parametrize("closest", [False, True])
def test_gather_matches_eval(closest):
    """environment_gather (the lane loop over a chunk of missed rays) adds what eval gives each."""
    import dacrt.lamps as lamps
    rng = np.random.default_rng(11)
    rgb = rng.random((12, 24, 3)).astype(F32) * 3
    env = lamps.environment_map(rgb, _rotation(rng), "Closest" if closest else "Linear")
    n = 1000
    D = _directions(rng, n)
    D /= np.linalg.norm(D.astype(np.float64), axis=0).astype(F32)
    miss = rng.random(n) < 0.6
    Le, pdf = env.eval(np.ascontiguousarray(D))
    L = np.zeros((3, n), F32)
    env.gather(0.0, np.ascontiguousarray(D), miss, None, None, np.arange(n, dtype=np.int64), L)
    np.testing.assert_array_equal(L[:, miss], Le[:, miss])
    assert not L[:, ~miss].any()


def _seam_and_centre_directions(rng, w, h, n):
    """(3, n) unit float32 directions whose (u, v) fall on texel centres and edges (the cells'
    floor steps), the u = 0 / 1 seam and the poles, beside _directions' set."""
    j = rng.integers(0, 2 * w + 1, n) / (2.0 * w)     # centres and edges of the columns
    i = rng.integers(0, 2 * h + 1, n) / (2.0 * h)
    phi, theta = np.pi * (1 - 2 * j), np.pi * (1 - i)
    d = np.stack([-np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), -np.cos(theta)]).astype(F32)
    return d


@pytest.mark.parametrize("interpolation", ["Linear", "Closest"])
def test_bsdf_gather_weighs_eval_by_the_power_heuristic(interpolation):
    """BSDF rays' environment_gather (prob > 0: the pdf's blend, thr, MIS) adds, bit for bit,
    eval's radiance weighed by 1 / (1 + (prob pdf / pdf_bsdf)^2) in float32 and times thr, with
    the directions at texel centres and edges, the seam, the poles, zero and NaN vectors among them
    (eval looks each up point by point; the gather finds the cells lane by lane)."""
    import dacrt.lamps as lamps
    rng = np.random.default_rng(17)
    h, w = 12, 24
    rgb = (rng.random((h, w, 3)) ** 3).astype(F32) * 3
    rgb[3, 5] = 0.0                                     # a black texel: cells of zero pdf
    # the map's own frame (no rotation), so the seam and centre directions stay on its grid
    env = lamps.environment_map(rgb, None, interpolation)
    D = np.concatenate([_directions(rng, 1500), _seam_and_centre_directions(rng, w, h, 1500)], axis=1)
    D = np.ascontiguousarray(D[:, rng.permutation(D.shape[1])])
    D[:, 7] = np.nan
    n = D.shape[1]
    miss = rng.random(n) < 0.7
    thr = rng.uniform(0.1, 1, (3, n)).astype(F32)
    pb = rng.uniform(0.05, 2, n).astype(F32)
    prob = F32(0.375)
    Le, pdf = env.eval(D)
    L = np.zeros((3, n), F32)
    env.gather(float(prob), D, miss, thr, pb, np.arange(n, dtype=np.int64), L)
    x = prob * pdf / pb
    x = x * x
    want = Le * (F32(1) / (F32(1) + x)) * thr
    np.testing.assert_array_equal(L[:, miss].view(np.uint32), want[:, miss].view(np.uint32))
    assert not L[:, ~miss].any()
    assert (pdf[miss] > 0).any() and (pdf[miss] == 0).any()


@pytest.mark.parametrize("prob", [0.0, 0.375])
def test_gather_reads_the_misses_from_the_hit_records(prob):
    """Given the tracer's hit records (dacrt.HIT_DTYPE) as miss, the gather reads which rays
    missed from them in place (prim < 0), so the integrator makes no flags: the sums bit for bit
    those of the flags given, camera rays (prob 0) and BSDF rays alike. Other structured arrays
    are refused, naming miss, the film untouched."""
    import dacrt
    import dacrt.lamps as lamps
    rng = np.random.default_rng(23)
    env = lamps.environment_map((rng.random((12, 24, 3)) ** 3).astype(F32) * 3, _rotation(rng), "Linear")
    n, N = 3000, 3500
    D = _directions(rng, n)
    D = np.ascontiguousarray(D / np.linalg.norm(D.astype(np.float64), axis=0).astype(F32))
    miss = rng.random(n) < 0.6
    hits = np.empty(n, dacrt.HIT_DTYPE)
    hits["t"], hits["u"], hits["v"] = rng.random(n), rng.random(n), rng.random(n)
    hits["prim"] = np.where(miss, -1, rng.integers(0, 1 << 30, n))
    hits["prim"][np.flatnonzero(~miss)[:3]] = 0
    thr, pb = (rng.uniform(0.1, 1, (3, n)).astype(F32), rng.uniform(0.05, 2, n).astype(F32)) if prob else (None, None)
    pid = rng.permutation(N)[:n].astype(np.int64)
    L0 = rng.random((3, N)).astype(F32)
    given, read = L0.copy(), L0.copy()
    env.gather(prob, D, miss, thr, pb, pid, given)
    env.gather(prob, D, hits, thr, pb, pid, read)
    assert (given != L0).any(axis=0).sum() > n // 2
    assert given.tobytes() == read.tobytes()
    for bad in (np.zeros(n, [("t", "<f4"), ("prim", "<i8"), ("u", "<f4")]), hits[::2], hits[:-1]):
        L = L0.copy()
        with pytest.raises(ValueError, match="miss"):
            env.gather(prob, D, bad, thr, pb, pid, L)
        assert L.tobytes() == L0.tobytes()


_ISA_GATHER_RUN = """
import sys
import numpy as np
import dacrt.lamps as lamps
rgb, D, u = (np.load(a) for a in sys.argv[1:4])
n = D.shape[1]
env = lamps.environment_map(rgb, None, "Linear")
L = np.zeros((3, n), np.float32)
env.gather(0.5, D, np.ones(n, bool), None, np.full(n, 0.7, np.float32), np.arange(n, dtype=np.int64), L)
wi, value, pdf = env.sample_lanes(u[0], u[1])
np.save(sys.argv[4], np.concatenate([a.ravel() for a in (L, wi, value, pdf)]))
"""


def test_gather_and_samples_give_the_same_bits_on_every_isa():
    """The cells of a 'Linear' map's lookups (env_cell_lanes) and the places of its samples give
    the same gathered radiance and the same samples from every instruction set."""
    rng = np.random.default_rng(19)
    rgb = (rng.random((24, 48, 3)) ** 4).astype(F32) * 2
    D = np.concatenate([_directions(rng, 2000), _seam_and_centre_directions(rng, 48, 24, 2001)], axis=1)
    u = rng.random((2, 4099)).astype(F32)
    out = outputs_per_isa(_ISA_GATHER_RUN, rgb, np.ascontiguousarray(D), u)
    first = out.pop('portable')
    for isa, got in out.items():
        np.testing.assert_array_equal(got.view(np.uint32), first.view(np.uint32), err_msg=isa)


@pytest.mark.parametrize("closest", [True, False])
def test_samples_land_where_the_map_has_weight(closest):
    """The guided CDF searches (a bucket's entries counted, or a binary search in a long one)
    pick a cell of non-zero weight for every (u1, u2), on a map that is mostly black (flat runs
    of equal CDF entries, buckets of none and of many entries) and wide (long buckets), at the
    uniforms' edges and the CDF's own values."""
    import dacrt.lamps as lamps
    rng = np.random.default_rng(13)
    for h, w in ((48, 96), (64, 2048)):
        rgb = np.zeros((h, w, 3), F32)
        k = rng.integers(0, h * w, 40)
        rgb.reshape(-1, 3)[k] = rng.random((40, 3)) * 100 + 0.1
        rgb[h // 2, w // 3: w // 3 + w // 4] = 1.0         # one long bright run: a long bucket
        env = lamps.environment_map(rgb, np.eye(3, dtype=F32), "Closest" if closest else "Linear")
        n = 40000
        u1 = rng.random(n).astype(F32)
        u2 = rng.random(n).astype(F32)
        edges = np.array([0, 2 ** -24, 0.5, 1 - 2 ** -24, 1 - 2 ** -23], F32)
        u1[:500] = rng.choice(edges, 500)
        u2[500:1000] = rng.choice(edges, 500)
        wi, value, pdf = env.sample(u1, u2)
        ok = pdf > 0
        assert ok.mean() > 0.99
        assert (value[:, ok].sum(axis=0) > 0).all()
        # (eval of the direction gives its pdf, but for a few directions on a texel's edge, whose
        # float round trip lands in the black neighbour: as many before the lane kernels)
        Le, pdf_eval = env.eval(np.ascontiguousarray(wi[:, ok]))
        assert (np.abs(pdf_eval - pdf[ok]) <= 2e-3 * pdf[ok]).mean() > 0.995
