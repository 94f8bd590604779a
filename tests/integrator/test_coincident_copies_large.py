"""lights/coincident.coincident_copies on a mesh that is mostly emitters (an emissive terrain,
an LED wall): it had hashed every one of the 3M corners of a 1M-triangle emissive grid and
sorted their keys (and, in its x prefilter, all 3M corner x's), 1.5-3.5 s of set-up for a scene
without a single coincident triangle. Each vertex is now hashed once, and keys are sorted only
where bucket counts leave some that may repeat. The copies found must stay exactly those a
brute-force match of the three float32 corners finds, in both paths (few emitters: the x
prefilter; mostly emitters: every triangle). No timings here: the work is counted instead."""
from __future__ import annotations

import types

import numpy as np
import pytest

from addon.lights import coincident
from addon.lights.coincident import coincident_copies


def _grid(n):
    xs = np.linspace(-1, 1, n + 1, dtype=np.float32)
    X, Y = np.meshgrid(xs, xs, indexing='ij')
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size, np.float32)], 1)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    a, b, c, d = i, i + (n + 1), i + (n + 2), i + 1
    t = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return v, t.astype(np.int32)


def _reference(v, t, emitters, blockers):
    """coincident_copies by brute force: groups of triangles with the same three float32 corners
    (-0 as +0, any order)."""
    v = np.asarray(v, np.float32) + np.float32(0.0)
    groups = {}
    for k, tri in enumerate(t):
        if emitters[k] or blockers[k]:
            groups.setdefault(tuple(sorted(tuple(v[i].tobytes() for i in tri))), []).append(k)
    copies, winners, grouped = [], [], np.zeros(len(t), bool)
    for members in groups.values():
        if len(members) < 2 or not any(emitters[m] for m in members):
            continue
        low = min((m for m in members if blockers[m]), default=None)
        for m in members:
            grouped[m] = bool(emitters[m])
            if emitters[m] and low is not None and low < m:
                copies.append(m)
                winners.append(low)
    order = np.argsort(copies)
    if not grouped.any():
        return None, None, None
    return np.array(copies)[order], np.array(winners)[order], grouped


def _scene(seed, n=40, emissive=1.0):
    """A grid (emissive in part) and copies of some of its triangles appended as other objects'
    (own vertices, corners rolled or winding flipped, a -0, some moved by one ulp: not copies),
    with emitters and blockers drawn at random."""
    rng = np.random.default_rng(seed)
    v, t = _grid(n)
    pick = rng.choice(len(t), 30, replace=False)
    cv = v[t[pick]].reshape(-1, 3).copy()
    cv[rng.choice(len(cv), 5, replace=False), 2] = -0.0
    moved = rng.choice(len(cv), 4, replace=False)
    cv[moved, 2] = np.nextafter(np.float32(0), np.float32(1))
    ct = (len(v) + np.arange(len(cv))).reshape(-1, 3)
    ct = np.array([np.roll(r, rng.integers(3)) if rng.random() < 0.5 else r[::-1] for r in ct], np.int32)
    v, t = np.concatenate([v, cv]), np.concatenate([t, ct])
    if rng.random() < 0.5:                  # the copies first: other winners
        t = np.concatenate([t[len(t) - len(ct):], t[:len(t) - len(ct)]])
    emitters = rng.random(len(t)) < emissive
    blockers = rng.random(len(t)) < 0.8
    return v, t, emitters, blockers


@pytest.mark.parametrize('emissive', [1.0, 0.5, 0.01])
@pytest.mark.parametrize('seed', range(6))
def test_finds_exactly_the_copies_a_brute_force_match_finds(seed, emissive):
    v, t, e, b = _scene(seed, emissive=emissive)
    got, want = coincident_copies(v, t, e, b), _reference(v, t, e, b)
    for g, w in zip(got, want):
        if w is None:
            assert g is None
        else:
            np.testing.assert_array_equal(g, w)


def test_may_repeat_keeps_every_repeated_key():
    rng = np.random.default_rng(3)
    keys = rng.integers(0, 2**63, 50000, dtype=np.int64).astype(np.uint64)
    keys[rng.choice(len(keys), 300)] = keys[rng.choice(len(keys), 300)]
    # keys equal in the bits either round reads, unequal elsewhere: kept by the rounds, not repeats
    keys[:10] = (np.arange(10, dtype=np.uint64) << np.uint64(24)) | np.uint64(5) | (np.uint64(7) << np.uint64(40))
    _, first, counts = np.unique(keys, return_index=True, return_counts=True)
    repeated = np.flatnonzero(np.isin(keys, keys[first[counts > 1]]))
    kept = coincident._may_repeat(keys)
    assert np.all(np.diff(kept) > 0) and np.isin(repeated, kept).all()
    assert len(kept) < len(keys) // 5


def test_a_big_emissive_grid_hashes_each_vertex_once_and_sorts_little(monkeypatch):
    """A 200x200 emissive grid (80k triangles, no copies): points hashed no more than its
    vertices, nothing sorted of the size of its triangles or corners."""
    v, t = _grid(200)
    hashed, sorted_sizes = [], []
    real_hash = coincident._corner_hash

    def counting_hash(xyz):
        hashed.append(np.asarray(xyz).size // 3)
        return real_hash(xyz)

    def counting(name):
        real = getattr(np, name)

        def f(a, *args, **kw):
            sorted_sizes.append(np.asarray(a).size)
            return real(a, *args, **kw)
        return f
    fake_np = types.SimpleNamespace(**{k: getattr(np, k) for k in dir(np) if not k.startswith('__')})
    for name in ('unique', 'sort', 'argsort', 'searchsorted'):
        setattr(fake_np, name, counting(name))
    monkeypatch.setattr(coincident, '_corner_hash', counting_hash)
    monkeypatch.setattr(coincident, 'np', fake_np)
    every = np.ones(len(t), bool)
    assert coincident_copies(v, t, every, every) == (None, None, None)
    assert sum(hashed) <= len(v), (hashed, len(v))
    assert max(sorted_sizes, default=0) < len(t) // 5, (sorted_sizes, len(t))
