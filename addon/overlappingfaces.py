"""Faces overlapping in part in one plane: two triangles in the same plane (within float
tolerance) covering a common area of positive size without repeating each other corner for
corner (coincidentfaces.py says exact copies). A single Mirror modifier without merging on a
mesh not symmetric about the mirror plane lays such faces (the fuzzer's Mirror on a moved cube:
a region 2.6x Cycles, pixels to 6x), as do quads mirrored onto themselves split along the other
diagonal. They z-fight: which one a ray meets, and whether a ray leaving one meets the other,
depends on each tracer's order, so no image can agree with Cycles. Said, naming the objects.

Cheap, and never claimed where it is not so: triangles are keyed by their quantised plane (unit
normal up to sign, offset in bins of _ULPS float32 ulps of the largest coordinate; a quad's two
triangles listed one after the other as one key), only repeated keys kept (native
repeated_keys) and counted in buckets of the key (4 a triangle). A pair alone in its bucket
is tested directly; groups of up to _SMALL all pair by pair; larger groups (up to _MAX_GROUP) only where
their triangles' areas, projected into the plane, add up to more than the area of a rectangle
bounding them there, which must cover some point twice (the smallest of the rectangles along the
edges of one triangle; a Mirror's faces mostly fill theirs). Every pair is tested exactly in the
first one's plane: the other's corners within _PAIR_ULPS float32 ulps of the pair's own largest
coordinate of it (surfaces further apart are met in one order by both tracers), and separating
axes (the six edge normals), each overlap deeper than that. So faces overlapping within a plane
holding more than _MAX_GROUP triangles (a face laid on a finely split floor) or whose other faces
spread far around them are not found, nor a sliver thinner than the tolerance, nor a triangle
whose key falls in the bin next to its twin's: misses, never a false message. Faces facing
each other are not said: they are objects in contact (a box resting on a floor, two boxes
stacked), the overlap closed off between them and seen by no ray, a common sight."""
from __future__ import annotations

import numpy as np

import dacrt

_ULPS = 64              # the plane offset's bin: float32 ulps of the scene's largest coordinate
_PAIR_ULPS = 16         # one plane, and the overlap depth: float32 ulps of the pair's largest coordinate
_NORMAL_BINS = 4096     # per unit of each normal component (~2.4e-4 rad)
_SMALL = 16             # groups tested pair by pair without the area bound
_MAX_GROUP = 512        # larger plane groups are left (their buckets' counts)
_PARALLEL = 1.0 - 1e-6  # cos between the normals of a pair in one plane facing one way
# the sign that makes n and -n one key (odd in n; a normal nearly perpendicular to it may split
# a plane's triangles into two groups: a miss, never a false message)
_SIGN = np.array([0.5773502, 0.6172134, 0.5345225], np.float32)
_K = np.array([0x9E3779B97F4A7C15], np.uint64)


def overlapping(vertices, indices, geo, candidates):
    """Mask (M,) of the triangles of mask candidates that overlap another candidate in part in
    the same plane (geo: triangle_table's rows, v0 at 0:3 and the unit normal at 9:12)."""
    M = len(candidates)
    out = np.zeros(M, bool)
    S = np.flatnonzero(candidates)
    if len(S) < 2:
        return out
    v = np.asarray(vertices, np.float32)
    tol = float(_ULPS * np.spacing(np.float32(max(float(np.abs(v).max(initial=0.0)), 1e-30))))
    n = wound = np.asarray(geo[9:12], np.float32)
    n = n * np.where(_SIGN @ n < 0, np.float32(-1), np.float32(1))
    d = geo[0] * n[0] + geo[1] * n[1] + geo[2] * n[2]
    # the key, exact: each normal component in 14 bits, the offset in 22 (|d| / tol is below
    # sqrt(3) 2^24 / _ULPS: the tolerance is _ULPS ulps of the largest coordinate)
    half = np.float32(_NORMAL_BINS + 0.5)
    key = (n[0] * np.float32(_NORMAL_BINS) + half).astype(np.int64) << 50
    key |= (n[1] * np.float32(_NORMAL_BINS) + half).astype(np.int64) << 36
    key |= (n[2] * np.float32(_NORMAL_BINS) + half).astype(np.int64) << 22
    key |= (d * np.float32(1.0 / tol) + np.float32(2 ** 21 + 0.5)).astype(np.int64) & (2 ** 22 - 1)
    key = key.view(np.uint64)
    t = np.asarray(indices)
    # a quad's two triangles, listed one after the other (as Blender triangulates), count as one
    # key: a quad alone in its plane (most of a low-poly mesh) is then unique; its mate rejoins
    # its group below
    p = np.flatnonzero(candidates[:-1] & candidates[1:] & (key[:-1] == key[1:]))
    p = p[_quads(t, wound, p, p + 1)]
    p = p[~np.isin(p - 1, p)]               # (a fan's chain: every other pair)
    mate = np.full(M, -1, np.intp)
    mate[p] = p + 1
    listed = candidates.copy()
    listed[p + 1] = False
    S = np.flatnonzero(listed)
    S = S[dacrt.shading.repeated_keys(key[S])]       # (native hash table: most keys are unique)
    S = np.r_[S, mate[S][mate[S] >= 0]]
    key = key[S]
    bits = int(np.clip(np.ceil(np.log2(4 * len(S) + 1)), 10, 20))   # few distinct keys share a bucket
    bucket = ((key * _K[0]) >> np.uint64(64 - bits)).astype(np.intp)
    count = np.bincount(bucket, minlength=1 << bits)[bucket]
    c = _Corners(v, t)
    pi, pj = [], []
    # pairs alone in their bucket: the partner is the bucket's sum of members less itself
    two = np.flatnonzero(count == 2)
    if len(two):
        total = np.bincount(bucket[two], weights=two.astype(np.float64), minlength=1 << bits)
        other = (total[bucket[two]] - two).astype(np.intp)
        first = (two < other) & (key[two] == key[other])
        pi.append(S[two[first]]), pj.append(S[other[first]])
    few = np.flatnonzero((count > 2) & (count <= _MAX_GROUP))
    if len(few):
        by = few[np.argsort(key[few], kind='stable')]
        k = key[by]
        start = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
        size = np.diff(np.r_[start, len(by)])
        rows = S[by]
        for s in np.unique(size[size > 1]):
            g = start[size == s]
            if s > _SMALL:
                g = g[_bound_exceeded(c, rows, g, s, tol)]
            a, b = np.triu_indices(s, 1)
            pi.append(rows[(g[:, None] + a).ravel()]), pj.append(rows[(g[:, None] + b).ravel()])
    if pi:
        i, j = np.concatenate(pi), np.concatenate(pj)
        keep = ~_quads(t, wound, i, j)
        i, j = i[keep], j[keep]
        hit = _pairs_overlap(c[i], c[j])
        out[i[hit]] = out[j[hit]] = True
    return out


def _quads(t, wound, i, j):
    """Mask of the pairs of triangles i, j sharing an edge by index, run one way by one and the
    other way by the other, both facing one way (wound: the unit normals (3, M)): on either side
    of the edge in their plane, so never overlapping (a quad's two triangles, a fan's neighbours)."""
    a, b = [t[i, k] for k in range(3)], [t[j, k] for k in range(3)]
    quad = np.zeros(len(i), bool)
    for k in range(3):
        for m in range(3):
            quad |= (a[k] == b[(m + 1) % 3]) & (a[(k + 1) % 3] == b[m])
    quad[quad] &= (wound[:, i[quad]] * wound[:, j[quad]]).sum(axis=0) > 0
    return quad


class _Corners:
    """The float64 corners (..., 3, 3) of the triangles indexed, gathered only when asked."""

    def __init__(self, v, t):
        self.v, self.t = v, t

    def __getitem__(self, rows):
        return self.v[self.t[rows]].astype(np.float64)


def _frame(c):
    """(origin, u, w, n) of triangles c (P, 3, 3): their plane's frame along the first edge."""
    n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    u = c[:, 1] - c[:, 0]
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
    return c[:, 0], u, np.cross(n, u), n


def _bound_exceeded(c, rows, g, s, tol):
    """Mask of the groups starting at g (each s rows of rows) whose projected areas add up to more
    than the smallest rectangle along an edge of the first triangle bounding them in its plane."""
    tri = c[rows[g[:, None] + np.arange(s)].ravel()].reshape(len(g), s, 3, 3)
    box = np.inf
    for k in range(3):
        f = np.roll(tri[:, 0], -k, axis=1)
        o, u, w, n = _frame(f)
        rel = tri - o[:, None, None, :]
        p = np.stack([np.einsum('gtkd,gd->gtk', rel, u), np.einsum('gtkd,gd->gtk', rel, w)], axis=-1)
        box = np.minimum(box, np.prod(p.max(axis=(1, 2)) - p.min(axis=(1, 2)), axis=1))
    e1, e2 = p[:, :, 1] - p[:, :, 0], p[:, :, 2] - p[:, :, 0]
    total = 0.5 * np.abs(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]).sum(axis=1)
    return total > box * (1.0 + 1e-6) + tol * tol


def _pairs_overlap(a, b):
    """Mask (P,) of the pairs of triangles a, b (P, 3, 3) lying in one plane, facing one way (b's
    corners within _PAIR_ULPS float32 ulps of the pair's largest coordinate of a's plane, the
    winding normals alike) whose interiors overlap deeper than that along each of the six edge
    normals (separating axes: exact for two convex shapes). Surfaces further apart are met in one
    order by both tracers (a ray's float test errs by a few ulps of the coordinates)."""
    big = np.maximum(np.abs(a).max(axis=(1, 2)), np.abs(b).max(axis=(1, 2)))
    tol = _PAIR_ULPS * np.spacing(np.maximum(big, 1e-30).astype(np.float32)).astype(np.float64)
    o, u, w, n = _frame(a)
    nb = np.cross(b[:, 1] - b[:, 0], b[:, 2] - b[:, 0])
    nb /= np.maximum(np.linalg.norm(nb, axis=1, keepdims=True), 1e-300)
    flat = (np.abs(np.einsum('pkd,pd->pk', b - o[:, None], n)) <= tol[:, None]).all(axis=1)
    flat &= np.einsum('pd,pd->p', n, nb) >= _PARALLEL
    p = [np.stack([np.einsum('pkd,pd->pk', x - o[:, None], u), np.einsum('pkd,pd->pk', x - o[:, None], w)], axis=2)
         for x in (a, b)]
    axes = []
    for q in p:
        e = np.roll(q, -1, axis=1) - q
        ax = np.stack([-e[..., 1], e[..., 0]], axis=-1)
        axes.append(ax / np.maximum(np.linalg.norm(ax, axis=-1, keepdims=True), 1e-300))
    axes = np.concatenate(axes, axis=1)                                  # (P, 6, 2)
    pa, pb = (np.einsum('pad,pkd->pak', axes, q) for q in p)             # (P, 6, 3)
    depth = np.minimum(pa.max(axis=2), pb.max(axis=2)) - np.maximum(pa.min(axis=2), pb.min(axis=2))
    return flat & (depth > tol[:, None]).all(axis=1)


def overlapping_faces(sd, tri, mats) -> list:
    """The message (a list of 0 or 1 (level, text)) naming the objects whose non-emissive faces
    overlap other faces in part in one plane (sd: SceneData; tri: surfacetables.Triangles;
    mats: surfacetables.Materials). Exact copies count once (coincidentfaces.py says them);
    emitters are lights/overlap.py's; wholly clear faces render alike (a ray passes them all)."""
    from .coincidentfaces import exact_groups
    from .scenedata import VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW
    m = np.asarray(tri.material)
    clear = (mats.transparency.min(axis=0) >= 1.0) & ~np.isin(np.arange(len(mats.transparent)),
                                                              [e[0] for e in mats.opacity])
    # (a material built per ray kind or depth copies each triangle: counted as the user's)
    family = np.array([x.variant_of if x.variant_of >= 0 else i for i, x in enumerate(sd.materials)], np.int64)
    cand = (np.asarray(tri.area) > 0) & ((np.asarray(tri.visibility) & (VIS_CAMERA | VIS_DIFFUSE | VIS_SHADOW)) != 0)
    cand &= ~clear[m] & ~np.asarray(mats.emissive)[m] & (family[m] == m)
    if sd.geometry.one_sided is not None:       # a hair or Curves tube's own triangles
        cand &= ~np.asarray(sd.geometry.one_sided, bool)
    if tri.twins.any():                        # one of each exact set
        rows, group = exact_groups(tri.vertices, tri.indices, tri.twins & cand)
        if len(rows):
            order = np.argsort(rows)
            _, firsts = np.unique(group[order], return_index=True)
            drop = np.ones(len(rows), bool)
            drop[order[firsts]] = False
            cand[rows[drop]] = False
    said = overlapping(tri.vertices, tri.indices, tri.geo, cand)
    if not said.any():
        return []
    return [('INFO', f"{int(said.sum())} triangles of {sd.named_objects(said)} overlap other triangles in "
                     "part in the same plane, facing the same way (a Mirror modifier without merging on a "
                     "mesh not symmetric about its mirror plane, or faces laid over others): such faces "
                     "z-fight, which one a ray meets depends on each renderer's order, so where they are "
                     "seen DACRT's image can differ from Cycles'; delete the overlap or move the faces apart")]
