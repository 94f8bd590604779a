"""Faces overlapping in part in one plane: two triangles in the same plane (within float
tolerance) covering a common area of positive size without repeating each other corner for
corner (coincidentfaces.py says exact copies). A single Mirror modifier without merging on a
mesh not symmetric about the mirror plane lays such faces (the fuzzer's Mirror on a moved cube:
a region 2.6x Cycles, pixels to 6x), as do quads mirrored onto themselves split along the other
diagonal. They z-fight: which one a ray meets, and whether a ray leaving one meets the other,
depends on each tracer's order, so no image can agree with Cycles. Said, naming the objects.

Cheap, and never claimed where it is not so: triangles are keyed by their quantised plane (unit
normal up to sign, offset in bins of _ULPS float32 ulps of the largest coordinate, plane_step;
written by the table's own pass, dacrt.shading.triangle_table's plane_keys) and grouped natively
where keys repeat, a quad's two triangles listed one after the other as one key
(dacrt.shading.coplanar_groups: threaded passes over the keys). Groups of up to _SMALL are
tested pair by pair; larger groups (up to _BIG) only
where their triangles' areas, projected into the plane, add up to more than the area of a
rectangle bounding them there, which must cover some point twice (the smallest of the rectangles
along the edges of one triangle; a Mirror's faces mostly fill theirs), and above _MAX_GROUP only
their pairs whose bounding boxes meet (a Screw of a flat profile about its normal: 1440 triangles
in one plane, pixels 2.5-3.2x Cycles); groups under the bound, in their pairs of separate pieces
whose boxes overlap (_sparse_pairs: a text instanced on points in one plane, pixels
1.3-1.7x). Every pair is tested exactly in the first one's plane: the other's corners within
_PAIR_ULPS float32 ulps of the pair's own largest coordinate of it (surfaces further apart are
met in one order by both tracers), and separating axes (the six edge normals), each overlap
deeper than that. So faces overlapping within a plane
holding more than _BIG triangles (a face laid on a finely split floor), faces of one piece
(joined by corners) in a plane their areas do not fill, nor a sliver thinner than the tolerance, nor twins
whose plane offsets lie more than half a bin apart across a bin's edge (float32 normals of thin
triangles: those within half a bin are keyed together by a second grid shifted by half a bin,
dacrt.shading.shifted_plane_keys): misses, never a false message. Faces facing
each other are not said: they are objects in contact (a box resting on a floor, two boxes
stacked), the overlap closed off between them and seen by no ray, a common sight; unless the
pair shares an edge by index: a face folded back over it (Triangulate's fixed split of a concave
quad along its outer diagonal: pixels 1.35-2.35x Cycles), never contact."""
from __future__ import annotations

import numpy as np

import dacrt

_ULPS = 64              # the plane offset's bin: float32 ulps of the scene's largest coordinate
_PAIR_ULPS = 16         # one plane, and the overlap depth: float32 ulps of the pair's largest coordinate
_SMALL = 16             # groups tested pair by pair without the area bound
_MAX_GROUP = 512        # larger plane groups: only their pairs whose bounding boxes meet
_BIG = 4096             # larger plane groups are left (a finely split floor)
_CHUNK = 1 << 16        # pairs tested at once
_NEAREST = 4            # a big group's first pairs: each triangle's nearest by box centre
_BUDGET = 1 << 17       # a big group's further pairs tested at most
_PARALLEL = 1.0 - 1e-6  # cos between the normals of a pair in one plane facing one way


def plane_step(vertices) -> float:
    """The plane keys' offset bin: _ULPS float32 ulps of the largest |coordinate| of vertices
    (triangle_table's plane_inv_step is its float32 inverse)."""
    v = np.asarray(vertices, np.float32)
    big = max(float(v.max(initial=0.0)), -float(v.min(initial=0.0)), 1e-30)    # (no |v| temporary)
    return float(_ULPS * np.spacing(np.float32(big)))


def overlapping(vertices, indices, geo, keys, step, candidates):
    """Mask (M,) of the triangles of mask candidates that overlap another candidate in part in
    the same plane (geo: triangle_table's rows, v0 at 0:3 and the unit normal at 9:12; keys its
    plane_keys, written with plane_inv_step float32(1 / step), step = plane_step(vertices))."""
    M = len(candidates)
    out = np.zeros(M, bool)
    if np.count_nonzero(candidates) < 2:
        return out
    v = np.asarray(vertices, np.float32)
    t = np.asarray(indices)
    c = _Corners(v, t)
    _found_in_groups(c, t, geo, keys, candidates, step, out)
    # twins whose keys fall on either side of a bin's edge (float32 rounding of thin triangles'
    # normals moves their offsets: 14 of 288 triangles of a ring copied in a tilted plane) share
    # a key of the grid shifted by half a bin (only its groups that join triangles of different
    # first keys: the others were tested whole); keyed natively in one threaded pass (a numpy
    # twin of the expressions had cost ~4 ms a dragon frame)
    shifted = dacrt.shading.shifted_plane_keys(geo, candidates, np.float32(1.0) / np.float32(step))
    _found_in_groups(c, t, geo, shifted, candidates & (shifted != 0), step, out, first=keys)
    return out


def _found_in_groups(c, t, geo, keys, candidates, step, out, first=None):
    """Marks in out the candidates overlapping another of their plane key's group (first: keys
    of an earlier pass; only groups joining triangles of different first keys are tested)."""
    # natively, in one threaded pass: a quad's two triangles as one, the groups of repeated keys
    # (most meshes have none, or one plane too large to test)
    rows, start = dacrt.shading.coplanar_groups(keys, geo, t, candidates, _BIG)
    if not len(rows):
        return
    size = np.diff(start)
    if first is not None:
        k = np.take(first, rows)
        mixed = np.minimum.reduceat(k, start[:-1]) != np.maximum.reduceat(k, start[:-1])
        if not mixed.any():
            return
        rows = rows[np.repeat(mixed, size)]
        size = size[mixed]
        start = np.concatenate([[0], np.cumsum(size)])
    start = start[:-1]
    pi, pj = [], []
    sparse = []         # (starts of the groups under the area bound, their size), per size
    # (the area bound of every group above _SMALL in one set of passes)
    tested = size > _SMALL
    bound = np.zeros(len(size), bool)
    if tested.any():
        bound[tested] = _bound_exceeded(c, rows, start[tested], size[tested], step)
    for s in np.unique(size):
        g = start[size == s]
        if s > _SMALL:
            over = bound[size == s]
            sparse.append((g[~over], s))
            g = g[over]
        if s > _MAX_GROUP:
            for g0 in g:
                _big_group(c, t, geo, rows[g0:g0 + s], out)
            continue
        a, b = np.triu_indices(s, 1)
        pi.append(rows[(g[:, None] + a).ravel()]), pj.append(rows[(g[:, None] + b).ravel()])
    # the sparse groups' pairs, all groups at once (one group at a time, bmw27's ~700 such groups
    # had cost ~0.5 s of CPU a frame in numpy calls on a few dozen triangles each); tested with
    # the rest below (a group's triangles are in no other group of this pass, so what _big_group
    # reads of out is not changed by testing them later)
    if sparse:
        g = np.concatenate([g for g, _ in sparse])
        n = np.concatenate([np.full(len(g), s, np.int64) for g, s in sparse])
        if len(g):
            a, b = _sparse_pairs(c, t, rows, g, n)
            pi.append(a), pj.append(b)
    if not pi:
        return
    i, j = np.concatenate(pi), np.concatenate(pj)
    _test(c, t, geo, i, j, out)


def _test(c, t, geo, i, j, out):
    """Marks in out the triangles of the pairs i, j (quads' pairs left) lying in one plane, facing
    one way or, where they fold over an edge they share (_folds), opposite ways (the second's
    corners within _PAIR_ULPS float32 ulps of the pair's largest coordinate of the first's plane,
    the winding normals alike or opposite) whose interiors overlap deeper than that along each of
    the six edge normals (separating axes: exact for two convex shapes). Surfaces further apart
    are met in one order by both tracers (a ray's float test errs by a few ulps of the
    coordinates)."""
    keep = ~_quads(t, np.asarray(geo[9:12]), i, j)
    i, j = i[keep], j[keep]
    if not len(i):
        return
    # each triangle's corners, box and largest |coordinate| once (a small group's triangle is in
    # up to 15 pairs; bmw27's 208K pairs gathered and reduced their corners pair by pair)
    if 16 * len(i) < len(t):   # (few pairs among many triangles: no arrays of the triangles' size)
        tri, at = np.unique(np.r_[i, j], return_inverse=True)
        i, j = at[:len(i)], at[len(i):]
    else:
        mark = np.zeros(len(t), bool)
        mark[i] = mark[j] = True
        tri = np.flatnonzero(mark)
        slot = np.empty(len(t), np.int64)
        slot[tri] = np.arange(len(tri))
        i, j = slot[i], slot[j]
    corners = c[tri]
    # (min and max over the short axes as chains of np.minimum / np.maximum: the same values,
    # numpy's reductions over an axis of 3 had been ~5x slower)
    lo, hi = _chain(np.minimum, corners, 1), _chain(np.maximum, corners, 1)
    big = _chain(np.maximum, np.abs(corners).reshape(len(tri), 9), 1)
    for k in range(0, len(i), _CHUNK):         # (a big group's pairs: bounded memory)
        a, b = i[k:k + _CHUNK], j[k:k + _CHUNK]
        tol = _PAIR_ULPS * np.spacing(np.maximum(np.maximum(big[a], big[b]), 1e-30).astype(np.float32)).astype(np.float64)
        # (boxes first: a pair that overlaps has a point of one within tol of a point of the
        # other, so their bounding boxes come within tol on every axis; 2 tol leaves room for
        # rounding. A 1M-triangle wave frame's 625 pairs left after _quads: 63 near)
        near = ((lo[b] <= hi[a] + 2 * tol[:, None]) & (lo[a] <= hi[b] + 2 * tol[:, None])).all(axis=1)
        if not near.any():
            continue
        a, b, tol = a[near], b[near], tol[near]
        hit = _overlap_in_plane(corners[a], corners[b], tol, _folds(t, tri[a], tri[b]))
        out[tri[a[hit]]] = out[tri[b[hit]]] = True


def _big_group(c, t, geo, rows, out):
    """Marks in out the triangles rows of a group above _MAX_GROUP overlapping another of it: of
    the pairs whose bounding boxes come within twice the pair's tolerance on every axis (_test's
    own box test), first each triangle's _NEAREST with the closest box centres (a Screw's steps:
    each overlaps the next, all found there), then those with a triangle not found yet, at most
    _BUDGET pairs (a floor with a rug on it: a few neighbours each). Past the budget, triangles
    are left unsaid: the count said is then a lower bound, still true."""
    tri = c[rows]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    # each triangle's margin, twice the pair tolerance of its own largest coordinate, a pair's
    # the larger of its two (as in _sparse_pairs): one of the whole group's had let a far face
    # in the plane's offset bin set it (a floor with a rug by the origin, a doubled ground 1e6
    # away: a 4 m margin made every pair of the floor near, the budget went on the first rows
    # and 24 of the 32 triangles under the rug were left unsaid)
    own = np.maximum(np.abs(tri).max(axis=(1, 2)), 1e-30)
    m = 2 * _PAIR_ULPS * np.spacing(own.astype(np.float32)).astype(np.float64)
    near = np.ones((len(tri), len(tri)), bool)
    for d in range(3):      # (lo_j <= hi_i + max(m_i, m_j) and its mirror, with no (n, n) floats)
        near &= (lo[None, :, d] <= hi[:, None, d] + m[:, None]) | (lo[None, :, d] - m[None, :] <= hi[:, None, d])
        near &= (lo[:, None, d] <= hi[None, :, d] + m[None, :]) | (lo[:, None, d] - m[:, None] <= hi[None, :, d])
    np.fill_diagonal(near, False)
    mid = (0.5 * (lo + hi)).astype(np.float32)
    dist = np.zeros(near.shape, np.float32)
    for d in range(3):
        dist += np.square(mid[:, None, d] - mid[None, :, d])
    dist[~near] = np.inf
    k = min(_NEAREST, len(tri) - 1)
    b = np.argpartition(dist, k - 1, axis=1)[:, :k]
    a = np.repeat(np.arange(len(tri)), k)
    b = b.ravel()
    first = near[a, b]
    pair = np.unique(np.sort(np.c_[a[first], b[first]], axis=1), axis=0)
    _test(c, t, geo, rows[pair[:, 0]], rows[pair[:, 1]], out)
    near[pair[:, 0], pair[:, 1]] = False
    a, b = np.nonzero(np.triu(near, 1))
    rest = ~(out[rows[a]] & out[rows[b]])
    a, b = a[rest][:_BUDGET], b[rest][:_BUDGET]
    _test(c, t, geo, rows[a], rows[b], out)


def _sparse_pairs(c, t, rows, starts, sizes):
    """The pairs (i, j) to test of the groups under the area bound (group k: rows[starts[k]:
    starts[k] + sizes[k]]): copies of a sparse shape laid over each other (a text's letters
    instanced on points in one plane leave most of the rectangle bounding them empty). Per group,
    the pairs whose bounding boxes overlap deeper than a margin (twice the pair tolerance of
    the larger of their two triangles' largest coordinates) along the two axes the group spreads
    most, and come within it along the third, found by sweeping along the axis it spreads most
    (no pair matrix: a 4000-triangle floor's ~6 neighbours each), nearest box centres first, at
    most _BUDGET pairs (beyond, a lower bound: still true). All groups in one set of numpy
    passes, each group's pairs as if it were swept alone."""
    G = len(starts)
    gid = np.repeat(np.arange(G), sizes)                                 # each row's group
    sel = np.repeat(starts - (np.cumsum(sizes) - sizes), sizes) + np.arange(int(sizes.sum()))
    r = rows[sel]
    first = np.cumsum(sizes) - sizes                                     # each group's first row in r
    # only pairs of separate pieces (joined by no corner index within the group): a piece's own
    # faces are its mesh's neighbours, whose folds the area bound and _folds are for; a plane of
    # one piece (a split floor, a fan of 1500 slivers all sharing the centre: ~500K pairs) costs
    # nothing here. Corners are keyed by (group, vertex): pieces never join across groups
    corner = gid[:, None].astype(np.int64) * len(c.v) + t[r]
    verts, local = np.unique(corner, return_inverse=True)
    local = local.reshape(-1, 3).astype(np.int32)
    piece = dacrt.shading.island_roots(len(verts), np.r_[local[:, :2], local[:, 1:]])[local[:, 0]]
    several = np.minimum.reduceat(piece, first) != np.maximum.reduceat(piece, first)
    keep = several[gid]
    if not keep.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    if not keep.all():
        sizes, r, piece = sizes[several], r[keep], piece[keep]
        G = len(sizes)
        gid = np.repeat(np.arange(G), sizes)
        first = np.cumsum(sizes) - sizes
    tri = c[r]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    # each triangle's margin, twice the pair tolerance of its own largest coordinate, a pair's
    # the larger of its two: one of the whole group's had let a far face in the plane's offset
    # bin set it (text laid over itself by the origin, a floor 1e6 away: a 2 m margin, every
    # overlap of the letters left unsaid)
    own = np.maximum(np.abs(tri).max(axis=(1, 2)), 1e-30)
    margin = 2 * _PAIR_ULPS * np.spacing(own.astype(np.float32)).astype(np.float64)
    spread = np.argsort(np.maximum.reduceat(hi, first) - np.minimum.reduceat(lo, first), axis=1)[:, ::-1]
    ax = spread[:, 0]
    key = lo[np.arange(len(r)), ax[gid]]
    order = np.lexsort((key, gid))                                       # per group, stable by lo
    los = key[order]
    # for each triangle (in sweep order), the later ones of its group whose box starts before its
    # own ends (by its own margin: a pair's is not smaller, so none is missed; the depth test
    # below takes the pair's): searchsorted(los of the group, hi - margin, 'left'), for all
    # groups in one sort (queries before equal boxes: those do not count)
    og = gid[order]
    query = hi[order, ax[og]] - margin[order]
    n = len(order)
    merged = np.lexsort((np.r_[np.ones(n, np.int8), np.zeros(n, np.int8)], np.r_[los, query], np.r_[og, og]))
    is_query = merged >= n
    below = np.cumsum(~is_query) - ~is_query                             # boxes before each entry
    end = np.empty(n, np.int64)
    end[merged[is_query] - n] = below[is_query]
    count = np.maximum(end - np.arange(n) - 1, 0)                        # (a box thinner than the margin: none)
    # (long slivers: every box over every other; bounded memory)
    total = np.bincount(og, weights=count, minlength=G)
    capped = total > 8 * _BUDGET
    if capped.any():
        count = np.where(capped[og], np.minimum(count, 8 * _BUDGET // sizes[og]), count)
    # the candidate pairs made and box-tested a slice of sweep rows at a time, each slice's at
    # most 8 _BUDGET (one group's cap: many capped groups at once had needed that many times
    # the memory), bmw27's ~700 small groups in one slice
    cum = np.cumsum(count)
    keep_a, keep_b, keep_g = [], [], []
    start = 0
    while start < n:
        stop = max(int(np.searchsorted(cum, (cum[start - 1] if start else 0) + 8 * _BUDGET, side='right')), start + 1)
        cnt = count[start:stop]
        a = np.repeat(np.arange(start, stop), cnt)
        b = a + 1 + (np.arange(len(a)) - np.repeat(np.cumsum(cnt) - cnt, cnt))
        pg = og[a]
        a, b = order[a], order[b]
        # boxes overlapping deeper than the margin along the two axes the plane spreads along
        # (boxes only touching, as a grid's neighbours' do, leave at most an overlap too thin to
        # z-fight visibly: left, as everywhere here, rather than tested pair by pair)
        near = piece[a] != piece[b]
        m = np.maximum(margin[a], margin[b])
        for k in range(3):
            d = spread[pg, k]
            depth = np.minimum(hi[a, d], hi[b, d]) - np.maximum(lo[a, d], lo[b, d])
            near &= depth > m if k < 2 else depth >= -m
        keep_a.append(a[near]), keep_b.append(b[near]), keep_g.append(pg[near])
        start = stop
    a, b, pg = np.concatenate(keep_a), np.concatenate(keep_b), np.concatenate(keep_g)
    many = np.flatnonzero(np.bincount(pg, minlength=G) > _BUDGET)
    if len(many):
        mid = 0.5 * (lo + hi)
        drop = np.zeros(len(a), bool)
        for g in many.tolist():                 # (rare: the nearest box centres first)
            at = np.flatnonzero(pg == g)
            ga, gb = a[at], b[at]
            drop[at[np.argsort(np.square(mid[ga] - mid[gb]).sum(axis=1), kind='stable')[_BUDGET:]]] = True
        a, b = a[~drop], b[~drop]
    return r[a], r[b]


def _folds(t, i, j):
    """Mask of the pairs of triangles i, j sharing exactly two corners by index (an edge of one
    mesh): facing opposite ways and overlapping, such a pair is a face folded back over the edge
    (Triangulate's fixed split of a concave quad), never two objects in contact."""
    a, b = t[i], t[j]
    return (a[:, :, None] == b[:, None, :]).any(axis=2).sum(axis=1) == 2


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


def _bound_exceeded(c, rows, starts, sizes, tol):
    """Mask of the groups (group k: rows[starts[k]:starts[k] + sizes[k]]) whose projected areas
    add up to more than the smallest rectangle along an edge of the first triangle bounding them
    in its plane."""
    total, box = _areas_and_box(c, rows, starts, sizes)
    return total > box * (1.0 + 1e-6) + tol * tol


def _areas_and_box(c, rows, starts, sizes):
    """(total, box) per group: its triangles' areas projected into the first one's plane, added,
    and the smallest rectangle bounding them there along an edge of that triangle. All groups at
    once (one size at a time, bmw27's 157 sizes had cost ~0.15 s of CPU a frame), each group's
    numbers as computed for it alone: per triangle the same operations, and the areas summed per
    size as (groups, size) rows (numpy's pairwise sum; np.add.reduceat adds in another order)."""
    G = len(starts)
    first = np.cumsum(sizes) - sizes
    gid = np.repeat(np.arange(G), sizes)
    tri = c[rows[np.repeat(starts - first, sizes) + np.arange(len(gid))]]
    box = np.inf
    for k in range(3):
        f = np.roll(tri[first], -k, axis=1)
        o, u, w, n = _frame(f)
        rel = tri - o[gid][:, None, :]
        p = np.stack([np.einsum('tkd,td->tk', rel, u[gid]), np.einsum('tkd,td->tk', rel, w[gid])], axis=-1)
        hi = np.maximum.reduceat(_chain(np.maximum, p, 1), first)
        lo = np.minimum.reduceat(_chain(np.minimum, p, 1), first)
        box = np.minimum(box, np.prod(hi - lo, axis=1))
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = np.abs(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0])
    total = np.empty(G)
    for s in np.unique(sizes).tolist():
        k = np.flatnonzero(sizes == s)
        total[k] = 0.5 * area[first[k][:, None] + np.arange(s)].sum(axis=1)
    return total, box


def _chain(ufunc, x, axis):
    """ufunc.reduce(x, axis) (np.minimum: x.min(axis), the same values, NaN too) as a chain of
    ufunc over the axis' slices: numpy's reduction over a short axis is several times slower."""
    x = np.moveaxis(x, axis, 0)
    out = ufunc(x[0], x[1])
    for k in range(2, len(x)):
        ufunc(out, x[k], out=out)
    return out


def _overlap_in_plane(a, b, tol, folds):
    """_test's test of pairs a, b (P, 3, 3), tol (P,) their tolerance (folds: the pairs
    that may face opposite ways)."""
    o, u, w, n = _frame(a)
    nb = np.cross(b[:, 1] - b[:, 0], b[:, 2] - b[:, 0])
    nb /= np.maximum(np.linalg.norm(nb, axis=1, keepdims=True), 1e-300)
    flat = (np.abs(np.einsum('pkd,pd->pk', b - o[:, None], n)) <= tol[:, None]).all(axis=1)
    cos = np.einsum('pd,pd->p', n, nb)
    flat &= (cos >= _PARALLEL) | (folds & (cos <= -_PARALLEL))
    if not flat.all():      # (the rest for the pairs in one plane only; each pair's own numbers)
        if not flat.any():
            return flat
        a, b, tol, o, u, w = a[flat], b[flat], tol[flat], o[flat], u[flat], w[flat]
    p = [np.stack([np.einsum('pkd,pd->pk', x - o[:, None], u), np.einsum('pkd,pd->pk', x - o[:, None], w)], axis=2)
         for x in (a, b)]
    axes = []
    for q in p:
        e = np.roll(q, -1, axis=1) - q
        ax = np.stack([-e[..., 1], e[..., 0]], axis=-1)
        axes.append(ax / np.maximum(np.linalg.norm(ax, axis=-1, keepdims=True), 1e-300))
    axes = np.concatenate(axes, axis=1)                                  # (P, 6, 2)
    pa, pb = (np.einsum('pad,pkd->pak', axes, q) for q in p)             # (P, 6, 3)
    depth = np.minimum(_chain(np.maximum, pa, 2), _chain(np.maximum, pb, 2)) - \
        np.maximum(_chain(np.minimum, pa, 2), _chain(np.minimum, pb, 2))
    flat[flat] = (depth > tol[:, None]).all(axis=1)
    return flat


def overlapping_faces(sd, tri, mats) -> list:
    """The message (a list of 0 or 1 (level, text)) naming the objects whose non-emissive faces
    overlap other faces in part in one plane (sd: SceneData; tri: surfacetables.Triangles;
    mats: surfacetables.Materials). Exact copies count once (coincidentfaces.py says them);
    emitters are lights/overlap.py's; wholly clear faces render alike (a ray passes them all)."""
    from .coincidentfaces import exact_groups, material_family, wholly_clear
    from .scenedata import VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW
    m = np.asarray(tri.material)
    clear = wholly_clear(mats)
    # (a material built per ray kind or depth copies each triangle: counted as the user's)
    family = material_family(sd)
    cand = (np.asarray(tri.area) > 0) & ((np.asarray(tri.visibility) & (VIS_CAMERA | VIS_DIFFUSE | VIS_SHADOW)) != 0)
    # (per material first, then one gather over the triangles)
    cand &= (~clear & ~np.asarray(mats.emissive, bool) & (family == np.arange(len(family))))[m]
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
    said = overlapping(tri.vertices, tri.indices, tri.geo, tri.plane_keys, tri.plane_step, cand)
    tri.plane_keys = None       # (8 bytes a triangle, read only here)
    if not said.any():
        return []
    return [('INFO', f"{int(said.sum())} triangles of {sd.named_objects(said)} overlap other triangles in "
                     "part in the same plane, facing the same way or folded back over an edge they share (a "
                     "Mirror modifier without merging on a mesh not symmetric about its mirror plane, faces "
                     "laid over others, or a concave quad split along its outer diagonal): such faces "
                     "z-fight, which one a ray meets depends on each renderer's order, so where they are "
                     "seen DACRT's image can differ from Cycles'; delete the overlap or move the faces apart")]
