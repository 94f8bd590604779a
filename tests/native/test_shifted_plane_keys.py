"""shading.shifted_plane_keys: the overlap check's second plane-key grid (overlappingfaces.py),
coplanar_key's float32 expressions on the grid shifted by half a bin, against a numpy replica of
every operation (the add-on's former _shifted_keys, kept here as the reference) on random tables
and edge cases (bin edges, out-of-range and NaN components, non-candidates), and against float64
bins: each component's bin holds the value the shifted grid puts it in."""
import numpy as np
import pytest
from dacrt import shading

F32 = np.float32


def _reference(geo, candidates, step):
    """The numpy twin the add-on had used (overlappingfaces._shifted_keys up to session 72)."""
    g = np.asarray(geo, np.float32)
    idx = np.flatnonzero(candidates)
    n = np.take(g[9:12], idx, axis=1)
    n = n * np.where(np.float32(0.5773502) * n[0] + np.float32(0.6172134) * n[1] + np.float32(0.5345225) * n[2]
                     < 0, np.float32(-1.0), np.float32(1.0))
    v0 = np.take(g[0:3], idx, axis=1)
    d = v0[0] * n[0] + v0[1] * n[1] + v0[2] * n[2]
    vals = [n[a] * np.float32(4096.0) + np.float32(4097.0) for a in range(3)]
    vals.append(d * (np.float32(1.0) / np.float32(step)) + np.float32(2097153.0))
    key = np.zeros(len(idx), np.uint64)
    ok = np.ones(len(idx), bool)
    for x, top, width in zip(vals, (16384.0,) * 3 + (4194304.0,), (14,) * 3 + (22,)):
        ok &= (x >= 0) & (x < top)
        key = (key << np.uint64(width)) | np.where(ok, x, 0).astype(np.uint64)
    keys = np.zeros(len(candidates), np.uint64)
    keys[idx] = np.where(ok, key, np.uint64(0))
    return keys


def _table(rng, m, scale):
    """A (15, m) table: v0 rows and unit normal rows (the other rows are not read)."""
    geo = rng.normal(size=(15, m)).astype(F32)
    geo[0:3] *= F32(scale)
    n = rng.normal(size=(3, m))
    geo[9:12] = (n / np.linalg.norm(n, axis=0)).astype(F32)
    return geo


def _edges(step):
    """Rows that sit on or next to the edges: axis normals both ways, components on a shifted
    bin's edge and one ulp either side, offsets at and past the 22-bit range, NaN and inf,
    a zero normal (a degenerate triangle's row)."""
    cols = []
    for a in range(3):
        for s in (1.0, -1.0):
            n = np.zeros(3)
            n[a] = s
            cols.append((n, np.zeros(3)))
    for b in (-4096, -4095, -1, 0, 1, 2047, 4095):           # n * 4096 + 4097 on an integer
        x = F32(b / 4096.0)
        for y in (x, np.nextafter(x, F32(2)), np.nextafter(x, F32(-2))):
            r = np.sqrt(max(0.0, 1.0 - float(y) ** 2))
            cols.append((np.array([y, r, 0.0]), np.array([0.5, 0.25, 0.0])))
    top = 2097151.0 * step
    for d in (top, top * 1.000001, -top, -top * 1.000001, 0.5 * step, -0.5 * step, 1e30):
        cols.append((np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, d])))
    cols += [(np.array([np.nan, 0.0, 1.0]), np.zeros(3)), (np.array([0.0, 0.0, 1.0]), np.array([np.inf, 0.0, 0.0])),
             (np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, np.nan])), (np.zeros(3), np.ones(3)),
             (np.array([2.0, 0.0, 0.0]), np.zeros(3)), (np.array([0.0, -3.0, 0.0]), np.zeros(3))]
    geo = np.zeros((15, len(cols)), F32)
    for i, (n, v) in enumerate(cols):
        geo[9:12, i] = n
        geo[0:3, i] = v
    return geo


@pytest.mark.parametrize("scale", [1e-3, 1.0, 37.5, 1e5])
def test_shifted_keys_match_the_numpy_expressions_bit_for_bit(scale):
    rng = np.random.default_rng(int(scale * 1000) % 9973)
    geo = _table(rng, 70001, scale)                  # (over the threaded pass's split)
    step = float(64 * np.spacing(F32(np.abs(geo[0:3]).max())))
    cand = rng.random(geo.shape[1]) < 0.8
    got = shading.shifted_plane_keys(geo, cand, F32(1.0) / F32(step))
    assert got.dtype == np.uint64 and got.shape == (geo.shape[1],)
    np.testing.assert_array_equal(got, _reference(geo, cand, step))
    assert (got[~cand] == 0).all() and (got[cand] != 0).all()


@pytest.mark.parametrize("step", [2.0 ** -20, 2.0 ** -6, 4.0])
def test_edge_rows_key_as_the_numpy_expressions_and_out_of_range_rows_are_keyless(step):
    geo = _edges(step)
    cand = np.ones(geo.shape[1], bool)
    got = shading.shifted_plane_keys(geo, cand, F32(1.0) / F32(step))
    np.testing.assert_array_equal(got, _reference(geo, cand, step))
    # a component out of its bins (in float64: NaN, inf, |offset| past 2^21 bins, a normal
    # component past 1 after the flip): the whole key 0 (no group of this grid joins them)
    with np.errstate(invalid='ignore'):
        n = geo[9:12].astype(np.float64)
        n *= np.where(0.5773502 * n[0] + 0.6172134 * n[1] + 0.5345225 * n[2] < 0, -1.0, 1.0)
        d = (geo[0:3].astype(np.float64) * n).sum(axis=0)
        vals = [n[a] * 4096 + 4097 for a in range(3)] + [d / step + 2097153]
        bad = np.zeros(geo.shape[1], bool)
        for x, top in zip(vals, (16384,) * 3 + (4194304,)):
            bad |= ~((x >= 0) & (x < top))
    assert (got[bad] == 0).all() and bad.sum() >= 6
    assert (got[~bad] != 0).all()
    # no candidate, no key
    assert (shading.shifted_plane_keys(geo, np.zeros(geo.shape[1], bool), F32(1.0) / F32(step)) == 0).all()


def test_each_component_bin_holds_the_shifted_value_in_float64():
    rng = np.random.default_rng(5)
    geo = _table(rng, 20000, 3.0)
    step = float(64 * np.spacing(F32(np.abs(geo[0:3]).max())))
    key = shading.shifted_plane_keys(geo, np.ones(geo.shape[1], bool), F32(1.0) / F32(step))
    n = geo[9:12].astype(np.float64)
    s = np.where(0.5773502 * n[0] + 0.6172134 * n[1] + 0.5345225 * n[2] < 0, -1.0, 1.0)
    n *= s
    d = (geo[0:3].astype(np.float64) * n).sum(axis=0)
    want = [n[a] * 4096 + 4097 for a in range(3)] + [d / step + 2097153]
    got = [(key >> np.uint64(s)) & np.uint64(m) for s, m in ((50, 0x3FFF), (36, 0x3FFF), (22, 0x3FFF), (0, 0x3FFFFF))]
    for g, w, err in zip(got, want, (4e-3,) * 3 + (0.35,)):
        g = g.astype(np.float64)
        # float32 rounding moves a value by well under a bin (err: ~4 ulps of 8192 for a normal
        # component; the offset's products and its sum at 2^21, ulp 0.25): its bin is the floor,
        # or one off where the value lies within that rounding of an edge
        assert (np.abs(g - np.floor(w)) <= 1).all()
        exact = np.abs(w - np.round(w)) > err
        assert (g[exact] == np.floor(w[exact])).all()


def test_bad_shapes_are_refused():
    geo = np.zeros((15, 4), F32)
    with pytest.raises(ValueError):
        shading.shifted_plane_keys(geo[:14], np.ones(4, bool), 1.0)
    with pytest.raises(ValueError):
        shading.shifted_plane_keys(geo, np.ones(3, bool), 1.0)
