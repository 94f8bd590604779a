"""Emitters overlapping in their plane: two light-sampled emissive triangles covering the same
area of one plane without repeating each other corner for corner (a quad's twin turned 90 degrees
splits along the other diagonal; a panel laid over part of another). BSDF rays meet one of them,
light samples pick both, so next-event estimation adds their emission twice where hits count it
once (the turned twin: 1.82x Cycles, which renders it darker, its shadow rays to one copy stopped
by the other). coincident.py's near_copies finds only triangles that repeat each other.

Found with the tracer: a few points well inside each emitter triangle, each probed by a ray
along the triangle's normal through a thin slab around its plane, skipping the triangle itself;
a hit on a parallel emitter inside the slab is an overlap. Edge neighbours (a mesh's own faces)
are never hit: the points lie away from every edge. So copies and overlaps covering one of a
triangle's points are found; a sliver of overlap along an edge is not (nor said)."""
from __future__ import annotations

import numpy as np

import dacrt

_MAX = 50_000              # emitter triangles looked at (8 rays each; 50K: 0.12 s)
_ULPS = 16                 # the plane's slab: float32 ulps of the emitters' largest coordinate
# probe points (barycentric): the centroid lies on a square's other diagonal, the others do not
_PROBES = np.array([[1 / 3, 1 / 3, 1 / 3], [0.6, 0.2, 0.2], [0.2, 0.6, 0.2], [0.2, 0.2, 0.6]])
_PARALLEL = 1.0 - 1e-5     # |cos| between normals of triangles in one plane


def coplanar_overlaps(vertices, indices, emitters):
    """(mask, tol): the emitters (bool (M,)) whose inside another emitter covers in the same plane
    (within tol: _ULPS float32 ulps of the emitters' largest coordinate), both marked; (None, tol)
    where there are none, or too many emitters to look (_MAX). Exact copies are found too (the
    caller has dropped those it renders as one surface); triangles too thin to hold a point tol
    away from their edges are only found as the coverers of others."""
    E = np.flatnonzero(emitters)
    if not 2 <= len(E) <= _MAX:
        return None, 0.0
    c32 = np.asarray(vertices, np.float32)[np.asarray(indices)[E]]          # (E, 3, 3)
    tol = float(_ULPS * np.spacing(np.float32(max(float(np.abs(c32).max()), 1e-30))))
    c = c32.astype(np.float64)
    cross = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    twice_area = np.linalg.norm(cross, axis=1)
    ok = twice_area > 0
    n = np.zeros_like(cross)
    n[ok] = cross[ok] / twice_area[ok, None]
    longest = np.max([np.linalg.norm(c[:, (i + 1) % 3] - c[:, i], axis=1) for i in range(3)], axis=0)
    # the probes' distance from the edges: at least 0.2 of the smallest height
    h = 8.0 * tol
    probed = np.flatnonzero(ok & (0.2 * twice_area > 4.0 * h * np.maximum(longest, 1e-300)))
    if not len(probed):
        return None, tol
    pts = np.einsum('pk,tkd->tpd', _PROBES, c[probed]).reshape(-1, 3)       # (T * 4, 3)
    normal = np.repeat(n[probed], len(_PROBES), axis=0)
    own = np.repeat(probed, len(_PROBES))
    scene = dacrt.Scene(c32.reshape(-1, 3), np.arange(3 * len(E), dtype=np.int32).reshape(-1, 3))
    found = np.zeros(len(E), bool)
    for side in (1.0, -1.0):       # from both sides: the nearer of two copies a slab apart hides the other
        rays = dacrt.make_rays(pts + side * h * normal, -side * normal, 2.0 * h)
        hits = scene.intersect(rays, skip=own.astype(np.int32))
        other = hits['prim']
        hit = (other >= 0) & (np.abs(hits['t'] - h) <= tol)
        hit[hit] &= np.abs(np.einsum('ij,ij->i', n[other[hit]], normal[hit])) >= _PARALLEL
        found[own[hit]] = found[other[hit]] = True
    if not found.any():
        return None, tol
    mask = np.zeros(len(emitters), bool)
    mask[E[found]] = True
    return mask, tol
