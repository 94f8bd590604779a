"""Coincident emitters: an emissive triangle modelled twice (a duplicated import, a Mirror
modifier applied twice, a second object sharing the mesh in place) is one surface to the tracer:
of exactly coincident triangles a ray's hit returns the lowest triangle index (native leaf.h's
tie rule), and a ray leaving either copy never meets the other. Light sampling must see the
same one surface, or next-event estimation adds each copy's emission where BSDF hits (and MIS)
count one: an emissive quad and its twin had lit a floor 1.42x the single quad.

Found vectorised: an order-independent hash of each triangle's three float32 vertices (as the
tracer reads them), among the triangles whose corners all share an x with an emitter's corner
(where emitters are few; otherwise each vertex hashed once), then an exact check of those
sharing a hash, sorted only where bucket counts of the hashes leave any."""
from __future__ import annotations

import numpy as np

_K = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], np.uint64)


def _corner_hash(xyz) -> np.ndarray:
    """(..., ) uint64: a hash of float32 points (..., 3) (-0 read as +0: the same point)."""
    bits = (xyz + np.float32(0.0)).view(np.uint32).astype(np.uint64)
    h = (bits * _K).sum(axis=-1, dtype=np.uint64)    # (wraps modulo 2^64)
    h ^= h >> np.uint64(31)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(29)
    return h


def _may_repeat(keys) -> np.ndarray:
    """The positions of the keys (uint64 (n,)) that may occur more than once, ascending: a
    superset of those that do, by two rounds of bucket counts on other bits of the keys (no
    sort; of n distinct keys ~6% are left)."""
    nb = 1 << max(10, min(22, (2 * len(keys)).bit_length()))      # buckets: 2-4 per key
    b = ((keys >> np.uint64(40)) & np.uint64(nb - 1)).astype(np.intp)
    keep = np.flatnonzero(np.bincount(b, minlength=nb)[b] > 1)
    if len(keep):
        b = (keys[keep] & np.uint64(nb - 1)).astype(np.intp)
        keep = keep[np.bincount(b, minlength=nb)[b] > 1]
    return keep


def coincident_copies(vertices, indices, emitters, blockers):
    """(copies, winners, grouped): the emitters (bool (M,)) that a triangle of blockers (bool
    (M,): those the rays in question hit and stop at) with a lower index covers exactly (same
    three float32 vertices, in any order or winding), as indices, ascending; the lowest such
    blocker of each (what hits return); and the mask (M,) of the emitters that coincide with
    any other emitter or blocker. None, None, None where no emitter coincides with anything."""
    cand = np.flatnonzero(emitters)
    if not len(cand):
        return None, None, None
    v = np.asarray(vertices, np.float32)
    indices = np.asarray(indices)
    pool = emitters | blockers
    if 8 * len(cand) < len(indices):
        # few emitters; prefilter (a 1M-triangle scene in a few ms): the triangles whose corners
        # all have an x an emitter's corner has (float compare: -0 == +0), then their corners
        # hashed
        x = v[:, 0]
        ex = np.unique(x[indices[cand]])
        near = ex[np.minimum(np.searchsorted(ex, x), len(ex) - 1)] == x
        S = np.flatnonzero(near[indices[:, 0]])
        S = S[pool[S] & near[indices[S, 1]] & near[indices[S, 2]]]                     # ascending
        if len(S) < 2:
            return None, None, None
        h = _corner_hash(v[indices[S]])
    else:
        # mostly emitters (an emissive terrain, an LED wall): the x prefilter would keep nearly
        # everything, so each vertex is hashed once and a corner reads its vertex's hash (hashing
        # 3M corners and sorting the x had cost 3.4 s on a 1M-triangle emissive grid)
        S = np.flatnonzero(pool)
        h = np.take(_corner_hash(v), indices if len(S) == len(indices) else indices[S])
    # an order-independent key per triangle (the sum of its corners' hashes); only triangles
    # sharing a key with another are checked exactly: first those whose key may repeat (no sort:
    # without coincident triangles few are left), then by the keys themselves
    keys = h.sum(axis=1, dtype=np.uint64)
    keep = _may_repeat(keys)
    if not len(keep):
        return None, None, None
    S, keys, h = S[keep], keys[keep], h[keep]
    uk, ki, kc = np.unique(keys, return_inverse=True, return_counts=True)
    shared = kc[ki.ravel()] > 1
    shared &= np.bincount(ki.ravel(), weights=emitters[S], minlength=len(uk))[ki.ravel()] > 0
    if not shared.any():
        return None, None, None
    S, h = S[shared], h[shared]
    xyz = v[indices[S]]                      # (S, 3 corners, 3)
    # exact: the three corners sorted (by hash), compared bit for bit
    order = np.argsort(h, axis=1, kind='stable')
    xyz = np.take_along_axis(xyz, order[:, :, None], axis=1) + np.float32(0.0)
    rows = np.ascontiguousarray(xyz.reshape(len(S), 9)).view(np.dtype((np.void, 36))).ravel()
    _, inverse, count = np.unique(rows, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    # the lowest blocker of each group: what a ray's hit returns there
    lowest = np.full(len(count), np.iinfo(np.int64).max, np.int64)
    b = blockers[S]
    np.minimum.at(lowest, inverse[b], S[b])
    grouped = np.zeros(len(emitters), bool)
    grouped[S] = count[inverse] > 1
    grouped &= emitters
    if not grouped.any():
        return None, None, None
    copy = emitters[S] & (lowest[inverse] < S)
    return S[copy], lowest[inverse][copy], grouped


_NEAR_MAX = 50_000         # emitter triangles looked at for near copies (a sort of their centroids)
_NEAR_ULPS = 16            # how near: float32 ulps of the emitters' largest coordinate
# a fixed direction the centroids are sorted along (not along an axis a grid lines up with)
_NEAR_DIR = np.array([0.5366, 0.6397, 0.5503]) / np.linalg.norm([0.5366, 0.6397, 0.5503])
# the six corner orders a copy may list its corners in (rolled, or wound the other way)
_ORDERS = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])


def near_copies(vertices, indices, emitters, tubes=None):
    """(mask, tol): the emitters (bool (M,)) another emitter repeats up to rounding, every corner
    within tol (_NEAR_ULPS float32 ulps of the emitters' largest coordinate, in any corner order
    or winding) but not bit for bit (a copy under another transform, or moved by ~1e-6: both are
    light-sampled, and coincident_copies, exact, leaves them); (None, tol) where there are none,
    or too many emitters to look (_NEAR_MAX). tubes (optional): (one_sided bool (M,), placement
    int (M,)): a pair of tube triangles of one placement is no copy (a tapering strand's tip
    triangles, rounded together, ~1e-11 in area: not a copy the user made). Only triangles
    split alike are found: a quad
    copied under a 90 degree turn splits along its other diagonal, and those are not
    (lights/overlap.py finds them). Cheap: the
    centroids sorted along one direction, each compared with the next few within tol."""
    E = np.flatnonzero(emitters)
    if not 2 <= len(E) <= _NEAR_MAX:
        return None, 0.0
    c32 = np.asarray(vertices, np.float32)[np.asarray(indices)[E]] + np.float32(0.0)   # (E, 3, 3)
    tol = float(_NEAR_ULPS * np.spacing(np.float32(max(float(np.abs(c32).max()), 1e-30))))
    cent = c32.mean(axis=1, dtype=np.float64)
    # triangles smaller than a few tol are rounding themselves: any two of them would match
    big = np.flatnonzero(np.abs(c32 - cent[:, None].astype(np.float32)).max(axis=(1, 2)) > 4 * tol)
    if len(big) < 2:
        return None, tol
    p = cent[big] @ _NEAR_DIR
    srt = np.argsort(p)
    order, p = big[srt], p[srt]
    found = np.zeros(len(E), bool)
    for k in range(1, 33):              # the next 32 along the direction at most
        close = np.flatnonzero(p[k:] - p[:-k] <= 2 * tol)      # (a centroid moves <= tol * sqrt(3))
        if not len(close):
            break
        a, b = order[close], order[close + k]
        near = np.abs(cent[a] - cent[b]).max(axis=1) <= tol     # centroids first: few are left
        a, b = a[near], b[near]
        if not len(a):
            continue
        ca, cb = c32[a].astype(np.float64), c32[b].astype(np.float64)
        err = np.min([np.abs(ca - cb[:, o]).max(axis=(1, 2)) for o in _ORDERS], axis=0)
        exact = np.zeros(len(a), bool)
        for o in _ORDERS:
            exact |= (c32[a] == c32[b][:, o]).all(axis=(1, 2))
        hit = (err <= tol) & ~exact
        if tubes is not None:
            one, place = tubes
            hit &= ~(one[E[a]] & one[E[b]] & (place[E[a]] == place[E[b]]))
        found[a[hit]] = found[b[hit]] = True
    if not found.any():
        return None, tol
    mask = np.zeros(len(emitters), bool)
    mask[E[found]] = True
    return mask, tol
