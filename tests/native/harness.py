"""Calling dacrt the way every test does: pack the rays (records in shuffled order, so ids are
not the array positions), call intersect/occluded, and check the in-place contract on the way
out: the rays come back as a permutation of the input records, org/dir/id untouched, tfar
changed exactly as specified (hit distance for hits, negative for occluded rays)."""

from __future__ import annotations

import numpy as np

from .rays import HIT_DTYPE, to_rays


def packed(org, dirs, tfar, shuffle_seed=0):
    rays = to_rays(org, dirs, tfar)
    if shuffle_seed is not None and len(rays) > 1:
        rays = rays[np.random.default_rng(shuffle_seed).permutation(len(rays))]
    return np.ascontiguousarray(rays)


def _by_id(before, after, n, what):
    ids = after["id"].astype(np.int64)
    assert np.array_equal(np.sort(ids), np.arange(n)), \
        f"{what}: ray ids after the call are not a permutation of 0..{n - 1}"
    b = before[np.argsort(before["id"], kind="stable")]
    a = after[np.argsort(after["id"], kind="stable")]
    for field in ("org", "dir"):
        same = np.all(a[field].view(np.uint32) == b[field].view(np.uint32), axis=1)
        assert same.all(), f"{what}: {field} of ray id(s) {np.flatnonzero(~same)[:5]} changed"
    return b, a


def intersect(scene, org, dirs, tfar, threads=0, shuffle_seed=0, **kw):
    """scene.intersect on packed rays (kw: skip, visible); returns the hits after checking the
    rays' contract."""
    rays = packed(org, dirs, tfar, shuffle_seed)
    before = rays.copy()
    hits = scene.intersect(rays, threads=threads, **kw)
    n = len(before)
    assert isinstance(hits, np.ndarray) and hits.dtype == HIT_DTYPE and hits.shape == (n,), \
        f"intersect returned {type(hits)} {getattr(hits, 'dtype', None)} " \
        f"{getattr(hits, 'shape', None)}"
    b, a = _by_id(before, rays, n, "intersect")
    hit = hits["prim"] >= 0
    want = np.where(hit, hits["t"], b["tfar"])
    wrong = a["tfar"].view(np.uint32) != want.astype(np.float32).view(np.uint32)
    assert not wrong.any(), (f"intersect: tfar of ray id(s) {np.flatnonzero(wrong)[:5]} is not "
                             "the hit distance (hits) / unchanged (misses)")
    return hits


def occluded(scene, org, dirs, tfar, threads=0, shuffle_seed=0, **kw):
    """scene.occluded on packed rays (kw: skip, visible); returns the mask after checking the
    rays' contract."""
    rays = packed(org, dirs, tfar, shuffle_seed)
    before = rays.copy()
    mask = scene.occluded(rays, threads=threads, **kw)
    n = len(before)
    assert isinstance(mask, np.ndarray) and mask.dtype == np.bool_ and mask.shape == (n,), \
        f"occluded returned {type(mask)} {getattr(mask, 'dtype', None)} " \
        f"{getattr(mask, 'shape', None)}"
    b, a = _by_id(before, rays, n, "occluded")
    bad = np.where(mask, ~(a["tfar"] < 0), a["tfar"].view(np.uint32) != b["tfar"].view(np.uint32))
    assert not bad.any(), (f"occluded: tfar of ray id(s) {np.flatnonzero(bad)[:5]} is not negative "
                           "(occluded) / unchanged (not occluded)")
    return mask
