"""Independent float64 brute-force ray tracer: the oracle the native tracer is checked against.

Same semantics as `dacrt` (see README): closest hit with t in (0, tfar], exact ties go to the
lowest triangle index, occlusion means a hit with t in (0, tfar), u and v are the barycentric
weights of vertices 1 and 2, zero-area triangles are never hit. Every ray is intersected with
every triangle (Moller-Trumbore in float64 on the float32 inputs), vectorised over chunks of
rays x all triangles.

Because the tracer works in float32, a hit closer to a triangle edge than its rounding error
may legitimately go to the neighbouring triangle or be missed. So besides the strict answer the
reference reports, per ray, how close the hit is to an edge, the second-best t, and the closest
*robust* hit (one that no float32 implementation may miss); `agreement.py` uses those to tell
genuine ties and edge cases from wrong answers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# A hit whose point lies within EDGE_TOL * S of a triangle edge (S = magnitude of the coordinates
# involved, measured perpendicular to the ray) is an edge case; float32 tracers err by ~1e-7 * S.
EDGE_TOL = 1e-5
# t tolerance: 1e-5 relative, widened for grazing hits where t is ill-conditioned (1/cosine).
T_REL_TOL = 1e-5
T_ABS_ULPS = 16 * 2.0 ** -24

PAIRS_PER_CHUNK = 1 << 20  # rays x triangles evaluated per numpy pass (~100 MB of temporaries)
BLOCK = 256                # triangles per run of _Blocks
BLOCKED_TRIANGLES = 1 << 18   # meshes this large skip runs of triangles far from the rays


@dataclass
class Mesh:
    """Triangles in float64 with precomputed edges; degenerate ones flagged."""

    v0: np.ndarray  # (M,3)
    e1: np.ndarray  # v1 - v0
    e2: np.ndarray  # v2 - v0
    valid: np.ndarray  # (M,) bool: non-zero area
    vmax: np.ndarray  # (M,) max |coordinate| of the three vertices

    @staticmethod
    def from_arrays(vertices, triangles) -> "Mesh":
        vert = np.asarray(vertices, dtype=np.float32).astype(np.float64)
        tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
        p0, p1, p2 = vert[tri[:, 0]], vert[tri[:, 1]], vert[tri[:, 2]]
        e1, e2 = p1 - p0, p2 - p0
        area2 = np.linalg.norm(np.cross(e1, e2), axis=1)
        vmax = np.max(np.abs(np.stack([p0, p1, p2], axis=1)), axis=(1, 2)) if len(tri) else \
            np.zeros(0)
        return Mesh(p0, e1, e2, area2 > 0.0, vmax)

    def __len__(self) -> int:
        return len(self.v0)


@dataclass
class PairEval:
    """Ray/triangle quantities, broadcast over whatever shapes the inputs had."""

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    margin: np.ndarray  # signed distance (perpendicular to the ray) of the hit point to the
    #                     nearest edge line: >= 0 inside the triangle
    h1: np.ndarray  # projected height of vertex 1 over its opposite edge (for u tolerance)
    h2: np.ndarray  # same for vertex 2 (for v tolerance)
    cosine: np.ndarray  # |cos| between ray and triangle normal
    scale: np.ndarray  # coordinate magnitude S
    ok: np.ndarray  # non-degenerate triangle and ray not parallel to it

    def t_tol(self, dnorm):
        with np.errstate(divide="ignore", invalid="ignore"):
            return T_REL_TOL * np.abs(self.t) + T_ABS_ULPS * self.scale / (
                np.maximum(self.cosine, 1e-12) * dnorm)

    def edge_tol(self):
        return EDGE_TOL * self.scale


def _evaluate(o, d, omax, v0, e1, e2, valid, vmax) -> PairEval:
    """Moller-Trumbore plus edge distances; o, d: (...,3) broadcastable with v0, e1, e2."""
    ox, oy, oz = o[..., 0], o[..., 1], o[..., 2]
    dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
    ax, ay, az = e1[..., 0], e1[..., 1], e1[..., 2]
    bx, by, bz = e2[..., 0], e2[..., 1], e2[..., 2]
    px, py, pz = dy * bz - dz * by, dz * bx - dx * bz, dx * by - dy * bx  # p = d x e2
    det = ax * px + ay * py + az * pz
    sx, sy, sz = ox - v0[..., 0], oy - v0[..., 1], oz - v0[..., 2]
    uu = sx * px + sy * py + sz * pz
    qx, qy, qz = sy * az - sz * ay, sz * ax - sx * az, sx * ay - sy * ax  # q = s x e1
    vv = dx * qx + dy * qy + dz * qz
    tt = bx * qx + by * qy + bz * qz
    ok = (det != 0.0) & valid
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(ok, 1.0 / np.where(det == 0.0, 1.0, det), 0.0)
        u, v, t = uu * inv, vv * inv, tt * inv
        w = 1.0 - u - v
        dd = dx * dx + dy * dy + dz * dz
        dn = np.sqrt(dd)
        area2_proj = np.abs(det) / dn  # twice the triangle's area projected along the ray

        def proj_len(ex, ey, ez):
            ed = ex * dx + ey * dy + ez * dz
            return np.sqrt(np.maximum(ex * ex + ey * ey + ez * ez - ed * ed / dd, 0.0))

        l0 = proj_len(bx - ax, by - ay, bz - az)  # edge opposite vertex 0
        l1 = proj_len(bx, by, bz)  # opposite vertex 1
        l2 = proj_len(ax, ay, az)  # opposite vertex 2
        h0, h1, h2 = area2_proj / l0, area2_proj / l1, area2_proj / l2
        margin = np.minimum(np.minimum(w * h0, u * h1), v * h2)
        nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        cosine = np.abs(det) / (dn * np.sqrt(nx * nx + ny * ny + nz * nz))
    margin = np.where(ok, margin, -np.inf)
    t = np.where(ok, t, np.nan)
    return PairEval(t, u, v, margin, h1, h2, np.where(ok, cosine, 0.0), np.maximum(omax, vmax), ok)


@dataclass
class Reference:
    """Per-ray answer of the brute-force tracer (arrays of length N, indexed like the input)."""

    t: np.ndarray  # closest strict hit (inf on miss)
    prim: np.ndarray  # its triangle (-1 on miss); lowest index among exact ties
    u: np.ndarray
    v: np.ndarray
    bary_min: np.ndarray  # min(1-u-v, u, v) of that hit (nan on miss)
    margin: np.ndarray  # its distance to the nearest edge, perpendicular to the ray
    t2: np.ndarray  # second-best strict t over the other triangles (inf if none)
    robust_t: np.ndarray  # closest hit that is far from edges and from 0/tfar (inf if none)
    robust_t_tol: np.ndarray  # t tolerance of that hit
    occluded: np.ndarray  # strict: a hit with t in (0, tfar)
    occluded_robust: np.ndarray  # a robust hit exists before tfar: any tracer must report it
    occluded_possible: np.ndarray  # a hit within tolerances exists before tfar (+tol)

    @property
    def hit(self):
        return self.prim >= 0


def _first_per_ray(rays_sorted):
    """Positions of the first entry of each run of equal ray indices in a sorted array."""
    return np.flatnonzero(np.r_[True, rays_sorted[1:] != rays_sorted[:-1]]) if len(
        rays_sorted) else np.zeros(0, np.int64)


class _Blocks:
    """Runs of BLOCK consecutive triangles, each with a sphere holding every triangle's culling
    sphere (centre, radius). A run whose sphere the ray's line misses by more than the largest
    culling radius it could need holds no candidate of that ray, by the triangle inequality: its
    triangles are skipped before the dense cull, which then sees the same pairs, in the same
    order, as without the runs. Only for meshes of BLOCKED_TRIANGLES or more (stress sizes: the
    5M-triangle torus's 100 reference rays took 36 s CPU unblocked). A run with a non-finite
    centre or radius is always kept."""

    def __init__(self, centre, radius):
        m = len(centre)
        self.starts = np.arange(0, m, BLOCK)
        with np.errstate(invalid='ignore', over='ignore'):
            self.centre = np.add.reduceat(centre, self.starts, axis=0) / \
                np.diff(np.append(self.starts, m))[:, None]
            reach = np.linalg.norm(centre - np.repeat(self.centre, BLOCK, axis=0)[:m], axis=1) + radius
            self.radius = np.maximum.reduceat(reach, self.starts) * (1 + 1e-6)
        self.always = ~(np.isfinite(self.centre).all(axis=1) & np.isfinite(self.radius))
        self.m = m

    def near(self, o, dhat, pad):
        """Ascending indices of the triangles in runs whose sphere some ray of the chunk passes
        within the run's radius + that ray's pad (+ a 1e-6 relative margin for rounding)."""
        with np.errstate(invalid='ignore', over='ignore'):
            w = self.centre[None] - o[:, None]                               # (rays, runs, 3)
            across = np.linalg.norm(np.cross(w, dhat[:, None]), axis=2)
            slack = 1e-6 * (np.linalg.norm(w, axis=2) + self.radius + pad[:, None])
            keep = (across <= self.radius + pad[:, None] + slack).any(axis=0) | self.always
        idx = (self.starts[keep, None] + np.arange(BLOCK)).ravel()
        return idx[idx < self.m]


def trace(vertices, triangles, org, dirs, tfar) -> Reference:
    """Closest hit and occlusion of every ray against every triangle.

    Brute force in two passes per chunk of rays: a dense, deliberately generous bounding-sphere
    cull (the ray's line must pass within radius + 1e-4 * S of the triangle's centre, ten times
    the edge tolerance, inside the ray's [0, tfar] extent), then the exact float64 evaluation of
    the surviving pairs. Every pair that can be a strict, robust or tolerated hit survives."""
    mesh = Mesh.from_arrays(vertices, triangles)
    o = np.asarray(org, dtype=np.float32).astype(np.float64).reshape(-1, 3)
    d = np.asarray(dirs, dtype=np.float32).astype(np.float64).reshape(-1, 3)
    tf = np.broadcast_to(np.asarray(tfar, dtype=np.float32).astype(np.float64), (len(o),))
    n, m = len(o), len(mesh)
    out = dict(
        t=np.full(n, np.inf), prim=np.full(n, -1, np.int64), u=np.zeros(n), v=np.zeros(n),
        bary_min=np.full(n, np.nan), margin=np.full(n, np.nan), t2=np.full(n, np.inf),
        robust_t=np.full(n, np.inf), robust_t_tol=np.zeros(n), occluded=np.zeros(n, bool),
        occluded_robust=np.zeros(n, bool), occluded_possible=np.zeros(n, bool))
    if n == 0 or m == 0:
        return Reference(**out)
    omax = np.max(np.abs(o), axis=1)
    dnorm = np.linalg.norm(d, axis=1)
    dhat = d / dnorm[:, None]
    centre = mesh.v0 + (mesh.e1 + mesh.e2) / 3.0
    radius = np.max(np.linalg.norm(np.stack([mesh.v0, mesh.v0 + mesh.e1, mesh.v0 + mesh.e2], 1)
                                   - centre[:, None], axis=2), axis=1)
    pad = 10 * EDGE_TOL * np.maximum(omax, mesh.vmax.max())  # >= 10x any pair's edge tolerance
    reach = np.where(np.isfinite(tf), tf * dnorm, np.inf)
    chunk = max(1, PAIRS_PER_CHUNK // m)
    blocks = _Blocks(centre, radius) if m >= BLOCKED_TRIANGLES else None
    for a in range(0, n, chunk):
        r = slice(a, min(n, a + chunk))
        near = blocks.near(o[r], dhat[r], pad[r]) if blocks is not None else slice(None)
        cx, cy, cz = centre[near, 0], centre[near, 1], centre[near, 2]
        wx, wy, wz = cx - o[r, 0:1], cy - o[r, 1:2], cz - o[r, 2:3]
        hx, hy, hz = dhat[r, 0:1], dhat[r, 1:2], dhat[r, 2:3]
        along = wx * hx + wy * hy + wz * hz
        dist2 = (wy * hz - wz * hy) ** 2 + (wz * hx - wx * hz) ** 2 + (wx * hy - wy * hx) ** 2
        big = radius[near] + pad[r, None]
        cand = (dist2 <= big * big) & (along >= -big) & (along <= reach[r, None] + big)
        ri, mi = np.nonzero(cand)
        del wx, wy, wz, along, dist2, cand
        ri = ri + a
        if blocks is not None:
            mi = near[mi]          # ascending, so the pairs keep the unblocked order
        ev = _evaluate(o[ri], d[ri], omax[ri], mesh.v0[mi], mesh.e1[mi], mesh.e2[mi],
                       mesh.valid[mi], mesh.vmax[mi])
        tfr = tf[ri]
        inside = ev.ok & (ev.u >= 0) & (ev.v >= 0) & (1.0 - ev.u - ev.v >= 0)
        out["occluded"][ri[inside & (ev.t > 0) & (ev.t < tfr)]] = True

        # closest strict hit per ray, exact ties to the lowest triangle index; then second best
        sel = np.flatnonzero(inside & (ev.t > 0) & (ev.t <= tfr))
        s = sel[np.lexsort((mi[sel], ev.t[sel], ri[sel]))]
        first = _first_per_ray(ri[s])
        best = s[first]
        rb = ri[best]
        bu, bv = ev.u[best], ev.v[best]
        out["t"][rb], out["prim"][rb] = ev.t[best], mi[best]
        out["u"][rb], out["v"][rb] = bu, bv
        out["bary_min"][rb] = np.minimum(np.minimum(bu, bv), 1.0 - bu - bv)
        out["margin"][rb] = ev.margin[best]
        nxt = first + 1
        has2 = nxt < len(s)
        has2[has2] = ri[s[nxt[has2]]] == rb[has2]
        out["t2"][rb[has2]] = ev.t[s[nxt[has2]]]

        ttol = ev.t_tol(dnorm[ri])
        etol = ev.edge_tol()
        robust = np.flatnonzero((ev.margin >= etol) & (ev.t > ttol) & (ev.t <= tfr - ttol))
        s = robust[np.lexsort((ev.t[robust], ri[robust]))]
        best = s[_first_per_ray(ri[s])]
        out["robust_t"][ri[best]] = ev.t[best]
        out["robust_t_tol"][ri[best]] = ttol[best]
        out["occluded_robust"][ri[best]] = True
        loose = (ev.margin >= -etol) & (ev.t > -ttol) & (ev.t < tfr + ttol)
        out["occluded_possible"][ri[loose]] = True
    return Reference(**out)


def evaluate_pairs(vertices, triangles, org, dirs, prims) -> PairEval:
    """Reference quantities of ray i against triangle prims[i], for each i (vectorised)."""
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)[np.asarray(prims)]
    mesh = Mesh.from_arrays(vertices, tri)
    o = np.asarray(org, dtype=np.float32).astype(np.float64).reshape(-1, 3)
    d = np.asarray(dirs, dtype=np.float32).astype(np.float64).reshape(-1, 3)
    return _evaluate(o, d, np.max(np.abs(o), axis=1) if len(o) else np.zeros(0),
                     mesh.v0, mesh.e1, mesh.e2, mesh.valid, mesh.vmax)
