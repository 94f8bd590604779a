"""dacrt.shading.coplanar_groups and triangle_table's plane_keys (native/cpp/coplanar.cpp,
surface.cpp: the plane keys behind the add-on's overlapping-faces check): each key the table
writes equals a numpy float32 replica of its formula on the table's own v0 and normal rows bit
for bit (the keys coplanar_groups had computed from those rows itself) and lies within one bin
of the float64 plane, also on slivers, planes through the origin, -0.0 corners, huge, infinite
and NaN coordinates; the groups equal a numpy reference (np.unique over the keys, a quad's two
triangles as one, groups of 2 .. max_group) on a mix of unique planes, planted groups, quads,
oversized groups and those adversarial rows, on one thread and on all."""
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


def _table(v, t, inv=None):
    """triangle_table's rows, its plane keys (offset bins 1 / inv, by default 64 ulps of the
    largest |coordinate|) and inv."""
    v = np.asarray(v, np.float32)
    inv = _inv_step(v) if inv is None else inv
    keys = np.zeros(len(t), np.uint64)
    geo, _ = shading.triangle_table(v, np.asarray(t, np.int32), 64.0, 2.0 ** -100, plane_keys=keys,
                                    plane_inv_step=inv)
    return geo, keys, inv


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
    big = np.abs(v[np.isfinite(v)]).max(initial=1e-30)
    return np.float32(1.0 / (64 * np.spacing(np.float32(big))))


def _in_planes(rng, n, v0, size):
    """One triangle a plane: corner v0 (M, 3), the other two within size of it in the plane
    normal to n (M, 3)."""
    u = np.cross(n, rng.normal(size=n.shape))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = np.cross(n, u)
    p = rng.uniform(-1, 1, (len(n), 2, 2)) * np.asarray(size).reshape(-1, 1, 1)
    c = np.stack([v0, v0 + p[:, 0, :1] * u + p[:, 0, 1:] * w, v0 + p[:, 1, :1] * u + p[:, 1, 1:] * w], axis=1)
    return c.reshape(-1, 3), np.arange(3 * len(n), dtype=np.int32).reshape(-1, 3)


def test_keys_match_float32_replica_and_float64_plane():
    rng = np.random.default_rng(3)
    M = 50_000
    n = rng.normal(size=(M, 3))
    n[:100] = np.eye(3)[rng.integers(0, 3, 100)] * rng.choice([-1, 1], (100, 1))   # axis normals
    n[100:200] = np.cross(_SIGN.astype(np.float64), rng.normal(size=(100, 3)))       # s . n ~ 0
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    v, t = _in_planes(rng, n, rng.uniform(-50, 50, (M, 3)), 1.0)
    geo, keys, inv = _table(v, t)
    assert np.array_equal(keys, _reference_keys(geo, np.ones(M, bool), inv))
    assert (keys != 0).all()
    # float64: each field within one bin of the plane it quantises (the side n or -n as float32
    # chose it: where s . n is ~0 float64 may choose the other, a different but valid key)
    s32 = _SIGN[0] * geo[9] + _SIGN[1] * geo[10] + _SIGN[2] * geo[11]
    g = geo.astype(np.float64)
    nn = g[9:12] * np.where(s32 < 0, -1.0, 1.0)
    fields = [(keys >> np.uint64(s)) & np.uint64(mask) for s, mask in ((50, 0x3FFF), (36, 0x3FFF), (22, 0x3FFF), (0, 0x3FFFFF))]
    exact = [nn[a] * 4096 + 4096.5 for a in range(3)] + [(g[0:3] * nn).sum(0) * float(inv) + 2 ** 21 + 0.5]
    for f, x in zip(fields, exact):
        assert np.abs(f.astype(np.float64) - np.floor(x)).max() <= 1


def _adversarial(rng):
    """Rows a key could get wrong, each kind also planted in repeats (groups of 2-6 in one plane):
    slivers (a corner 1e-7 off the line of the other two), planes through the origin with -0.0
    corners, huge coordinates (1e30 and 3e38, the offset out of range), zero-area triangles,
    NaN and infinite corners, planes whose offset lies on a bin's edge."""
    pieces = []

    def add(c):
        pieces.append(np.asarray(c, np.float64).reshape(-1, 3))
    for k in rng.integers(1, 7, 60):
        a, b = rng.normal(size=3), rng.normal(size=3)
        for _ in range(k):                                          # slivers along one line
            s = rng.uniform(-2, 2, 2)
            add([a + s[0] * b, a + s[1] * b, a + 0.5 * (s[0] + s[1]) * b + 1e-7 * rng.normal(size=3)])
    for k in rng.integers(1, 7, 60):                                # through the origin, -0.0
        n = rng.normal(size=3)
        c, _ = _in_planes(rng, np.repeat(n[None] / np.linalg.norm(n), k, axis=0), np.zeros((k, 3)), 2.0)
        c = c.reshape(k, 3, 3)
        c[:, 0] = -0.0
        c[c == 0] *= rng.choice([-1.0, 1.0], c[c == 0].shape)
        add(c)
    ax = np.zeros((40, 3, 3))                                       # axis planes, -0.0 components
    ax[:, 1:, :2] = rng.uniform(-1, 1, (40, 2, 2))
    ax[:, :, 2] = -0.0
    add(ax)
    for scale in (1e30, 3e38):                                      # huge, in planes and not
        n = np.repeat(rng.normal(size=(1, 3)), 5, axis=0)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        c, _ = _in_planes(rng, n, np.repeat(rng.uniform(-1, 1, (1, 3)) * scale, 5, axis=0), 0.1 * scale)
        add(c)
        add(rng.uniform(-scale, scale, (12, 3)))
    add(np.repeat(rng.normal(size=(1, 3)), 3 * 6, axis=0))          # zero area (all corners one point)
    bad = rng.normal(size=(30, 3, 3))                               # NaN and infinite corners
    bad[:10, rng.integers(0, 3, 10), rng.integers(0, 3, 10)] = np.nan
    bad[10:20, :, 0] = np.nan
    bad[20:, rng.integers(0, 3, 10), 1] = np.inf * rng.choice([-1, 1], 10)
    add(bad)
    return pieces


def test_adversarial_rows_key_as_the_replica_and_group_as_the_reference():
    rng = np.random.default_rng(11)
    pieces = _adversarial(rng)
    # after ~45K ordinary triangles and quads (so that two threads split the rows), the pieces in
    # a random order
    v, t = _mix(2, unique=20000, planted=(2, 4), big=600)
    extra = np.concatenate([pieces[k] for k in rng.permutation(len(pieces))])
    ordinary = len(t)
    t = np.concatenate([t, len(v) + np.arange(len(extra), dtype=np.int32).reshape(-1, 3)])
    with np.errstate(all='ignore'):
        v32 = np.concatenate([v, extra.astype(np.float32)])
    no_offset = []
    for inv in (None, np.float32(1.0 / (64 * np.spacing(np.float32(4.0))))):   # the largest finite, and a small step
        geo, keys, inv = _table(v32, t, inv)
        with np.errstate(all='ignore'):
            want = _reference_keys(geo, np.ones(len(t), bool), inv)
        assert np.array_equal(keys, want)
        # (the kinds are there: NaN corners, zero normals, offsets NaN or out of range, 0 bits)
        assert np.isnan(geo[0:3]).any() and (geo[9:12] == 0).all(axis=0).any()
        no_offset.append(int(((keys & np.uint64(0x3FFFFF)) == 0).sum()))
        cand = np.ones(len(t), bool)
        cand[rng.random(len(t)) < 0.02] = False
        masked = np.where(cand, keys, np.uint64(0))
        want_rows, want_start = _reference_groups(masked, t, geo, 512)
        for threads in (1, 2):
            with dacrt.thread_limit(threads):
                rows, start = shading.coplanar_groups(keys, geo, t, cand, 512)
            assert np.array_equal(start, want_start) and np.array_equal(rows, want_rows)
        assert (want_rows >= ordinary).sum() > 200       # (the adversarial repeats are groups)
    assert no_offset[1] > no_offset[0] >= 30            # (the huge ones out of range with the small step)


def test_groups_match_numpy_reference_on_one_thread_and_two():
    straddled = []
    for tail in (0, 1):                   # (one of the two puts a quad across the threads' split)
        v, t = _mix(5, tail)
        geo, keys, inv = _table(v, t)
        cand = np.ones(len(t), bool)
        cand[np.random.default_rng(tail).random(len(t)) < 0.01] = False
        assert np.array_equal(keys, _reference_keys(geo, np.ones(len(t), bool), inv))
        masked = np.where(cand, keys, np.uint64(0))
        with dacrt.thread_limit(2):
            rows, start = shading.coplanar_groups(keys, geo, t, cand, 512)
        want_rows, want_start = _reference_groups(masked, t, geo, 512)
        assert np.array_equal(start, want_start) and np.array_equal(rows, want_rows)
        sizes = np.diff(start)
        assert len(sizes) >= 6 and sizes.max() <= 512 and (sizes >= 2).all()   # planted found, the big one left
        with dacrt.thread_limit(1):
            r1, s1 = shading.coplanar_groups(keys, geo, t, cand, 512)
        assert np.array_equal(r1, rows) and np.array_equal(s1, start)
        b = (len(t) + 1) // 2
        straddled.append(masked[b - 1] != 0 and masked[b - 1] == masked[b] and (t[b - 1, 0] == t[b, 0]))
    assert len(t) >= 2 ** 16 and any(straddled), straddled     # (two threads: the split at b)


def test_unique_planes_and_lone_quads_give_no_group_at_scale():
    # 400K triangles of a wavy grid (every quad's triangles in two planes) and 80K lone quads:
    # no key repeats, though ~12% share a bitmap slot and ~1.5% both (looked up, then dropped)
    n = 300
    x, y = np.meshgrid(np.linspace(0, 10, n + 1), np.linspace(0, 10, n + 1))
    i = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    t = np.c_[i, i + 1, i + n + 2, i, i + n + 2, i + n + 1].reshape(-1, 3)
    v = np.c_[x.ravel(), y.ravel(), np.sin(3 * x.ravel() + 0.1) * np.cos(2.3 * y.ravel() + 0.2) + 0.05 * x.ravel()]
    geo, keys, _ = _table(v, t)
    rows, start = shading.coplanar_groups(keys, geo, t, np.ones(len(t), bool), 512)
    want_rows, want_start = _reference_groups(keys, t.astype(np.int32), geo, 512)
    assert np.array_equal(rows, want_rows) and np.array_equal(start, want_start)


def test_small_and_empty_inputs():
    geo = np.zeros((15, 0), np.float32)
    rows, start = shading.coplanar_groups(np.zeros(0, np.uint64), geo, np.zeros((0, 3), np.int32), np.zeros(0, bool), 512)
    assert len(rows) == 0 and list(start) == [0]
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0], [1.2, 0.2, 0], [0.2, 1.2, 0]], np.float32)
    t = np.array([[0, 1, 2], [3, 4, 5]], np.int32)
    geo, keys, _ = _table(v, t)
    rows, start = shading.coplanar_groups(keys, geo, t, np.ones(2, bool), 512)
    assert list(rows) == [0, 1] and list(start) == [0, 2]
    rows, start = shading.coplanar_groups(keys, geo, t, np.array([True, False]), 512)
    assert len(rows) == 0 and list(start) == [0]
    with pytest.raises(ValueError):
        shading.coplanar_groups(keys, geo[:14], t, np.ones(2, bool), 512)
    with pytest.raises(ValueError, match="keys"):
        shading.coplanar_groups(keys[:1], geo, t, np.ones(2, bool), 512)
    with pytest.raises(ValueError, match="plane_keys"):
        shading.triangle_table(v, t, 64.0, plane_keys=np.zeros(3, np.uint64), plane_inv_step=1.0)
