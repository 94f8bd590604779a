"""shading.drop_columns: a few columns dropped in place from per-path arrays and bounce-ray
records gives the bits take_columns of the kept indices and pack_rays give (the integrator's
bounce drops the rays a smooth normal sends below the surface this way)."""
import numpy as np
import pytest
from dacrt import shading

F32 = np.float32


def _arrays(rng, n):
    return [rng.random((3, n)).astype(F32), rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32),
            rng.integers(-5, 5, n), rng.random(n), rng.random(n) < 0.5, rng.integers(0, 9, (2, n)).astype(np.int16)]


def _keeps(rng, n):
    few = np.ones(n, bool)
    few[[0, 1, 7, n // 2, n - 1]] = False                  # the ends and a run of two
    runs = np.repeat(rng.random(n // 50 + 1) < 0.5, 50)[:n]  # long runs both ways
    return [few, runs, rng.random(n) < 0.9, np.ones(n, bool), np.zeros(n, bool)]


@pytest.mark.parametrize("case", range(5))
def test_dropped_columns_match_taking_the_kept_and_repacking_the_rays(case):
    rng = np.random.default_rng(40 + case)
    n = 5003
    keep = _keeps(rng, n)[case]
    arrays = _arrays(rng, n)
    keys = arrays[1]
    ns = rng.normal(size=(3, n)).astype(F32)
    ns /= np.linalg.norm(ns, axis=0)
    origins = rng.random((3, n)).astype(F32)
    wi, pdf, ok, rays = shading.cosine_scatter(keys, 7, 9, ns, origins=origins)
    idx = np.flatnonzero(keep)
    want = shading.take_columns(idx, *arrays, origins, wi, pdf)
    want_rays = shading.pack_rays(want[-3], want[-2], np.full(len(idx), np.inf, F32))
    got = shading.drop_columns(keep, *arrays[:2], None, *arrays[2:], origins, wi, pdf, rays=rays)
    assert got[2] is None
    got = got[:2] + got[3:]
    assert len(got) == len(want) + 1
    for g, w in zip(got, want + [want_rays]):
        assert g.dtype == w.dtype and g.shape == w.shape
        assert g.flags.c_contiguous
        np.testing.assert_array_equal(g.view(np.uint8), w.view(np.uint8))   # the same bits (records too)


def test_drop_columns_refuses_what_it_cannot_compact_in_place():
    n = 64
    keep = np.ones(n, bool)
    keep[3] = False
    a = np.zeros((6, n), F32)
    with pytest.raises(ValueError, match="share memory"):
        shading.drop_columns(keep, a[0:3], a[2:5])             # overlapping rows
    with pytest.raises(ValueError, match="C-contiguous"):
        shading.drop_columns(keep, np.zeros((n, 3), F32).T)    # a copy would be compacted, not it
    with pytest.raises(ValueError, match="columns"):
        shading.drop_columns(keep, np.zeros(n + 1))
    read_only = np.zeros(n)
    read_only.flags.writeable = False
    with pytest.raises(ValueError, match="writeable"):
        shading.drop_columns(keep, read_only)
    kept = shading.drop_columns(keep, a[0:3], a[3:6])          # rows of one buffer, apart: fine
    assert kept[0].shape == (3, n - 1) and kept[1].shape == (3, n - 1)
