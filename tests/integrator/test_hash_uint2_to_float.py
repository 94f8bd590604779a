"""procedural.hash_uint2_to_float (Curves Info / Point Info Random, curve_random, point_random)
against Cycles' util/hash.h expression (float)hash_uint2(kx, ky) / (float)0xFFFFFFFFu in float32:
the hash rounded to float32, then divided by 2^32 (what (float)0xFFFFFFFFu rounds to), so
exactly. Dividing the exact hash by 2^32 - 1 in float64 and rounding after had differed by one
float32 step on ~0.8% of keys (curve 492 among them). Reference: lookup3's final mix in Python
integers."""
import numpy as np

from addon.procedural import hash_uint2_to_float

_FULL = 0xFFFFFFFF


def _rot(x, k):
    return ((x << k) | (x >> (32 - k))) & _FULL


def _hash_uint2(kx, ky):
    """Cycles' hash_uint2 in Python integers (lookup3: a = b = c = 0xdeadbeef + (2 << 2) + 13,
    a += kx, b += ky, final(a, b, c))."""
    a = b = c = (0xdeadbeef + (2 << 2) + 13) & _FULL
    a, b = (a + kx) & _FULL, (b + ky) & _FULL
    for k, rot in enumerate((14, 11, 25, 16, 4, 14, 24)):
        if k % 3 == 0:
            c = ((c ^ b) - _rot(b, rot)) & _FULL
        elif k % 3 == 1:
            a = ((a ^ c) - _rot(c, rot)) & _FULL
        else:
            b = ((b ^ a) - _rot(a, rot)) & _FULL
    return c


def test_hash_uint2_to_float_is_cycles_float32_expression():
    keys = np.concatenate([np.arange(2000), [492, 543, 559, 1059, 1115], np.arange(0xFFFFFF00, 0xFFFFFFFF + 1)])
    ky = np.zeros_like(keys)
    ky[:100] = 7
    got = hash_uint2_to_float(keys.astype(np.uint32), ky.astype(np.uint32))
    want = np.array([np.float32(_hash_uint2(int(x), int(y))) / np.float32(4294967296.0) for x, y in zip(keys, ky)],
                    np.float32)
    assert got.dtype == np.float32
    bad = np.flatnonzero(got != want)
    assert not len(bad), (keys[bad[:5]], got[bad[:5]], want[bad[:5]])
    assert 0.0 <= got.min() and got.max() <= 1.0
