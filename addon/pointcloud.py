"""Point clouds as the spheres Cycles renders them as: each point (position, radius) becomes a
tessellated sphere the tracer can intersect, with smooth (exact radial) normals.

A polyhedron inscribed in the sphere would look smaller than it (an icosphere of 80 faces has
6% less surface); each template is scaled so its surface area is the sphere's 4 pi r^2, which by
Cauchy's formula makes its projected area, averaged over view directions, the sphere's pi r^2:
the light a point cloud catches and the pixels it covers agree with Cycles' exact spheres on
average. The subdivision drops as points grow in number so the frame's triangle count stays
bounded (LEVELS). Plain numpy; the export layer (export/strands.py) reads the Blender data.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

# (most points, icosphere subdivision level): 1280 triangles a sphere for a few points, down to
# the 20-face icosahedron beyond 50K points; a cloud costs at most ~4M triangles up to 200K points
# (then 20 a point)
LEVELS = ((3_000, 3), (12_000, 2), (50_000, 1))
# every level from the finest down: below level_for's floor only when the frame would not fit in
# memory (export/budget.py); -1 is the octahedron (8 triangles)
LADDER = (3, 2, 1, 0, -1)
DEFAULT_RADIUS = 0.01      # Cycles' radius for a point cloud without a 'radius' attribute


def level_for(n: int) -> int:
    for most, level in LEVELS:
        if n <= most:
            return level
    return 0


@lru_cache(maxsize=None)
def unit_sphere(level: int):
    """(vertices (v, 3) on the unit sphere, triangles (t, 3) wound outward, area scale): an
    icosphere of `level` subdivisions (-1: the octahedron) and the factor that gives it the unit
    sphere's area."""
    if level < 0:
        v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64)
        t = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
                     np.int32)
        return v, t, float(np.sqrt(4.0 * np.pi / (8 * 0.5 * np.sqrt(3.0))))
    p = (1.0 + 5.0 ** 0.5) / 2.0
    v = np.array([[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0], [0, -1, p], [0, 1, p],
                  [0, -1, -p], [0, 1, -p], [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], np.float64)
    t = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], np.int64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(level):
        # split every edge at its midpoint (shared edges once), four triangles per triangle
        edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(v) + inv.reshape(3, len(t)).T          # midpoints of edges 01, 12, 20
        v = np.concatenate([v, mid])
        t = np.concatenate([np.stack([t[:, 0], m[:, 0], m[:, 2]], 1), np.stack([m[:, 0], t[:, 1], m[:, 1]], 1),
                            np.stack([m[:, 2], m[:, 1], t[:, 2]], 1), m])
    e1, e2 = v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1).sum()
    return v, t.astype(np.int32), float(np.sqrt(4.0 * np.pi / area))


def triangle_count(radii, level: int) -> int:
    """The triangles spheres() makes of points of these radii at `level`."""
    return int(np.count_nonzero(np.asarray(radii) > 0)) * len(unit_sphere(level)[1])


def spheres(positions, radii, level: int | None = None):
    """Sphere meshes of the points with radius > 0 (and finite): (vertices (n*v, 3) float32,
    triangles (n*t, 3) int32, vertex normals (n*v, 3) float32, points kept). Points of radius 0
    or less are not rendered (Cycles gives them no extent)."""
    positions = np.asarray(positions, np.float64).reshape(-1, 3)
    radii = np.asarray(radii, np.float64).reshape(-1)
    keep = np.flatnonzero(radii > 0)              # NaN compares False: dropped too
    pos, rad = positions[keep], radii[keep]
    n = len(pos)
    v, t, scale = unit_sphere(level_for(n) if level is None else level)
    vertices = (pos[:, None, :] + (rad * scale)[:, None, None] * v[None]).reshape(-1, 3).astype(np.float32)
    triangles = (t[None] + (np.arange(n, dtype=np.int32) * len(v))[:, None, None]).reshape(-1, 3)
    normals = np.broadcast_to(v.astype(np.float32)[None], (n, len(v), 3)).reshape(-1, 3)
    return vertices, triangles, np.ascontiguousarray(normals), len(keep)
