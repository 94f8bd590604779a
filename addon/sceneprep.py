"""What the integrator does to a SceneData before rendering it: `validate` checks its arrays
and settings (a ValueError naming what is wrong), `recentred` moves a scene that lies far from
the origin (or the geometry around its camera) onto it so float32 shading keeps its precision,
and says when no origin can. Nothing here knows Blender."""

from dataclasses import replace

import numpy as np

from .scenedata import NO_TRANSMISSION, VIS_CAMERA, VIS_DIFFUSE, SceneData
from .surfacetables import OFFSET_ULPS

F32 = np.float32


# Camera-relative centring (see recentred). The geometry around the camera: the vertices
# within _GAP x the reach (largest camera distance) of those found so far, grown from the
# nearest one, so a far cluster beyond such a gap (an object left 1e5 away) is not part of it
# (vertices: contiguous, a few % of the set-up; triangles would cost as much as the set-up).
# How imprecise an origin leaves it: the self-intersection step (surfacetables.OFFSET_ULPS
# ULPs of a triangle's largest coordinate) over the triangle's size, the median weighted by
# the solid angle the triangle's box subtends at the camera (what the camera sees up close,
# and the room around it), on up to _SAMPLE of its triangles. The render's origin stays the
# bounding box's unless that ratio exceeds _WARN_STEP / _GAIN there and another origin (the
# cluster's centre, the camera) shrinks it _GAIN-fold (4 bits): a scene already around the
# origin keeps its coordinates bit for bit.
_GAP = 8.0
_GAIN = 16.0
# Warn above this ratio: the step lifts points off surfaces by that share of their size (a
# closed 4 m room 1e5 away, 1.6e-2: 1.1% darker; 1e4, 2e-3: 0.05%, within noise).
_WARN_STEP = 1e-3
_SAMPLE = 1 << 14


def _camera_cluster(v, eye):
    """The vertices around the camera at eye (bool mask), or None without finite vertices."""
    d = _distances(v, eye)
    d[~np.isfinite(d)] = np.inf
    if not np.isfinite(d).any():
        return None
    # (reductions with where=: no copies of the selected distances; min and max are exact)
    positive = d > 0
    reach = float(np.min(d, where=positive, initial=np.inf)) if positive.any() else 0.0   # (a camera on a vertex)
    for _ in range(64):     # the reach grows ~_GAP-fold per round where geometry is dense
        near = d <= _GAP * reach
        grown = float(np.max(d, where=near, initial=-np.inf))
        if grown <= reach:
            break
        reach = grown
    return near


# rows of v made into distances at a time by _distances: their columns stay in cache
_DISTANCE_ROWS = 1 << 16


def _distances(v, eye):
    """|v - eye| per row of v (k, 3), float64, as sqrt((dx^2 + dz^2) + dy^2): the sum numpy's
    einsum('ij,ij->i') of the differences gave here (its SIMD lanes add the first and third
    products, then the second), a block of rows at a time, column by column: the einsum had run
    its inner loop three elements at a time over a fresh (k, 3) difference (~7 ms of a
    500K-vertex frame's check)."""
    v = np.asarray(v)
    out = np.empty(len(v))
    rows = min(len(v), _DISTANCE_ROWS)
    dx, dy, dz = np.empty(rows), np.empty(rows), np.empty(rows)
    for s in range(0, len(v), _DISTANCE_ROWS):
        n = min(_DISTANCE_ROWS, len(v) - s)
        x, y, z = dx[:n], dy[:n], dz[:n]
        np.subtract(v[s:s + n, 0], eye[0], out=x)
        np.subtract(v[s:s + n, 1], eye[1], out=y)
        np.subtract(v[s:s + n, 2], eye[2], out=z)
        np.multiply(x, x, out=x)
        np.multiply(z, z, out=z)
        np.add(x, z, out=x)
        np.multiply(y, y, out=y)
        np.add(x, y, out=out[s:s + n])
    return np.sqrt(out, out=out)


def _largest(a):
    """Per row of a (k,3): its largest entry."""
    return np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2])


def _magnitude(p):
    """Per row of points p (k,3): its largest finite |coordinate| (0 where none is)."""
    a = np.abs(np.asarray(p, np.float64))
    return _largest(np.where(np.isfinite(a), a, 0.0))


def _near_boxes(v, tri, near, eye, found=None):
    """Boxes (lo, hi (k,3) float64), sizes (k,) and solid-angle weights (k,) of up to _SAMPLE
    triangles with a vertex in near (an even spread), or None. Where near holds every vertex
    the sample is huge_surfaces' own: its smallest face size (None: none) and the sampled rows
    with their boxes and sizes go to found."""
    # (column by column: numpy's reductions over a short axis are ~10x slower)
    if near.all():      # (an even spread of all rows: a strided view, no gather of them)
        step = max(1, -(-len(tri) // _SAMPLE))
        idx, t = np.arange(0, len(tri), step), tri[::step]
    else:
        idx = np.flatnonzero(near[tri[:, 0]] | near[tri[:, 1]] | near[tri[:, 2]])
        idx = idx[::-(-len(idx) // _SAMPLE)] if len(idx) > _SAMPLE else idx
        t = tri[idx]
    # (np.take along rows: ~3x faster than v[...]'s fancy index, the same rows)
    c0, c1, c2 = (np.asarray(np.take(v, t[:, k], axis=0), np.float64) for k in range(3))
    lo, hi = np.minimum(np.minimum(c0, c1), c2), np.maximum(np.maximum(c0, c1), c2)
    side = _largest(hi - lo)
    gap = np.maximum(np.maximum(lo - eye, 0.0), eye - hi)
    dist = np.sqrt(np.einsum('ij,ij->i', gap, gap))
    keep = np.isfinite(side) & np.isfinite(dist) & (side > 0)
    if found is not None and near.all():
        faces = side[np.isfinite(side) & (side > 0)]     # (huge_surfaces' rows: no distance)
        found['smallest_face'] = float(faces.min()) if len(faces) else None
        found['sample'] = (idx, lo, hi, side)            # (huge_surfaces' own sample, the same rows)
    if not keep.any():
        return None
    if not keep.all():      # (most scenes: every sampled face kept, no copies)
        lo, hi, side, dist = lo[keep], hi[keep], side[keep], dist[keep]
    return lo, hi, side, (side / np.maximum(dist, side)) ** 2


def _imprecision(boxes, origin):
    """The weighted median step / size of the boxes (_near_boxes) at this origin, and their
    largest |coordinate - origin|."""
    lo, hi, side, weight = boxes
    big = _largest(np.maximum(np.abs(lo - origin), np.abs(hi - origin)))
    ratio = float(OFFSET_ULPS) * np.spacing(big.astype(F32)).astype(np.float64) / side
    order = np.argsort(ratio)
    w = np.cumsum(weight[order])
    return float(ratio[order][min(np.searchsorted(w, 0.5 * w[-1]), len(w) - 1)]), float(big.max())


def _median_above(boxes, origin, limit) -> bool:
    """Whether _imprecision(boxes, origin)'s weighted median exceeds limit, without its sort
    where the weights settle it: the median lies above limit exactly when the boxes at or below
    it hold less than half the weight in the sorted cumulative sum. Summed in another order the
    two sums differ by rounding only (~n ULPs of the total, n <= _SAMPLE), so a difference from
    half beyond 1e-9 of the total decides; closer ones (and no weight) take the sort."""
    lo, hi, side, weight = boxes
    big = _largest(np.maximum(np.abs(lo - origin), np.abs(hi - origin)))
    ratio = float(OFFSET_ULPS) * np.spacing(big.astype(F32)).astype(np.float64) / side
    total = float(weight.sum())
    below = float(weight[ratio <= limit].sum())
    margin = 1e-9 * total
    if total > 0 and below >= 0.5 * total + margin:
        return False
    if total > 0 and below <= 0.5 * total - margin:
        return True
    return _imprecision(boxes, origin)[0] > limit


def recentred(sd: SceneData, found=None):
    """The scene translated for float32 shading, that offset (float64), and a warning (or None)
    when precision cannot be had. found (a dict, optional): where the scene keeps its
    coordinates, what huge_surfaces can reuse of its sampled triangles (their smallest size,
    and the geometry sampled).

    Shading works in float32 (hit points, self-intersection steps of a few ULPs of the
    coordinates): a scene a few units across placed 1e5 from the origin would shade on a grid
    of 2^-7 and step ~6% of its size off surfaces. A translation changes no image, so the
    render uses coordinates centred on the scene: on its bounding box when it lies away from
    the origin (further than its half-extent), and, when that leaves the geometry around the
    camera far from the origin (a room 3e5 away and one object left on the other side of the
    origin: the box centres near 0 and the room stepped 0.25 m off its walls, 0.61x Cycles),
    on that geometry instead, as game engines rebase their origin on the camera's
    surroundings. Vertices, camera and lamp positions move; directions do not; passes and
    textures that read world positions add the offset back. The vertices are shifted in
    float64 before rounding to float32, so input given in float64 keeps its precision."""
    v = np.asarray(sd.geometry.vertices)
    if v.ndim != 2 or not len(v):
        return sd, np.zeros(3), None
    fv = v if np.isfinite(v).all() else v[np.isfinite(v).all(axis=1)]
    if not len(fv):
        return sd, np.zeros(3), None
    # per column: min/max over axis 0 of an (N, 3) array is ~10x slower in numpy; exact in
    # any float type, so only the centre needs float64
    lo = np.array([fv[:, a].min() for a in range(3)], np.float64)
    hi = np.array([fv[:, a].max() for a in range(3)], np.float64)
    origin = 0.5 * (lo + hi)
    # only worth it when the scene lies off the origin: the largest coordinate then drops from
    # |centre| + half-extent to half-extent (a scene around the origin keeps its coordinates)
    if np.abs(origin).max() <= 0.5 * (hi - lo).max():
        origin = np.zeros(3)
    warning = None
    tri = np.asarray(sd.geometry.triangles)
    eye = np.asarray(sd.camera.matrix, np.float64)[:3, 3]
    near = _camera_cluster(np.asarray(v, np.float64), eye) if np.isfinite(eye).all() and len(tri) else None
    boxes = None if near is None else _near_boxes(v, tri, near, eye, found)
    # Weighed only when the origin is not good enough already: most scenes, which the weights
    # settle without the weighted median's sort (_median_above)
    if boxes is not None and _median_above(boxes, origin, _WARN_STEP / _GAIN):
        kept = _imprecision(boxes, origin)
        # the cluster's centre, or the camera where it does much better (a camera amid a large
        # cluster); the centre first, as it stays put while the camera moves through a scene
        clo, chi = (lo, hi) if near.all() else (v[near].min(axis=0).astype(np.float64),
                                                 v[near].max(axis=0).astype(np.float64))
        centre = 0.5 * (clo + chi)
        at_centre, at_eye = _imprecision(boxes, centre)[0], _imprecision(boxes, eye)[0]
        candidate, score = (eye, at_eye) if _GAIN * at_eye < at_centre else (centre, at_centre)
        if kept[0] > _GAIN * score:
            origin = candidate
            kept = _imprecision(boxes, origin)
        if kept[0] > _WARN_STEP:
            world = float(np.maximum(np.abs(boxes[0]), np.abs(boxes[1])).max())
            where = f"{kept[1]:.3g}" if not origin.any() else \
                f"{kept[1]:.3g} from the render's origin, {world:.3g} in world space"
            warning = (f"the surfaces around the camera lie too far apart for float32 precision "
                       f"(coordinates up to {where}): bounce and shadow rays start {kept[0]:.2g}x "
                       f"of a typical triangle's size off the surface, so the image may be too dark "
                       f"or leak light; move the objects the camera sees near the world origin (or "
                       f"render far-apart parts as separate scenes)")
    if not origin.any():
        if found is not None and 'smallest_face' in found:
            found['geometry'] = sd.geometry
            if fv is v:     # (every vertex finite: the largest |coordinate| of them all)
                found['largest'] = float(np.maximum(np.abs(lo), np.abs(hi)).max())
        return sd, origin, warning
    if found is not None:
        found.clear()               # (moved: the sample's sizes are not the moved vertices')

    def moved(matrix):
        m = np.array(matrix, np.float64)
        m[:3, 3] -= origin
        return m

    geometry = replace(sd.geometry, vertices=(v.astype(np.float64) - origin).astype(F32))
    camera = replace(sd.camera, matrix=moved(sd.camera.matrix))
    lights = [replace(light, matrix=moved(light.matrix)) for light in sd.lights]
    return replace(sd, geometry=geometry, camera=camera, lights=lights), origin, warning


# Thin strands (rounded_strands): a hair tube's corner rounded by more than this fraction of the
# triangle's shortest edge has lost its shape in float32 (a ring of radius 5e-5 where the spacing
# is 6.1e-5 had become rings of radius 0 to 8.6e-5: 3000 strands 1.095x Cycles' coverage)
_STRAND_ROUNDING = 0.2
# ... said where such triangles can move more than this share of their placement's tube area: a
# tapering strand always ends thinner than float32 near its tip (fur of Shape 0.9 at the origin,
# radii down to 1e-8: 96000 of its 624000 triangles rounded), where the area the rounding can
# move is a negligible share of the tubes' and the image is Cycles'
_STRAND_SHARE = 0.01
_STRAND_CHUNK = 1 << 18
_STRAND_SAMPLE = 4096


def _strand_rounding(v, tri, r, origin):
    """For tube triangles r: which round out of shape (a corner moved by more than
    _STRAND_ROUNDING of the shortest edge once centred on origin and rounded to float32), the
    area each of those can gain or lose so (0 for the others: its own area, plus its perimeter
    times the corners' move and the disc of that move), and each one's area."""
    c = v[tri[r]] - origin                                              # (k, 3, 3)
    err = np.abs(c.astype(F32).astype(np.float64) - c).max(axis=(1, 2))
    e = [c[:, (i + 1) % 3] - c[:, i] for i in range(3)]
    lengths = np.stack([np.linalg.norm(x, axis=1) for x in e], axis=1)
    area = 0.5 * np.linalg.norm(np.cross(e[0], e[1]), axis=1)
    bad = err > _STRAND_ROUNDING * lengths.min(axis=1)
    move = np.sqrt(3.0) * err                                           # (a corner's distance moved)
    return bad, np.where(bad, area + lengths.sum(axis=1) * move + np.pi * move * move, 0.0), area


def rounded_strands(sd: SceneData, origin):
    """Mask (M,) of the hair and Curves tube triangles (Geometry.one_sided) whose float32
    coordinates once centred on `origin` (recentred's) move a corner by more than
    _STRAND_ROUNDING of the triangle's shortest edge, in the placements (Geometry.instance, else
    the objects) where those triangles can move more than _STRAND_SHARE of the tubes' area; or
    None where there are none or the vertices are float32 already (nothing to compare). Strands
    thinner than a few float32 steps at their place lose their shape there however they are
    tessellated: Cycles keeps a curve's radius apart from its keys. Chunked: (k, 3, 3) float64
    corners per chunk."""
    g = sd.geometry
    one = getattr(g, 'one_sided', None)
    v = np.asarray(g.vertices)
    if one is None or v.dtype != np.float64:
        return None
    rows = np.flatnonzero(one)
    if not len(rows):
        return None
    tri = np.asarray(g.triangles)
    origin = np.asarray(origin, np.float64)
    owner = getattr(g, 'instance', None)
    owner = np.asarray(g.object_index if owner is None else owner)

    def places(ids):
        """The placement ids as counts' positions (counted, not sorted, where their range is
        short: they index arrays) and how many."""
        lo, hi = int(ids.min()), int(ids.max())
        if hi - lo <= 4 * len(ids):
            return (ids - lo).astype(np.intp), hi - lo + 1
        _, who = np.unique(ids, return_inverse=True)
        return who, int(who.max()) + 1
    # a spread sample first (most renders: no placement near the share, ~1 ms); all past it
    if len(rows) > _STRAND_SAMPLE:
        picked = rows[::len(rows) // _STRAND_SAMPLE]
        bad, change, area = _strand_rounding(v, tri, picked, origin)
        if not bad.any():
            return None
        who, k = places(owner[picked])
        # (a placement at a quarter of the share in the sample is looked at in full)
        if not (np.bincount(who, change, k) > 0.25 * _STRAND_SHARE * np.bincount(who, area, k)).any():
            return None
    who, k = places(owner[rows])
    moved, total = np.zeros(k), np.zeros(k)
    bad = np.zeros(len(rows), bool)
    for c0 in range(0, len(rows), _STRAND_CHUNK):
        part = slice(c0, c0 + _STRAND_CHUNK)
        bad[part], change, area = _strand_rounding(v, tri, rows[part], origin)
        moved += np.bincount(who[part], change, k)
        total += np.bincount(who[part], area, k)
    bad &= (moved > _STRAND_SHARE * total)[who]
    if not bad.any():
        return None
    out = np.zeros(len(tri), bool)
    out[rows[bad]] = True
    return out


def thin_strands(sd: SceneData, origin):
    """The warning (text) naming the hair and Curves objects whose tubes render out of shape
    where they are (rounded_strands), or None."""
    rounded = rounded_strands(sd, origin)
    if rounded is None:
        return None
    return (f"hair or curves of {sd.named_objects(rounded)}: {int(rounded.sum())} of their tube triangles are "
            f"thinner than float32 can hold where they are (their corners round by more than "
            f"{_STRAND_ROUNDING:g} of an edge), so those strands render out of shape, wider or narrower than "
            "Cycles' curves; move them nearer the world origin (or render them apart from far-off objects)")


# Far-reaching surfaces (huge_surfaces): float32 places a point on a triangle only to ULPs of
# its coordinates. What the render still gets wrong near objects resting on a huge face
# (measured: a 1 m box on one quad of half-size H, against the same plane split small under the
# box, which renders right): hit points placed to ~1 ULP of H along the surface (its float32
# barycentrics: median 1, largest ~4.5 ULPs; Cycles' are the same), points within the step
# (8 ULPs of H) of a face's edge moved up to 2 steps along the surface (the margin that keeps a
# neighbour's float test from taking them), and on a tilted face the step along the normal (P's
# error there, ULPs of H). An axis-aligned plane steps only ULPs of its own height off itself
# (native shading.h triangle_table): the 0.5 m step under everything on a plane of half-size 1e6,
# which lost the contact shadows (the box's 8x8 shadow block 1.128x Cycles'), is gone. Said
# where one of those exceeds _HUGE_STEP of the size of the objects within _NEAR_STEPS steps of
# the surface (H = 1e4: 0.8%, not said).
_HUGE_STEP = 1e-2
_NEAR_STEPS = 4.0
_HUGE_CANDIDATES = 8      # the largest triangles of each far-reaching object that are checked
_HUGE_OBJECTS = 3         # objects named in full
_HUGE_SEARCH = 16         # objects checked, those of the largest steps
_HUGE_SEEN = 1e-4          # objects on the surface smaller than this x their camera distance are not weighed


def _steps(mag):
    """The self-intersection step of triangles whose largest |coordinate| is mag (float64)."""
    return float(OFFSET_ULPS) * np.spacing(np.maximum(np.asarray(mag, F32), F32(2.0 ** -100))).astype(np.float64)


def _plane_gap(a, b, c, lo, hi):
    """Distances (k,) from boxes lo, hi (k,3) to the plane of triangle a, b, c (float64; 0
    where a box crosses it or the triangle has no plane)."""
    n = np.cross(b - a, c - a)
    length = float(np.linalg.norm(n))
    if not (length > 0 and np.isfinite(length)):
        return np.zeros(len(lo))
    n = n / length
    d = float(n @ a)
    near, far = np.where(n > 0, lo, hi) @ n, np.where(n > 0, hi, lo) @ n    # the box's extent along n
    return np.maximum(np.maximum(near - d, d - far), 0.0)


def _group_boxes(groups, lo, hi):
    """Per distinct value of groups (k,), in ascending order: the box (lo, hi (g,3)) of its rows'
    boxes lo, hi (k,3). Runs of equal values are reduced first (a placement's triangles are
    consecutive): np.minimum.at, a per-row loop, had cost ~2.5 ms a render on the dragon's
    16K sampled rows; minima and maxima are exact, so the boxes are the same."""
    starts = np.concatenate(([0], np.flatnonzero(groups[1:] != groups[:-1]) + 1))
    run_lo, run_hi = np.minimum.reduceat(lo, starts, axis=0), np.maximum.reduceat(hi, starts, axis=0)
    kinds, which = np.unique(groups[starts], return_inverse=True)
    if (np.diff(which) > 0).all():
        return run_lo, run_hi                   # (one run per group, in order)
    out_lo, out_hi = np.full((len(kinds), 3), np.inf), np.full((len(kinds), 3), -np.inf)
    np.minimum.at(out_lo, which, run_lo)
    np.maximum.at(out_hi, which, run_hi)
    return out_lo, out_hi


def huge_surfaces(sd: SceneData, recentred_origin=None, geo=None, found=None) -> list:
    """Warnings (texts) naming the surfaces whose self-intersection step (OFFSET_ULPS ULPs of
    a triangle's largest coordinate) is a sizeable share of the objects resting on or near them:
    a huge single-quad ground plane. The step cannot shrink there without its neighbour across
    the quad's diagonal being re-hit (README, Robustness); subdividing the surface makes the
    faces under the objects small and their steps with them. geo: the frame's triangle table
    (surfacetables.Triangles.geo, (15, M) float32), whose rows 12:15 hold each triangle's step
    along its normal: read from there (contiguous rows) instead of from the vertices. Where
    nothing is said this costs those rows' min / max and a sampled triangle box pass, or not
    even that where recentred (found) sampled the same triangles of this geometry: its smallest
    face size then settles the first test (the dragon's 4-spp set-up: ~1 ms a render), and its
    sampled boxes are the objects' past it."""
    g = sd.geometry
    v = np.asarray(g.vertices)
    tri = np.asarray(g.triangles)
    if v.ndim != 2 or not len(v) or not len(tri):
        return []
    reuse = found is not None and found.get('geometry') is g
    if reuse and 'largest' in found:
        # recentred's box of the vertices (all finite): their largest |coordinate|, which bounds
        # every triangle's step the candidates below take (_steps grows with it), without the
        # table's rows reduced again (0.3 ms of the dragon's set-up, ~4 ms at 1M triangles)
        largest_step = _steps(found['largest'])
        if not np.isfinite(largest_step):       # (beyond float32's range, as the table's inf)
            largest_step = np.inf
    elif geo is not None:
        # the largest coordinate: at most |v0| + the larger edge, per axis (contiguous rows)
        rows = np.asarray(geo)
        big = sum(max(abs(float(rows[a].min())), abs(float(rows[a].max())))
                  + max(abs(float(rows[b].min())), abs(float(rows[b].max())), abs(float(rows[b + 3].min())),
                        abs(float(rows[b + 3].max()))) for a, b in ((0, 3), (1, 4), (2, 5)))
        largest_step = _steps(big) if np.isfinite(big) else np.inf
    else:
        # from the largest |coordinate|: per column min / max (no copies); non-finite rows
        # (dropped by the triangle tables) only looked past where there are any
        big = max(max(abs(float(v[:, a].min())), abs(float(v[:, a].max()))) for a in range(3))
        if not np.isfinite(big):
            fin = v[np.isfinite(v).all(axis=1)]
            big = float(np.abs(fin).max()) if len(fin) else 0.0
        largest_step = _steps(big)
    if reuse:
        small = found['smallest_face']
        if small is None or not largest_step > _HUGE_STEP * small:
            return []
    if reuse and 'sample' in found:
        idx, lo, hi, side = found['sample']     # (recentred's: the same rows of this geometry)
    else:
        # sampled triangle sizes (an even spread of up to _SAMPLE)
        idx = np.arange(len(tri))
        idx = idx[::-(-len(idx) // _SAMPLE)] if len(idx) > _SAMPLE else idx
        t = tri[idx]
        c0, c1, c2 = (np.asarray(v[t[:, k]], np.float64) for k in range(3))
        lo, hi = np.minimum(np.minimum(c0, c1), c2), np.maximum(np.maximum(c0, c1), c2)
        side = _largest(hi - lo)
    # (a finite side is a finite hi - lo on each axis (np.maximum passes NaN on), so finite
    # corners: their own per-row test over the short axis is not needed)
    ok = np.isfinite(side) & (side > 0)
    if not ok.any():
        return []
    if not ok.all():        # (most scenes: every sampled face, no copies)
        idx, lo, hi, side = idx[ok], lo[ok], hi[ok], side[ok]
    if not largest_step > _HUGE_STEP * float(side.min()):
        return []                   # not even of the smallest face: no object's boxes needed
    # nothing can step off by _HUGE_STEP of any object (its sampled faces' box: a scanned
    # mesh of tiny faces is one object several units across): the common case ends here
    index = np.asarray(g.object_index) if getattr(g, 'object_index', None) is not None else np.zeros(len(tri), np.int64)
    # each placement apart (an instance of an object; else the object): instances of one rock
    # scattered over a ground plane share an object index, and their joint box had been weighed
    # as one object as wide as the scatter, leaving the lost contact shadows unsaid
    instance = getattr(g, 'instance', None)
    objects = np.asarray(instance) if instance is not None else index
    sample_obj = objects[idx]
    obj_lo, obj_hi = _group_boxes(sample_obj, lo, hi)
    smallest_object = max(float(_largest(obj_hi - obj_lo).min()), float(side.min()))
    if not largest_step > _HUGE_STEP * smallest_object:
        return []
    # Only faces much wider than the smallest sampled ones can swallow objects (`near` below
    # wants 16x): those are the candidates, found from the table's edge rows without a gather
    # of vertices (a scanned mesh of tiny faces 100 units out passed the test above and had cost
    # ~0.5 s a million triangles); 8x leaves room for the float32 edges' rounding.
    small = float(side.min())
    if geo is not None:
        edges = np.asarray(geo)[3:9]
        extent = np.zeros(len(tri), F32)
        for a in range(3):
            e1, e2 = edges[a], edges[3 + a]
            np.maximum(extent, np.maximum(np.maximum(e1, e2), 0) - np.minimum(np.minimum(e1, e2), 0), out=extent)
        wide = np.flatnonzero(extent > 8.0 * small)
        wide_step = _steps(_largest(np.stack([_magnitude(v[tri[wide, k]]) for k in range(3)], axis=1)))
    else:
        wide = np.arange(len(tri))
        wide_step = _steps(_largest(np.stack([_magnitude(v[tri[:, k]]) for k in range(3)], axis=1)))
    tstep = np.zeros(len(tri))                 # each candidate's step (the others' are not read)
    tstep[wide] = wide_step
    candidates = wide[wide_step > _HUGE_STEP * smallest_object]
    names = list(getattr(sd, 'object_names', None) or [])
    eye = np.asarray(sd.camera.matrix, np.float64)[:3, 3]
    found = {}
    # the objects with the largest steps first, _HUGE_SEARCH of them (bounds the cost where
    # many objects reach far: a city block 1e4 out)
    ranked_c = candidates[np.argsort(-tstep[candidates], kind='stable')]
    first_obj, first_at = np.unique(objects[ranked_c], return_index=True)
    for obj in first_obj[np.argsort(first_at)][:_HUGE_SEARCH]:
        mine = candidates[objects[candidates] == obj]
        cv = [np.asarray(v[tri[mine, k]], np.float64) for k in range(3)]
        clo, chi = np.minimum(np.minimum(cv[0], cv[1]), cv[2]), np.maximum(np.maximum(cv[0], cv[1]), cv[2])
        cside = _largest(chi - clo)
        good = np.isfinite(cside)
        mine, clo, chi, cside = mine[good], clo[good], chi[good], cside[good]
        order = np.argsort(-cside)[:_HUGE_CANDIDATES]
        for j in order:
            step = float(tstep[mine[j]])
            gap = np.maximum(np.maximum(lo - chi[j], clo[j] - hi), 0.0)
            # a lower bound of each box's distance to the triangle: the larger of its gap to
            # the triangle's box and to its plane (a tilted huge face's box holds objects far
            # off the face itself)
            dist = np.maximum(np.sqrt(np.einsum('ij,ij->i', gap, gap)),
                              _plane_gap(cv[0][j], cv[1][j], cv[2][j], lo, hi))
            near = (dist <= _NEAR_STEPS * step) & (side * 16.0 < cside[j])
            if not near.any():
                continue
            # the objects there, each by the box of its small triangles near the surface
            olo, ohi = _group_boxes(sample_obj[near], lo[near], hi[near])
            sizes = _largest(ohi - olo)
            # only objects the camera can make out (a 1 cm part 1e4 away cannot show its
            # contact shadow): at least _HUGE_SEEN of their distance across
            gap_eye = np.maximum(np.maximum(olo - eye, 0.0), eye - ohi)
            seen = sizes >= _HUGE_SEEN * np.sqrt(np.einsum('ij,ij->i', gap_eye, gap_eye))
            if not seen.any():
                continue
            size = float(np.median(sizes[seen]))
            if not (size > 0 and step > _HUGE_STEP * size):
                continue
            corners = [c[j] for c in cv]
            said = _what_is_off(corners, step, _normal_step(geo, mine[j], v, tri), olo[seen], ohi[seen],
                                _HUGE_STEP * size)
            if said:
                share = max(err for err, _ in said) / size
                named = int(index[mine[j]])    # by its object: a huge tile's instances said once
                if named not in found or share > found[named][0]:
                    found[named] = (share, [text for _, text in said], size, float(_magnitude(np.array(corners)).max()))
    if not found:
        return []
    where = "the render's origin" if recentred_origin is not None and np.any(recentred_origin) else "the world origin"
    out = []
    ranked = sorted(found.items(), key=lambda kv: -kv[1][0])
    for obj, (share, texts, size, mag) in ranked[:_HUGE_OBJECTS]:
        name = names[int(obj)] if 0 <= int(obj) < len(names) else f"#{int(obj)}"
        out.append(f"object '{name}' has faces reaching {mag:.3g} from {where}: {'; '.join(texts)} "
                   f"(up to {share:.0%} of the {size:.3g}-unit objects on or near it), so shading "
                   f"and contact shadows there are off by that much; subdivide it so the faces under "
                   f"the objects are small (Subdivide, or a Grid), or make it smaller")
    if len(ranked) > _HUGE_OBJECTS:
        out[-1] += f" ({len(ranked) - _HUGE_OBJECTS} more such objects)"
    return out


def _normal_step(geo, i, v, tri):
    """Triangle i's step along its normal: the frame's table row (geo: rows 12:15), else its
    own table's (which cannot know of a coincident twin)."""
    if geo is None:
        import dacrt
        geo = dacrt.shading.triangle_table(np.asarray(v[tri[i]], F32), np.array([[0, 1, 2]], np.int32),
                                           OFFSET_ULPS)[0]
        i = 0
    return float(np.linalg.norm(np.asarray(geo)[12:15, i].astype(np.float64)))


def _what_is_off(corners, step, normal, olo, ohi, limit):
    """(error, text) of what float32 still gets wrong by more than `limit` on the triangle of
    corners (3 float64 points) whose whole step is `step` and step along the normal `normal`,
    near the objects of boxes olo / ohi (k, 3): the hit points' placement (an ULP of its largest
    coordinate), the move of points within the step of an edge (where an object lies that near
    one), the step along the normal."""
    c = [np.asarray(x, np.float64) for x in corners]
    mag = float(max(np.abs(x).max() for x in c))
    ulp = float(np.spacing(np.float32(mag)))
    said = []
    if ulp > limit:
        said.append((ulp, f"hit points on them are placed only to ~{ulp:.2g} (a float32 ULP of that coordinate)"))
    if step > limit:
        centre, half = 0.5 * (olo + ohi), 0.5 * np.sqrt(((ohi - olo) ** 2).sum(axis=1))
        for a, b in ((c[0], c[1]), (c[1], c[2]), (c[2], c[0])):
            e = b - a
            s = np.clip(((centre - a) @ e) / max(float(e @ e), 1e-300), 0.0, 1.0)
            gap = np.sqrt((((a + s[:, None] * e) - centre) ** 2).sum(axis=1)) - half
            if (gap <= _NEAR_STEPS * step).any():
                said.append((step, f"shading points within {step:.2g} of their edges move up to "
                                   f"{2 * step:.2g} along them"))
                break
        if normal > limit:
            said.append((normal, f"bounce and shadow rays leave them {normal:.2g} off the surface"))
    return said


def validate(sd: SceneData):
    g = sd.geometry
    m = len(np.asarray(g.triangles))
    checks = [
        (np.asarray(g.vertices).ndim == 2 and np.asarray(g.vertices).shape[1] == 3, "geometry.vertices must be (V,3)"),
        (np.asarray(g.triangles).ndim == 2 and np.asarray(g.triangles).shape[1] == 3, "geometry.triangles must be (M,3)"),
        (np.issubdtype(np.asarray(g.triangles).dtype, np.integer), "geometry.triangles must be integers"),
        (np.asarray(g.material).shape == (m,), f"geometry.material must have one entry per triangle ({m})"),
        (np.asarray(g.normals).shape == (m, 3, 3), f"geometry.normals must be ({m},3,3)"),
        (np.asarray(g.visibility).shape == (m,), f"geometry.visibility must have one entry per triangle ({m})"),
        (g.uvs is None or np.asarray(g.uvs).shape == (m, 3, 2), f"geometry.uvs must be None or ({m},3,2)"),
        (g.terminator is None or np.asarray(g.terminator).shape == (m, 2),
         f"geometry.terminator must be None or ({m},2)"),
        (g.has_uv is None or np.asarray(g.has_uv).shape == (m,), f"geometry.has_uv must be None or ({m},)"),
        (getattr(g, 'unbumped', None) is None or np.asarray(g.unbumped).shape == (m,),
         f"geometry.unbumped must be None or ({m},)"),
        (getattr(g, 'one_sided', None) is None or np.asarray(g.one_sided).shape == (m,),
         f"geometry.one_sided must be None or ({m},)"),
        (getattr(g, 'tangents', None) is None or np.asarray(g.tangents).shape == (m, 3, 4),
         f"geometry.tangents must be None or ({m}, 3, 4)"),
        (getattr(g, 'colors', None) is None or np.asarray(g.colors).shape == (m, 3, 3),
         f"geometry.colors must be None or ({m}, 3, 3)"),
        (getattr(g, 'coords', None) is None or np.asarray(g.coords).shape in ((m, 3, 6), (m, 3, 9)),
         f"geometry.coords must be None or ({m}, 3, 6) or ({m}, 3, 9)"),
        (all(np.asarray(a).shape == (m, 3, 3 if kind == 'color' else 1)
             for (_, kind), a in (getattr(g, 'aovs', None) or {}).items()),
         f"geometry.aovs must map (name, 'color' | 'value') to ({m}, 3, 3) or ({m}, 3, 1)"),
        (all(np.asarray(a).shape == (m, 3, 4) for a in (getattr(g, 'attributes', None) or {}).values()),
         f"geometry.attributes must map names to ({m}, 3, 4)"),
    ]
    for ok, msg in checks:
        if not ok:
            raise ValueError(msg)
    if g.terminator is not None:
        t = np.asarray(g.terminator, np.float64)
        if not (np.isfinite(t).all() and (t >= 0).all() and (t <= 1).all()):
            raise ValueError("geometry.terminator (shadow terminator offsets) must lie in 0..1")
    nv = len(np.asarray(g.vertices))
    tri = np.asarray(g.triangles)
    if m and (tri.min() < 0 or tri.max() >= nv):
        raise ValueError(f"geometry.triangles index a vertex outside 0..{nv - 1}")
    mat = np.asarray(g.material)
    if m and (mat.min() < 0 or mat.max() >= len(sd.materials)):
        raise ValueError(f"geometry.material indexes a material outside 0..{len(sd.materials) - 1}")
    w = np.asarray(sd.world, np.float64)
    if w.shape != (3,) or not np.isfinite(w).all() or (w < 0).any():
        raise ValueError(f"world must be 3 finite non-negative numbers, got {sd.world!r}")
    wv = sd.world_visibility
    if not isinstance(wv, (int, np.integer)) or int(wv) & ~(VIS_CAMERA | VIS_DIFFUSE | NO_TRANSMISSION):
        raise ValueError(f"world_visibility must be bits of VIS_CAMERA | VIS_DIFFUSE | NO_TRANSMISSION, got {wv!r}")
    env = sd.environment
    if env is not None:
        # (its shape alone: an 8-bit image's texels are made into floats only if read)
        shape, st = np.shape(env.pixels), np.asarray(env.strength, np.float64)
        if len(shape) != 3 or shape[2] < 3 or shape[0] < 1 or shape[1] < 1:
            raise ValueError(f"environment.pixels must be (h, w, 3 or 4) with h, w >= 1, got {shape}")
        if st.shape != (3,) or not np.isfinite(st).all() or (st < 0).any():
            raise ValueError(f"environment.strength must be 3 finite non-negative numbers, got {env.strength!r}")
        m = np.asarray(env.to_map, np.float64)
        if m.shape != (3, 3) or not np.allclose(m @ m.T, np.eye(3), atol=1e-4):
            raise ValueError(f"environment.to_map must be an orthogonal 3x3 matrix, got {env.to_map!r}")
        if env.interpolation not in ('Linear', 'Closest'):
            raise ValueError(f"environment.interpolation must be 'Linear' or 'Closest', got {env.interpolation!r}")
        enc = np.shape(env.encoded)
        if env.encoded is not None and (len(enc) != 3 or enc[:2] != tuple(shape[:2]) or enc[2] < 3):
            raise ValueError(f"environment.encoded must be (h, w, 3 or 4) as its pixels {tuple(shape[:2])}, "
                             f"got {np.shape(env.encoded)}")
    s = sd.settings
    if int(s.samples) < 1:
        raise ValueError(f"settings.samples must be >= 1, got {s.samples!r}")
    if int(s.max_bounces) < 0:
        raise ValueError(f"settings.max_bounces must be >= 0, got {s.max_bounces!r}")
    if int(s.threads) < 0:
        raise ValueError(f"settings.threads must be >= 0 (0 = all cores), got {s.threads!r}")
    if not 0 <= int(s.seed) < 2 ** 63:
        raise ValueError(f"settings.seed must be a non-negative integer, got {s.seed!r}")
    mist = np.asarray(s.mist, np.float64)
    if mist.shape != (3,) or not np.isfinite(mist).all() or mist[1] < 0 or mist[2] < 0:
        raise ValueError(f"settings.mist must be (start, depth >= 0, falloff >= 0), finite, got {s.mist!r}")
