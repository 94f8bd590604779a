"""Whether any triangle comes within a sphere light's radius (its centre closer than r to some
point of the triangle): the shading points Cycles lights from inside the sphere. The distance is
the exact point-triangle distance (Ericson, Real-Time Collision Detection 5.1.5) in float64,
on the triangles whose bounding boxes come within r only."""
from __future__ import annotations

import numpy as np


def _dot(a, b):
    return np.einsum('ij,ij->i', a, b)


def triangles_within(center, radius, geo) -> bool:
    """geo: (>= 9, n) float32 triangles as the tracer holds them (v0, edge 1, edge 2)."""
    if not radius > 0 or geo.shape[1] == 0:
        return False
    c = np.asarray(center, np.float64)
    a = geo[0:3].T.astype(np.float64)
    b = a + geo[3:6].T
    cc = a + geo[6:9].T
    lo = np.minimum(np.minimum(a, b), cc)
    hi = np.maximum(np.maximum(a, b), cc)
    near = np.einsum('ij,ij->i', *(2 * [np.maximum(np.maximum(lo - c, c - hi), 0.0)])) <= radius * radius
    if not near.any():
        return False
    a, b, cc = a[near], b[near], cc[near]
    p = np.broadcast_to(c, a.shape)
    ab, ac, ap = b - a, cc - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - cc
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide='ignore', invalid='ignore'):
        # the face's interior by default, then each region where the nearest point is a
        # vertex or lies on an edge (later assignments take precedence, as the early returns)
        den = va + vb + vc
        q = a + ab * (vb / den)[:, None] + ac * (vc / den)[:, None]
        t = d1 / (d1 - d3)
        q = np.where(((vc <= 0) & (d1 >= 0) & (d3 <= 0))[:, None], a + ab * t[:, None], q)
        t = d2 / (d2 - d6)
        q = np.where(((vb <= 0) & (d2 >= 0) & (d6 <= 0))[:, None], a + ac * t[:, None], q)
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        q = np.where(((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[:, None], b + (cc - b) * t[:, None], q)
        q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], cc, q)
        q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
        q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
    dist2 = _dot(q - p, q - p)
    return bool((np.nan_to_num(dist2, nan=np.inf) < radius * radius).any())
