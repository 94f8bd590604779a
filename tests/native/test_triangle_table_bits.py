"""dacrt.shading.triangle_table (native surface.cpp) equals, bit for bit in every row, area, key
and plane key, a numpy replica of its arithmetic (the same IEEE float32 / float64 operations in
the same order), on random triangles at scales 1e-30 .. 1e30, zero-area, sliver, huge (3e38),
-0.0, NaN and infinite corners, with and without `full`, on one thread and on all: however the
native loop is arranged (blocked, vectorised), every output keeps the bits it had."""
import numpy as np
import pytest

import dacrt
from dacrt import shading

F32 = np.float32
_MIX = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], np.uint64)
_SIGN = np.array([0.5773502, 0.6172134, 0.5345225], F32)


def _ulp(x):
    """shading.h ulp_of: the exponent bits of x (float32) less 23."""
    b = (np.asarray(x, F32).view(np.uint32) & np.uint32(0x7F800000)) - np.uint32(23 << 23)
    return b.astype(np.uint32).view(F32)


def _plane_key(v0, ng, inv):
    """coplanar.h coplanar_key in float32."""
    x, y, z = ng
    s = _SIGN[0] * x + _SIGN[1] * y + _SIGN[2] * z
    sign = np.where(s < 0, F32(-1), F32(1))
    n = [x * sign, y * sign, z * sign]
    d = v0[0] * n[0] + v0[1] * n[1] + v0[2] * n[2]

    def bin_(v, top):
        return np.where((v >= 0) & (v < top), v, F32(0)).astype(np.int64).astype(np.uint64)
    half = F32(4096.5)
    return (bin_(n[0] * F32(4096) + half, 16384) << np.uint64(50) | bin_(n[1] * F32(4096) + half, 16384) << np.uint64(36)
            | bin_(n[2] * F32(4096) + half, 16384) << np.uint64(22) | bin_(d * F32(inv) + F32(2 ** 21 + 0.5), 2 ** 22))


def _replica(v, t, offset_ulps, tiny, full, inv):
    """(geo, area, keys, plane_keys) as surface.cpp computes them."""
    c = v[np.minimum(t.astype(np.int64) & 0xFFFFFFFF, len(v) - 1)]            # (M, 3, 3) float32
    c64 = c.astype(np.float64)
    e1, e2 = c64[:, 1] - c64[:, 0], c64[:, 2] - c64[:, 0]
    n = np.stack([e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1], e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
                  e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]], axis=1)
    length = np.sqrt((n[:, 0] * n[:, 0] + n[:, 1] * n[:, 1]) + n[:, 2] * n[:, 2])
    # axis[a] = max(tiny, |c0|, |c1|, |c2|) in that order (std::max keeps the first on a NaN)
    axis = np.full((len(t), 3), F32(tiny))
    for k in range(3):
        x = np.abs(c[:, k])
        axis = np.where(axis < x, x, axis)
    mag = np.full(len(t), F32(tiny))
    for a in range(3):
        mag = np.where(mag < axis[:, a], axis[:, a], mag)
    good = length > 0
    safe = np.where(good, length, 1.0)
    s = np.zeros(len(t))
    for a in range(3):
        s = s + np.abs(n[:, a] / safe) * _ulp(axis[:, a]).astype(np.float64)
    q = s / _ulp(mag).astype(np.float64)
    share = np.where(good & ~full, np.where(q < 1.0, q, 1.0).astype(F32), F32(1))
    step = _ulp(mag) * F32(offset_ulps) * share
    ng = np.where(good[:, None], (n / safe[:, None]).astype(F32), F32(0))
    geo = np.concatenate([c[:, 0].T, e1.T.astype(F32), e2.T.astype(F32), ng.T, (ng * step[:, None]).T]).astype(F32)
    bits = (c + F32(0)).view(np.uint32).astype(np.uint64)                      # (-0 as +0)
    with np.errstate(over='ignore'):
        keys = (bits * _MIX).sum(axis=(1, 2), dtype=np.uint64) | np.uint64(1)
    return geo, 0.5 * length, keys, _plane_key(c[:, 0].T, ng.T, inv)


def _meshes():
    rng = np.random.default_rng(21)
    V = 3000
    v = rng.normal(size=(V, 3)) * 10.0 ** rng.uniform(-30, 30, (V, 1))
    v[:300] *= 1e-8                                                  # small beside the rest
    v[300:320] = rng.choice([-1.0, 1.0], (20, 3)) * 3e38            # near float32's largest
    v[320:340] = -0.0
    v[340:350, 0] = np.nan
    v[350:360, 1] = np.inf
    v[360:370, 2] = -np.inf
    t = rng.integers(0, V, (40000, 3))
    t[:2000] = rng.integers(0, 370, (2000, 3))                      # mostly the special corners
    t[2000:2100, 2] = t[2000:2100, 0]                               # zero area
    line = rng.normal(size=(100, 3))                                 # slivers: corners on a line
    sl = np.stack([line, 2 * line, 3 * line + 1e-7], axis=1).reshape(-1, 3)
    v = np.concatenate([v, sl])
    t = np.concatenate([t, V + np.arange(300).reshape(-1, 3)])
    with np.errstate(over='ignore'):
        return np.ascontiguousarray(v, F32), np.ascontiguousarray(t, np.int32)


def _same_bits(a, b, uint):
    nan = np.isnan(a)
    return np.array_equal(nan, np.isnan(b)) and np.array_equal(a[~nan].view(uint), b[~nan].view(uint))


@pytest.mark.parametrize('threads', [1, 2])
def test_table_rows_keys_and_areas_equal_the_replica_bit_for_bit(threads):
    v, t = _meshes()
    rng = np.random.default_rng(5)
    full = rng.random(len(t)) < 0.2
    inv = F32(1.0 / (64 * np.spacing(F32(1e20))))
    for f in (None, full):
        keys, pk = np.zeros(len(t), np.uint64), np.zeros(len(t), np.uint64)
        with dacrt.thread_limit(threads):
            geo, area = shading.triangle_table(v, t, 8.0, 2.0 ** -100, full=f, keys=keys, plane_keys=pk,
                                               plane_inv_step=inv)
        with np.errstate(all='ignore'):
            want = _replica(v, t, 8.0, F32(2.0 ** -100), np.zeros(len(t), bool) if f is None else f, inv)
        assert _same_bits(geo, want[0], np.uint32) and _same_bits(area, want[1], np.uint64)
        assert np.array_equal(keys, want[2]) and np.array_equal(pk, want[3])
    # (the kinds are there: zero area, NaN and infinite rows, steps shrunk and whole)
    assert (area == 0).any() and np.isnan(geo).any() and np.isinf(geo[0:3]).any()
    assert ((want[0][12:15] != 0).any(axis=0) & ~full).any()
