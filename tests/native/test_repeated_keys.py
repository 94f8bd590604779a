"""dacrt.shading.repeated_keys (the twin finder of the triangle table's keys) against a
numpy reference: nonzero keys that another entry repeats, with planted repeats and zeros."""
import numpy as np
import pytest

from dacrt import shading


def _reference(keys):
    out = np.zeros(len(keys), bool)
    nz = np.flatnonzero(keys)
    values, inverse, counts = np.unique(keys[nz], return_inverse=True, return_counts=True)
    out[nz] = counts[inverse] > 1
    return out


@pytest.mark.parametrize("n", [0, 1, 2, 17, 5000, 300_000])
def test_repeated_keys_match_a_sort(n):
    rng = np.random.default_rng(n)
    keys = rng.integers(1, 2**63, n, dtype=np.uint64) | np.uint64(1)
    if n:
        keys[rng.random(n) < 0.3] = 0                      # keys of 0 are never twins
        k = max(n // 10, 1)
        src, dst = rng.integers(0, n, k), rng.integers(0, n, k)
        keys[dst] = keys[src]                              # planted repeats (some of zeros)
        keys[: min(n, 3)] = 12345                          # a key held three times
    got = shading.repeated_keys(keys)
    want = _reference(keys)
    assert got.dtype == bool and got.shape == (n,)
    assert np.array_equal(got, want)
    if n >= 3:
        assert got[:3].all() and want.any() and not want.all()


def test_keys_that_collide_in_the_table_stay_apart():
    # keys equal in their low and high hash bits' mixing neighbourhood: many distinct keys
    # sharing a slot chain must not be taken for repeats
    keys = (np.arange(1, 70_000, dtype=np.uint64) << np.uint64(40)) | np.uint64(1)
    assert not shading.repeated_keys(keys).any()
    keys[-1] = keys[0]
    got = shading.repeated_keys(keys)
    assert got[0] and got[-1] and got.sum() == 2
