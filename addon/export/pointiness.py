"""Cycles' Pointiness (the Geometry node's output, the standard attribute 'pointiness'): per
vertex, as Cycles' attr_create_pointiness computes it at sync: vertices at one position welded
(their Blender vertex normals summed and normalised), the angle between the normal and the mean
of the unit edge directions leaving the vertex over pi (0.5 on a flat surface, more on a convex
corner), then averaged with its edge neighbours' (a two-ring blur), each welded edge counted
once. Interpolated over the triangles as a point attribute."""

from __future__ import annotations

import numpy as np

F32 = np.float32


def pointiness(positions, normals, edges):
    """(nv,) float32 Pointiness of a mesh's vertices: positions and Blender's vertex normals
    (nv, 3), edges (m, 2) vertex indices."""
    p = np.asarray(positions, F32).reshape(-1, 3)
    nv = len(p)
    if nv == 0:
        return np.zeros(0, F32)
    # weld: every vertex to the first of those at its position (Cycles merges vertices closer
    # than sqrt(FLT_EPSILON) whose coordinate sums agree; exact duplicates in practice)
    _, first, orig = np.unique(p, axis=0, return_index=True, return_inverse=True)
    orig = first[orig.reshape(-1)]
    n = np.zeros((nv, 3), np.float64)
    np.add.at(n, orig, np.asarray(normals, F32).reshape(-1, 3))
    length = np.sqrt((n * n).sum(axis=1, keepdims=True))
    with np.errstate(divide='ignore', invalid='ignore'):
        n = np.where(length > 0, n / length, 0.0).astype(F32)
    e = orig[np.asarray(edges, np.int64).reshape(-1, 2)]
    # each welded edge once (either direction), in the order first met
    key = np.minimum(e[:, 0], e[:, 1]) * nv + np.maximum(e[:, 0], e[:, 1])
    _, once = np.unique(key, return_index=True)
    e = e[np.sort(once)]
    v0, v1 = e[:, 0], e[:, 1]
    d = p[v1] - p[v0]
    dl = np.sqrt((d * d).sum(axis=1, keepdims=True, dtype=F32))
    with np.errstate(divide='ignore', invalid='ignore'):
        d = np.where(dl > 0, d / dl, F32(0.0)).astype(F32)
    accum = np.zeros((nv, 3), F32)
    np.add.at(accum, v0, d)
    np.add.at(accum, v1, -d)
    count = np.bincount(v0, minlength=nv) + np.bincount(v1, minlength=nv)
    raw = np.zeros(nv, F32)
    has = count > 0
    mean = accum[has] / count[has, None].astype(F32)
    cos = np.clip((n[has] * mean).sum(axis=1, dtype=F32), -1.0, 1.0)       # (safe_acosf)
    raw[has] = np.arccos(cos).astype(F32) * F32(1.0 / np.pi)
    raw[orig != np.arange(nv)] = 0.0          # (duplicates take their original's below)
    data = raw.copy()
    np.add.at(data, v0, raw[v1])
    np.add.at(data, v1, raw[v0])
    data = data / (count + 1).astype(F32)
    return data[orig].astype(F32)
