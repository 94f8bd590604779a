"""Whether any triangle comes within a sphere light's radius (its centre closer than r to some
point of the triangle): the shading points Cycles lights from inside the sphere. The distance is
the exact point-triangle distance (Ericson, Real-Time Collision Detection 5.1.5) in float64,
on the triangles whose bounding boxes come within r only. TriangleReach sorts the triangles by
their boxes' low x once, so each light reads only the slice its x range can reach (plus the few
triangles wider than nearly all: a floor), not every triangle: 1M small triangles take 0.9 s
CPU to arrange and 10K spot queries 2.4 s, where 10K passes over all of them would take minutes
(only scenes with sphere spots under MIS pay it)."""
from __future__ import annotations

import numpy as np


def _dot(a, b):
    return np.einsum('ij,ij->i', a, b)


class TriangleReach:
    """The triangles of geo ((>= 9, n) float32 as the tracer holds them: v0, edge 1, edge 2),
    arranged for within() queries."""

    def __init__(self, geo):
        a = geo[0:3].T.astype(np.float64)
        b = a + geo[3:6].T
        c = a + geo[6:9].T
        lo = np.minimum(np.minimum(a, b), c)
        hi = np.maximum(np.maximum(a, b), c)
        width = hi[:, 0] - lo[:, 0]
        # the widest 0.1% (and any non-finite) are kept apart: every query reads them
        self.width = float(np.percentile(width, 99.9)) if len(width) else 0.0
        wide = ~(width <= self.width)
        order = np.flatnonzero(~wide)
        order = order[np.argsort(lo[order, 0], kind='stable')]
        self._lo_x = lo[order, 0]
        self._sorted = (a[order], b[order], c[order], lo[order], hi[order])
        self._wide = (a[wide], b[wide], c[wide], lo[wide], hi[wide])

    def within(self, center, radius) -> bool:
        if not radius > 0:
            return False
        c = np.asarray(center, np.float64)
        # a triangle narrower than self.width reaches x >= c.x - r only if its low x does
        # from self.width below it
        i = int(np.searchsorted(self._lo_x, c[0] - radius - self.width, side='left'))
        j = int(np.searchsorted(self._lo_x, c[0] + radius, side='right'))
        return (_within(c, radius, *(x[i:j] for x in self._sorted))
                or _within(c, radius, *self._wide))


def triangles_within(center, radius, geo) -> bool:
    """Whether any triangle of geo comes within radius of center (one query)."""
    return TriangleReach(geo).within(center, radius)


def _within(c, radius, a, b, cc, lo, hi) -> bool:
    if len(a) == 0:
        return False
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
