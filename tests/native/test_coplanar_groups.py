"""dacrt.shading.coplanar_groups (native/cpp/coplanar.cpp, the plane keys behind the add-on's
overlapping-faces check): each key equals a numpy float32 replica of its formula bit for bit
and lies within one bin of the float64 plane; the groups equal a numpy reference (np.unique
over the keys, a quad's two triangles as one, groups of 2 .. max_group) on a mix of unique
planes, planted groups, quads and oversized groups, on one thread and on all."""
import numpy as np
import pytest

import dacrt
from dacrt import shading

_SIGN = np.array([0.5773502, 0.6172134, 0.5345225], np.float32)
_F = np.float32


def _reference_keys(geo, candidates, inv_step):
    """The key of coplanar.h in numpy float32, the same operations in the same order."""
    x, y, z = geo[9], geo[10], geo[11]
    s = _SIGN[0] * x + _SIGN[1] * y + _SIGN[2] * z
    sign = np.where(s < 0, _F(-1), _F(1))
    n = [x * sign, y * sign, z * sign]
    d = geo[0] * n[0] + geo[1] * n[1] + geo[2] * n[2]

    def bin_(v, top):
        ok = (v >= 0) & (v < top)
        return np.where(ok, v, _F(0)).astype(np.int64).astype(np.uint64)
    half = _F(4096.5)
    key = bin_(n[0] * _F(4096) + half, 16384) << np.uint64(50)
    key |= bin_(n[1] * _F(4096) + half, 16384) << np.uint64(36)
    key |= bin_(n[2] * _F(4096) + half, 16384) << np.uint64(22)
    key |= bin_(d * _F(inv_step) + _F(2 ** 21 + 0.5), 2 ** 22)
    return np.where(candidates, key, np.uint64(0))


def _reference_groups(key, tri, geo, max_group):
    M = len(key)
    a, b = tri[:-1], tri[1:]
    shared = np.zeros(M - 1, bool)
    for k in range(3):
        for m in range(3):
            shared |= (a[:, k] == b[:, (m + 1) % 3]) & (a[:, (k + 1) % 3] == b[:, m])
    n = geo[9:12]
    q = (key[:-1] != 0) & (key[:-1] == key[1:]) & shared & ((n[0, :-1] * n[0, 1:] + n[1, :-1] * n[1, 1:]) + n[2, :-1] * n[2, 1:] > 0)
    q = np.r_[q, False]
    head = q & ~np.r_[False, q[:-1]]
    listed = (key != 0) & ~np.r_[False, head[:-1]]
    rows = np.flatnonzero(listed)
    u, inv, count = np.unique(key[rows], return_inverse=True, return_counts=True)
    weight = np.bincount(inv, weights=1 + head[rows].astype(np.int64)).astype(np.int64)
    keep = (count >= 2) & (weight <= max_group)
    out_rows, out_start = [], [0]
    for g in np.flatnonzero(keep):                     # (np.unique: by key, as the native order)
        r = rows[inv == g]
        r = np.sort(np.r_[r, r[head[r]] + 1])
        out_rows.extend(r.tolist()), out_start.append(out_start[-1] + len(r))
    return np.array(out_rows, np.int64), np.array(out_start, np.int64)


def _table(v, t):
    geo, _ = shading.triangle_table(np.asarray(v, np.float32), np.asarray(t, np.int32), 64.0, 2.0 ** -100)
    return geo


def _mix(seed, tail=0, unique=34000, planted=(2, 3, 5, 17, 40), big=700):
    """Triangles: unique ones, lone quads (two triangles sharing an edge,
    listed one after the other, alone in their plane) around the middle, quads and triangles of
    planted groups sharing a plane, a group too big, tail more unique ones."""
    rng = np.random.default_rng(seed)
    pieces = []

    def add(n, d, quads):
        """A triangle or quad in each plane n . x = d (n: (k, 3))."""
        u = np.cross(n, [0.3, 0.5, 0.7])
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        w = np.cross(n, u)
        c = rng.uniform(-3, 3, (len(n), 1, 2))
        p = c + (np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) if quads else rng.uniform(-1, 1, (len(n), 3, 2)))
        v = p[..., :1] * u[:, None] + p[..., 1:] * w[:, None] + (d[:, None] * n)[:, None]
        t = np.array([[0, 1, 2], [0, 2, 3]] if quads else [[0, 1, 2]])
        k = v.shape[1]
        pieces.append((v.reshape(-1, 3), (t[None] + k * np.arange(len(n))[:, None, None]).reshape(-1, 3)))

    def unit(k):
        n = rng.normal(size=(k, 3))
        return n / np.linalg.norm(n, axis=1, keepdims=True)
    add(unit(unique), rng.uniform(-5, 5, unique), False)
    add(unit(unique // 2), rng.uniform(-5, 5, unique // 2), True)
    for k in planted + (big,):
        add(np.repeat(unit(1), k, axis=0), np.full(k, rng.uniform(-5, 5)), rng.random() < 0.5)
    # axis-aligned planes both ways (n and -n are one key)
    add(np.repeat([[0.0, 0.0, 1.0]], 3, axis=0), np.ones(3), True)
    add(np.repeat([[0.0, 0.0, -1.0]], 3, axis=0), -np.ones(3), False)
    add(unit(tail), rng.uniform(-5, 5, tail), False)
    vs, ts, off = [], [], 0
    for v, t in pieces:
        vs.append(v), ts.append(t + off)
        off += len(v)
    return np.concatenate(vs).astype(np.float32), np.concatenate(ts).astype(np.int32)


def _inv_step(v):
    return np.float32(1.0 / (64 * np.spacing(np.float32(np.abs(v).max()))))


def test_keys_match_float32_replica_and_float64_plane():
    rng = np.random.default_rng(3)
    M = 50_000
    n = rng.normal(size=(M, 3))
    n[:100] = np.eye(3)[rng.integers(0, 3, 100)] * rng.choice([-1, 1], (100, 1))   # axis normals
    n[100:200] = np.cross(_SIGN.astype(np.float64), rng.normal(size=(100, 3)))       # s . n ~ 0
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    geo = np.zeros((15, M), np.float32)
    geo[9:12] = n.T.astype(np.float32)
    geo[0:3] = rng.uniform(-50, 50, (3, M)).astype(np.float32)
    cand = rng.random(M) < 0.9
    inv = np.float32(1.0 / (64 * np.spacing(np.float32(50 * np.sqrt(3)))))
    keys = np.zeros(M, np.uint64)
    shading.coplanar_groups(geo, np.arange(3 * M, dtype=np.int32).reshape(M, 3), cand, inv, 512, keys=keys)
    want = _reference_keys(geo, cand, inv)
    assert np.array_equal(keys, want)
    assert (keys[cand] != 0).all() and (keys[~cand] == 0).all()
    # float64: each field within one bin of the plane it quantises (the side n or -n as float32
    # chose it: where s . n is ~0 float64 may choose the other, a different but valid key)
    s32 = _SIGN[0] * geo[9] + _SIGN[1] * geo[10] + _SIGN[2] * geo[11]
    g = geo.astype(np.float64)
    nn = g[9:12] * np.where(s32 < 0, -1.0, 1.0)
    k = keys[cand]
    fields = [(k >> np.uint64(s)) & np.uint64(mask) for s, mask in ((50, 0x3FFF), (36, 0x3FFF), (22, 0x3FFF), (0, 0x3FFFFF))]
    exact = [nn[a, cand] * 4096 + 4096.5 for a in range(3)] + [(g[0:3, cand] * nn[:, cand]).sum(0) * float(inv) + 2 ** 21 + 0.5]
    for f, x in zip(fields, exact):
        assert np.abs(f.astype(np.float64) - np.floor(x)).max() <= 1


def test_groups_match_numpy_reference_on_one_thread_and_two():
    straddled = []
    for tail in (0, 1):                   # (one of the two puts a quad across the threads' split)
        v, t = _mix(5, tail)
        geo = _table(v, t)
        cand = np.ones(len(t), bool)
        cand[np.random.default_rng(tail).random(len(t)) < 0.01] = False
        inv = _inv_step(v)
        keys = np.zeros(len(t), np.uint64)
        with dacrt.thread_limit(2):
            rows, start = shading.coplanar_groups(geo, t, cand, inv, 512, keys=keys)
        assert np.array_equal(keys, _reference_keys(geo, cand, inv))
        want_rows, want_start = _reference_groups(keys, t, geo, 512)
        assert np.array_equal(start, want_start) and np.array_equal(rows, want_rows)
        sizes = np.diff(start)
        assert len(sizes) >= 6 and sizes.max() <= 512 and (sizes >= 2).all()   # planted found, the big one left
        with dacrt.thread_limit(1):
            r1, s1 = shading.coplanar_groups(geo, t, cand, inv, 512)
        assert np.array_equal(r1, rows) and np.array_equal(s1, start)
        b = (len(t) + 1) // 2
        straddled.append(keys[b - 1] != 0 and keys[b - 1] == keys[b] and (t[b - 1, 0] == t[b, 0]))
    assert len(t) >= 2 ** 16 and any(straddled), straddled     # (two threads: the split at b)


def test_unique_planes_and_lone_quads_give_no_group_at_scale():
    # 400K triangles of a wavy grid (every quad's triangles in two planes) and 80K lone quads:
    # no key repeats, though ~12% share a bitmap slot and ~1.5% both (keyed again, then dropped)
    n = 300
    x, y = np.meshgrid(np.linspace(0, 10, n + 1), np.linspace(0, 10, n + 1))
    i = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    t = np.c_[i, i + 1, i + n + 2, i, i + n + 2, i + n + 1].reshape(-1, 3)
    v = np.c_[x.ravel(), y.ravel(), np.sin(3 * x.ravel() + 0.1) * np.cos(2.3 * y.ravel() + 0.2) + 0.05 * x.ravel()]
    geo = _table(v, t)
    cand = np.ones(len(t), bool)
    keys = np.zeros(len(t), np.uint64)
    rows, start = shading.coplanar_groups(geo, t, cand, _inv_step(v), 512, keys=keys)
    want_rows, want_start = _reference_groups(keys, t.astype(np.int32), geo, 512)
    assert np.array_equal(rows, want_rows) and np.array_equal(start, want_start)


def test_small_and_empty_inputs():
    geo = np.zeros((15, 0), np.float32)
    rows, start = shading.coplanar_groups(geo, np.zeros((0, 3), np.int32), np.zeros(0, bool), 1.0, 512)
    assert len(rows) == 0 and list(start) == [0]
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0], [1.2, 0.2, 0], [0.2, 1.2, 0]], np.float32)
    t = np.array([[0, 1, 2], [3, 4, 5]], np.int32)
    geo = _table(v, t)
    rows, start = shading.coplanar_groups(geo, t, np.ones(2, bool), _inv_step(v), 512)
    assert list(rows) == [0, 1] and list(start) == [0, 2]
    rows, start = shading.coplanar_groups(geo, t, np.array([True, False]), _inv_step(v), 512)
    assert len(rows) == 0 and list(start) == [0]
    with pytest.raises(ValueError):
        shading.coplanar_groups(geo[:14], t, np.ones(2, bool), 1.0, 512)
