"""Which triangles a point inside a point-cloud sphere can lie on.

A shadow ray blocked by a point-cloud sphere is traced a second time, past sphere walls met from
inside (integrator._occluded_past_insides: Cycles' points have no inside). A ray leaving a point
outside every sphere meets a sphere, if at all, from outside first (the tessellated spheres are
closed), so the second trace can only open rays whose origin is inside one: on a sphere's own
triangle, or on a triangle that reaches into the sphere's bounding box. inside_starts flags those
triangles, so the rays leaving the others skip the second trace (the same answer, unflagged
rays would be found blocked again).

Spheres are found without the export's help: triangles sharing a vertex belong to one sphere, and
merging the triangles' vertex-index ranges that overlap joins every such pair (each group is one
sphere or a union of them, whose box still holds each; the export writes each sphere's vertices
together, so a group is one sphere there). Triangle boxes are tested against
the group boxes on a uniform grid of cells as large as the largest group box; triangles spanning
many cells are tested against every group box, in chunks. Every shortcut errs towards a flag.
"""
from __future__ import annotations

import numpy as np

# candidate triangle-group pairs through shared cells held at most (beyond, a shared cell is
# enough for a flag), and large triangles' box tests against every group made at most (beyond,
# they are flagged unexamined)
MAX_PAIRS = 4_000_000
MAX_TESTS = 50_000_000
# boxes padded by this fraction of the largest box extent plus float32's rounding at the scene's
# coordinates: a ray origin is a hit point rounded near, not exactly on, its triangle
PAD = 1e-4


def sphere_boxes(vertices, indices):
    """(lo (g, 3), hi (g, 3)) float64 boxes of groups of triangles joined through shared vertices
    (indices: (k, 3) of the sphere triangles): each the box of the vertices its triangles' index
    range spans (vertices it does not use in that range only make it larger)."""
    v = np.asarray(vertices)
    if not len(indices):
        return np.zeros((0, 3)), np.zeros((0, 3))
    lo_i, hi_i = _min3(indices), _max3(indices)
    # vertices k and k + 1 are joined where some triangle's range [lo, hi] holds both: counted
    # by a difference array (no sort)
    n = len(v)
    open_ = np.cumsum(np.bincount(lo_i, minlength=n + 1) - np.bincount(hi_i, minlength=n + 1))[:n] > 0
    used = open_.copy()
    used[1:] |= open_[:-1]
    used[lo_i] = True                           # (a triangle of one repeated vertex)
    joined_before = np.concatenate([[False], open_[:-1]])
    first = np.flatnonzero(used & ~joined_before)
    last = np.flatnonzero(used & ~open_)
    # each group's range [first, last] and the gap after it, reduced in one pass: the gaps' rows
    # are dropped (an empty gap reduces its one row, dropped too)
    bounds = np.stack([first, last + 1], 1).ravel()
    if bounds[-1] >= n:
        bounds = bounds[:-1]
    lo = np.minimum.reduceat(v, bounds, axis=0)[::2].astype(np.float64)
    hi = np.maximum.reduceat(v, bounds, axis=0)[::2].astype(np.float64)
    return lo, hi


def _min3(rows):
    return np.minimum(np.minimum(rows[:, 0], rows[:, 1]), rows[:, 2])


def _max3(rows):
    return np.maximum(np.maximum(rows[:, 0], rows[:, 1]), rows[:, 2])


def inside_starts(vertices, indices, spheres):
    """(m,) bool: the triangles a point inside one of the spheres' closed meshes can lie on
    (spheres: (m,) bool, the sphere triangles)."""
    flag = np.asarray(spheres, bool).copy()
    if not flag.any():
        return flag
    glo, ghi = sphere_boxes(vertices, indices[flag])
    v = np.asarray(vertices)
    test = np.flatnonzero(~flag)
    tlo, thi = np.empty((len(test), 3), np.float32), np.empty((len(test), 3), np.float32)
    for a in range(3):                  # an axis at a time: (n, 3) corners, not (n, 3, 3)
        corners = v[:, a][indices[test]]
        tlo[:, a], thi[:, a] = _min3(corners), _max3(corners)
    size = float((ghi - glo).max())
    scale = float(np.abs(v).max()) if len(v) else 0.0
    pad = PAD * size + 4.0 * np.finfo(np.float32).eps * scale
    glo, ghi = glo - pad, ghi + pad
    cell = 1.01 * (size + 2.0 * pad)     # (a group box spans at most 2 cells an axis, rounding too)
    if not cell > 0.0 or not np.isfinite(cell):
        flag[:] = True
        return flag
    origin = glo.min(axis=0)
    c0 = np.floor((tlo - origin) / cell).astype(np.int64)
    small = ((np.floor((thi - origin) / cell).astype(np.int64) - c0) <= 1).all(axis=1)
    rows = np.flatnonzero(small)
    flag[test[rows]] = _grid_pairs(rows, c0[rows], glo, ghi, origin, cell, tlo, thi)
    rows = np.flatnonzero(~small)
    flag[test[rows]] = _all_pairs(rows, glo, ghi, tlo, thi)
    return flag


def _keys(c):
    """One int64 key of cell coordinates (n, 3) (collisions only join cells: more candidates)."""
    return (c[:, 0] * 73856093) ^ (c[:, 1] * 19349663) ^ (c[:, 2] * 83492791)


def _corner_cells(c0):
    """(8, n, 3): the cells of a box starting in cell c0 and spanning at most 2 an axis."""
    step = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.int64)
    return c0[None] + step[:, None, :]


def _overlap(alo, ahi, blo, bhi):
    return ((alo <= bhi) & (blo <= ahi)).all(axis=-1)


def _grid_pairs(tris, c0, glo, ghi, origin, cell, tlo, thi):
    """Whether each triangle's box (tris: rows of tlo/thi) meets some group box, through the
    groups sharing one of its cells."""
    n, g = len(tris), len(glo)
    out = np.zeros(n, bool)
    if not n:
        return out
    gc = _corner_cells(np.floor((glo - origin) / cell).astype(np.int64))     # (8, g, 3)
    gkeys = _keys(gc.reshape(-1, 3))
    ggroup = np.tile(np.arange(g), 8)
    order = np.argsort(gkeys, kind='stable')
    gkeys, ggroup = gkeys[order], ggroup[order]
    tkeys = _keys(_corner_cells(c0).reshape(-1, 3))                         # (8 n,)
    trow = np.tile(np.arange(n), 8)
    left = np.searchsorted(gkeys, tkeys, 'left')
    count = np.searchsorted(gkeys, tkeys, 'right') - left
    has = count > 0
    if int(count.sum()) > MAX_PAIRS:        # too crowded to pair up: a shared cell is enough
        out[np.unique(trow[has])] = True
        return out
    left, count, trow = left[has], count[has], trow[has]
    rep = np.repeat(np.arange(len(trow)), count)
    gi = ggroup[np.repeat(left, count) + (np.arange(len(rep)) - np.repeat(np.cumsum(count) - count, count))]
    ti = trow[rep]
    hit = _overlap(tlo[tris[ti]], thi[tris[ti]], glo[gi], ghi[gi])
    out[ti[hit]] = True
    return out


def _all_pairs(tris, glo, ghi, tlo, thi):
    """Whether each of these (large) triangles' boxes meets some group box, by testing all."""
    out = np.zeros(len(tris), bool)
    if not len(tris):
        return out
    g = len(glo)
    if len(tris) * g > MAX_TESTS:
        out[:] = True
        return out
    chunk = max(1, 4_000_000 // max(g, 1))
    for s in range(0, len(tris), chunk):
        t = tris[s:s + chunk]
        out[s:s + chunk] = _overlap(tlo[t][:, None], thi[t][:, None], glo[None], ghi[None]).any(axis=1)
    return out
