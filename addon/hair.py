"""Hair curves as tubes: each curve of a Curves object (control points with a radius each)
becomes a tessellated tube the tracer can intersect, as Cycles renders curves: a uniform
Catmull-Rom spline through the points (the end points repeated as their own neighbours, as
Cycles' curve keys), its radius interpolated the same way.

A polygon inscribed in a circle is thinner than it on average; each ring is scaled so its
perimeter is the circle's 2 pi r, which makes the tube's width averaged over view directions
around it (Cauchy's formula) the curve's 2r. Rings are oriented by transporting a normal along
each curve (projection onto each new ring plane), so a curve that bends does not twist its
tube; each curve's first ring is turned by its own share of one polygon sector, so that curves
of a common direction show a view 2r on average (a polygon is wider across its corners than
across its sides). Rings and segment steps drop as curves grow in number so the frame's
triangle count stays bounded (LEVELS). Poly curves end in hemispherical caps, as Cycles' round
linear curves (Embree's cone segments with a sphere at each point) do; Catmull-Rom tubes are open
at their ends, as Cycles' swept circles are. Plain numpy; the export layer (export/strands.py)
reads the Blender data.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

# (most curve points, ring sides, steps per segment): the tube's triangles are about
# points x steps x sides x 2, at most 8M. Sides matter beyond the width: a diffuse bounce
# sampled about the smooth normal that dips below its flat facet ends the path (as on any
# smooth low-poly mesh, in Cycles too), which darkens a tube of few sides. Measured against
# Cycles' round curves, 30 wavy curves under a sun and a white world: 8 sides 1.6% dark,
# 16 sides 0.5%, 32 sides 0.3%.
LEVELS = ((20_000, 16, 4), (100_000, 8, 2), (500_000, 6, 1))
FEWEST = (4, 1)
# every level from the finest down: below FEWEST only when the frame would not fit in memory
# (export/budget.py)
LADDER = ((16, 4), (8, 2), (6, 1), (4, 1), (3, 1))
DEFAULT_RADIUS = 0.005     # Cycles' radius for curves without a 'radius' attribute
# the sharpest turn one mitred ring makes (stretched 1 / cos(MAX_TURN / 2) = 1.41 at most);
# a sharper one is split into 2 rings at the sample (_joins)
MAX_TURN = np.pi / 2
# a Poly curve's: Cycles rounds each point with a sphere, which mitred rings of at most 45 degrees
# follow on the outside of a turn within 0.02 r^2 of profile area a ring (one 90-degree ring: 0.21,
# a 90-degree zig-zag 1.1% over Cycles' coverage)
MAX_TURN_POLY = np.pi / 4
# rings of a Poly curve's end cap from its end ring to its pole (the pole included), at 45 and 90
# degrees: a cap costs 3 x sides triangles, 1.5 segments' (with 1, a cone, the cap would be 1.8
# radii long to have the hemisphere's area; with 2 it is 1.13 at 16 sides)
CAP_RINGS = 2


@lru_cache(maxsize=None)
def cap_height(sides: int) -> float:
    """The length of a cap along the tube's axis, in radii: its rings sit at latitudes k / m of
    90 degrees, each scaled as the tube's rings (perimeter 2 pi r cos(latitude)), at H r sin(latitude)
    past the end; H makes the cap's area the hemisphere's 2 pi r^2, so that by Cauchy's
    formula the strand covers what Cycles' round one does on average over view directions."""
    m = CAP_RINGS
    scale = np.pi / (sides * np.sin(np.pi / sides))
    lat = np.arange(m + 1) * (0.5 * np.pi / m)
    ang = 2.0 * np.pi * np.arange(sides + 1) / sides

    def area(h):
        ring = scale * np.cos(lat)[:, None]
        pts = np.stack(np.broadcast_arrays(ring * np.cos(ang), ring * np.sin(ang), (h * np.sin(lat))[:, None]), -1)
        a, b, c, d = pts[:-1, :-1], pts[:-1, 1:], pts[1:, :-1], pts[1:, 1:]
        return 0.5 * (np.linalg.norm(np.cross(b - a, c - a), axis=-1).sum()
                      + np.linalg.norm(np.cross(d - b, c - b), axis=-1).sum())
    lo, hi = 0.5, 2.0               # area grows with h; bisect to float64's last bits
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if area(mid) < 2.0 * np.pi else (lo, mid)
    return 0.5 * (lo + hi)


def level_for(points: int) -> tuple:
    for most, sides, steps in LEVELS:
        if points <= most:
            return sides, steps
    return FEWEST


def rings(positions, radii, offsets, steps: int, linear: bool = False):
    """The samples of the curves at `steps` a segment and their mitred rings, (samples (s, 4),
    counts, key, u (as _samples with between), _joins' rings or None where no curve has 2
    points): what triangle_count and tubes both compute, made once where the export counts
    the triangles and then makes them (twice, 100K curves had spent 0.9 s in _samples and
    _joins). linear: Poly curves, their turns split at MAX_TURN_POLY."""
    positions = np.asarray(positions, np.float64).reshape(-1, 3)
    keys = np.concatenate([positions, np.asarray(radii, np.float64).reshape(-1, 1)], axis=1)
    samples, counts, key, u = _samples(keys, np.asarray(offsets, np.int64), steps, between=True)
    return samples, counts, key, u, (_joins(samples[:, :3], counts, _max_turn(linear)) if len(counts) else None)


def triangle_count(offsets, level: tuple, linear: bool = False, positions=None, sampled=None) -> int:
    """The most triangles tubes() makes of curves with these offsets at `level` (fewer where a
    radius is 0): with their positions, counting the rings the sharp turns are split into;
    without, as if every turn were split into the most rings (at a U-turn). sampled: rings()
    of these curves at the level's steps (1 where linear), read instead of the positions (the
    radii play no part in the samples' positions). Poly (linear) curves count their two end caps."""
    offsets = np.asarray(offsets, np.int64)
    n = np.diff(offsets)
    sides, steps = level
    steps = 1 if linear else steps
    caps = 2 * (2 * CAP_RINGS - 1) * sides if linear else 0     # a cap: m - 1 bands and a fan
    if sampled is not None:
        joins = sampled[4]
        return 0 if joins is None else int((joins[4] - 1).sum()) * sides * 2 + caps * len(joins[4])
    if positions is None:
        segments = (n[n >= 2] - 1) * steps
        most = int(np.ceil(np.pi / _max_turn(linear) - 1e-9))      # rings at a sample turning back
        return int((most * (segments - 1) + 1).sum()) * sides * 2 + caps * int(np.count_nonzero(n >= 2))
    p = np.asarray(positions, np.float64).reshape(-1, 3)
    keys = np.concatenate([p, np.zeros((len(p), 1))], axis=1)
    samples, counts = _samples(keys, offsets, steps)
    if not len(counts):
        return 0
    return int((_joins(samples[:, :3], counts, _max_turn(linear))[4] - 1).sum()) * sides * 2 + caps * len(counts)


def _catmull_rom(p0, p1, p2, p3, u):
    """Uniform Catmull-Rom between p1 and p2 at u (0..1), rows broadcast."""
    u2, u3 = u * u, u * u * u
    return 0.5 * ((2.0 * p1) + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2
                  + (3.0 * p1 - p0 - 3.0 * p2 + p3) * u3)


def _samples(keys, offsets, steps, between=False):
    """Points along every curve of 2+ keys: (samples (s, 4) = xyz + radius, per-curve counts),
    and with `between` each sample's key k1 (s,) and place u (s,) from it towards k1 + 1."""
    counts = np.diff(offsets)
    curves = np.flatnonzero(counts >= 2)
    first, n = offsets[curves], counts[curves]
    # segment j of a curve runs from key first + j to first + j + 1
    seg_curve = np.repeat(np.arange(len(curves)), n - 1)
    seg_j = np.arange(len(seg_curve)) - np.repeat(np.cumsum(n - 1) - (n - 1), n - 1)
    k1 = first[seg_curve] + seg_j
    last = (first + n - 1)[seg_curve]
    k0 = np.maximum(k1 - 1, first[seg_curve])
    k2 = k1 + 1
    k3 = np.minimum(k1 + 2, last)
    u = (np.arange(steps) / steps)[None, :, None]
    pts = _catmull_rom(keys[k0][:, None], keys[k1][:, None], keys[k2][:, None], keys[k3][:, None], u)
    # each curve: its segments' steps, then its last key
    per_curve = (n - 1) * steps + 1
    out = np.empty((int(per_curve.sum()), 4))
    starts = np.cumsum(per_curve) - per_curve
    seg_rows = (starts[seg_curve] + seg_j * steps)[:, None] + np.arange(steps)[None, :]
    out[seg_rows.reshape(-1)] = pts.reshape(-1, 4)
    out[starts + per_curve - 1] = keys[first + n - 1]
    if not between:
        return out, per_curve
    k = np.empty(len(out), np.int64)
    w = np.zeros(len(out))
    k[seg_rows.reshape(-1)] = np.repeat(k1, steps)
    w[seg_rows.reshape(-1)] = np.tile(np.arange(steps) / steps, len(k1))
    last = starts + per_curve - 1
    k[last], w[last] = first + n - 2, 1.0          # the last key: the end of the last segment
    return out, per_curve, k, w


def _across(tv):
    """A unit vector across each unit row of tv: its cross product with its least aligned axis."""
    axis = np.zeros_like(tv)
    axis[np.arange(len(tv)), np.argmin(np.abs(tv), axis=1)] = 1.0
    c = np.cross(tv, axis)
    return c / np.linalg.norm(c, axis=1, keepdims=True)


def _max_turn(linear):
    return MAX_TURN_POLY if linear else MAX_TURN


def _joins(p, counts, max_turn=MAX_TURN):
    """The rings of the curves' samples p (each curve's counts in a row), mitred: a ring at a
    sample where the curve turns by an angle a is square to the bisector of its two segments and
    stretched by 1 / cos(a / 2) along the bend, so that each segment's tube keeps its width 2r
    up to the joint (a ring square to the mean tangent alone shows cos(a / 2) of it: a Poly 'V'
    of 147 degrees had rendered a third thin). A turn of more than max_turn is split into k
    rings at the sample, turned a / k apart, each mitred for its a / k: a join rounded as
    Cycles' (its segments are round at their ends), never stretched beyond 1 / cos(max_turn / 2).
    Returns (the sample of each ring (g,), its unit tangent (g, 3), its unit bend direction
    (g, 3) (0 on a straight run), its stretch along it (g,), rings a curve (c,))."""
    m = len(p)
    starts = np.cumsum(counts) - counts
    first, last = np.zeros(m, bool), np.zeros(m, bool)
    first[starts], last[starts + counts - 1] = True, True
    d = np.diff(p, axis=0)
    dl = np.linalg.norm(d, axis=1, keepdims=True)
    unit = np.divide(d, dl, out=np.zeros_like(d), where=dl > 0)
    d_in, d_out = np.zeros((m, 3)), np.zeros((m, 3))
    d_in[1:], d_out[:-1] = unit, unit
    d_in[first], d_out[last] = 0.0, 0.0
    # an end (or a segment of no length) takes the direction of the other side
    no_in, no_out = ~d_in.any(axis=1), ~d_out.any(axis=1)
    d_in[no_in], d_out[no_out] = d_out[no_in], d_in[no_out]
    lost = ~d_in.any(axis=1)                     # no length on either side: any direction
    d_in[lost] = d_out[lost] = (0.0, 0.0, 1.0)
    c = np.clip(np.einsum('ij,ij->i', d_in, d_out), -1.0, 1.0)
    turn = np.arccos(c)
    e = d_out - c[:, None] * d_in                # towards the bend, square to d_in
    el = np.linalg.norm(e, axis=1, keepdims=True)
    straight = el[:, 0] < 1e-9
    e = np.divide(e, el, out=np.zeros_like(e), where=~straight[:, None])
    back = straight & (c < 0)                    # turned straight back: bend any way across
    if back.any():
        e[back] = _across(d_in[back])
    turn[straight & ~back] = 0.0
    k = np.maximum(np.ceil(turn / max_turn - 1e-9), 1).astype(np.int64)
    ring = np.repeat(np.arange(m), k)
    j = np.arange(len(ring)) - np.repeat(np.cumsum(k) - k, k)
    phi = (2 * j + 1) / (2 * k[ring]) * turn[ring]
    cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
    t = cos * d_in[ring] + sin * e[ring]
    bend = -sin * d_in[ring] + cos * e[ring]
    stretch = 1.0 / np.cos(turn[ring] / (2 * k[ring]))
    return ring, t, bend, stretch, np.add.reduceat(k, starts)


def _frames(p, counts, sector=0.0, t=None):
    """Unit tangent t and normal n at every sample (t: given, or along the chord between the
    sample's neighbours), n transported along each curve, each curve's first normal turned by
    its share of `sector` radians."""
    m = len(p)
    starts = np.cumsum(counts) - counts
    if t is None:
        ends = starts + counts - 1
        nxt = np.minimum(np.arange(m) + 1, np.repeat(ends, counts))
        prv = np.maximum(np.arange(m) - 1, np.repeat(starts, counts))
        t = p[nxt] - p[prv]
        length = np.linalg.norm(t, axis=1, keepdims=True)
        t = np.divide(t, length, out=np.tile([0.0, 0.0, 1.0], (m, 1)), where=length > 0)

    n = np.empty_like(t)
    n[starts] = _across(t[starts])
    if sector:
        # each curve's rings turned by its own share of one sector (golden-ratio sequence): a
        # polygon is wider across its corners than across its sides, and with one orientation
        # for all, curves of a common direction would all show the camera the same width
        phi = sector * np.modf(np.arange(len(starts)) * 0.6180339887498949)[0]
        t0, n0 = t[starts], n[starts]
        n[starts] = n0 * np.cos(phi)[:, None] + np.cross(t0, n0) * np.sin(phi)[:, None]
    for i in range(1, int(counts.max()) if len(counts) else 0):
        live = np.flatnonzero(counts > i)
        rows = starts[live] + i
        prev = n[rows - 1]
        q = prev - t[rows] * np.einsum('ij,ij->i', t[rows], prev)[:, None]
        ql = np.linalg.norm(q, axis=1, keepdims=True)
        bad = ql[:, 0] < 1e-6                  # the curve turned back on itself: start afresh
        q = np.where(bad[:, None], 0.0, q / np.where(ql > 0, ql, 1.0))
        if bad.any():
            q[bad] = _across(t[rows[bad]])
        n[rows] = q
    return t, n


def _capped(at, p, r, key, u, t, bend, stretch, unsized, counts, sides):
    """The rings with each curve's two end caps added (Cycles' Poly curves end in a sphere of
    the end point's radius): CAP_RINGS rings before its first ring and after its
    last, at latitudes k / m of 90 degrees, the last a pole of radius 0, which tubes() closes
    as it closes a tip. Returns the rings' arrays in the same order (and their latitudes,
    negative on the first cap: its normals tilt back along the tangent), counts per curve."""
    m = CAP_RINGS
    starts = np.cumsum(counts) - counts
    ends = starts + counts - 1
    c = len(counts)
    # each curve's new rows: m cap rings (pole first), its own rings, m cap rings (pole last)
    new_counts = counts + 2 * m
    new_starts = np.cumsum(new_counts) - new_counts
    src = np.empty(int(new_counts.sum()), np.int64)
    lat = np.zeros(len(src))
    body = np.repeat(new_starts + m - starts, counts) + np.arange(int(counts.sum()))
    src[body] = np.arange(int(counts.sum()))
    k = np.arange(1, m + 1) * (0.5 * np.pi / m)
    head = new_starts[:, None] + (m - np.arange(1, m + 1))[None, :]          # latitude k at row m - k
    tail = (new_starts + new_counts - m - 1)[:, None] + np.arange(1, m + 1)[None, :]
    src[head], lat[head] = np.broadcast_to(starts[:, None], (c, m)), -np.broadcast_to(k, (c, m))
    src[tail], lat[tail] = np.broadcast_to(ends[:, None], (c, m)), np.broadcast_to(k, (c, m))
    r0 = r[src]
    # along the end's tangent, H r sin(latitude) past it (cap_height: the hemisphere's area)
    p = p[src] + (cap_height(sides) * r0 * np.sin(lat))[:, None] * t[src]
    r = r0 * np.cos(lat)
    r[np.abs(lat) == 0.5 * np.pi] = 0.0          # the pole exactly (cos(90 degrees) is 6e-17)
    stretch = np.where(lat == 0, stretch[src], 1.0)
    return at[src], p, r, key[src], u[src], t[src], bend[src], stretch, unsized[src], lat, new_counts


def tubes(positions, radii, offsets, level: tuple | None = None, curve_of: bool = False, linear: bool = False,
          vertex_keys: bool = False, sampled=None, exact: bool = False):
    """Tube meshes of the curves (offsets: c + 1 first-point indices, the last = point count),
    Catmull-Rom, or with `linear` straight between the points and capped by hemispheres at their
    ends (POLY curves, as Cycles draws them):
    (vertices float32 (v, 3), triangles int32 (t, 3) wound outward, vertex normals float32
    (v, 3), curves rendered), and with curve_of the curve (index into offsets) each triangle
    belongs to (t,) int64. Curves of fewer than 2 points are not rendered; a sample of radius 0
    or less closes the tube there (Cycles gives it no width), so a curve's triangle count
    depends on its radii. exact: the vertices in float64 (a ring far from the origin keeps
    a radius below float32's spacing there)."""
    positions = np.asarray(positions, np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, np.int64)
    sides, steps = level_for(len(positions)) if level is None else level
    if sampled is None:         # (given: rings() of these curves at these steps)
        sampled = rings(positions, radii, offsets, 1 if linear else steps, linear)   # 1 step: the points
    samples, counts, key, u, joins = sampled
    if not len(counts):
        empty = (np.empty((0, 3), np.float32), np.empty((0, 3), np.int32), np.empty((0, 3), np.float32), 0)
        empty += (np.empty(0, np.int64),) if curve_of else ()
        return empty + ((np.empty(0, np.int64), np.empty(0)),) if vertex_keys else empty
    at, t, bend, stretch, counts = joins     # the rings, mitred
    p, r, key, u = samples[at, :3], samples[at, 3], key[at], u[at]
    # a NaN or infinite radius (its key's, spread by the spline to its neighbours' segments):
    # no tube there (they had made NaN vertices, reported as the positions'); the export says so
    unsized = ~np.isfinite(r)
    r = np.where(unsized, 0.0, np.maximum(r, 0.0))
    lat = np.zeros(len(p))                   # each ring's latitude on an end cap (0: the tube's)
    if linear:
        at, p, r, key, u, t, bend, stretch, unsized, lat, counts = _capped(at, p, r, key, u, t, bend, stretch,
                                                                           unsized, counts, sides)
    t, n = _frames(p, counts, 2.0 * np.pi / sides, t)
    b = np.cross(t, n)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    radial = np.cos(ang)[None, :, None] * n[:, None, :] + np.sin(ang)[None, :, None] * b[:, None, :]
    scale = np.pi / (sides * np.sin(np.pi / sides))    # perimeter of the ring = 2 pi r
    # the mitre: each ring's points stretched along its bend; their normals stay radial (the
    # mean of the two segments' normals there)
    along = np.einsum('rsk,rk->rs', radial, bend)
    offset = radial + ((stretch - 1.0)[:, None] * along)[:, :, None] * bend[:, None, :]
    vertices = (p[:, None, :] + (r * scale)[:, None, None] * offset).reshape(-1, 3)
    if linear:      # a cap ring's normals: the sphere's, tilted by its latitude towards the pole
        radial = np.cos(lat)[:, None, None] * radial + np.sin(lat)[:, None, None] * t[:, None, :]
    # quads between ring i and i + 1 of the same curve; ring j runs anticlockwise about t,
    # so (i, j), (i, j + 1), (i + 1, j) faces outward
    starts = np.cumsum(counts) - counts
    ring = np.flatnonzero(np.isin(np.arange(len(p)), starts + counts - 1, invert=True))
    j = np.arange(sides)
    a = ring[:, None] * sides + j[None, :]
    a1 = ring[:, None] * sides + ((j + 1) % sides)[None, :]
    c, c1 = a + sides, a1 + sides
    # where a ring has radius 0 (a tip) its points coincide: of each quad only the triangle
    # with one corner there is kept (a cone), the other would have no area (and be reported
    # as the user's degenerate geometry)
    quads = np.stack([np.stack([a, a1, c], -1), np.stack([a1, c1, c], -1)], axis=1)   # (rings, 2, sides, 3)
    sized = ~(unsized[ring] | unsized[ring + 1])
    keep = np.broadcast_to(np.stack([(r[ring] > 0) & sized, (r[ring + 1] > 0) & sized], axis=1)[:, :, None],
                           quads.shape[:3])
    joint = np.flatnonzero((at[ring] == at[ring + 1]) & (lat[ring] == 0) & (lat[ring + 1] == 0))   # a split turn's
    if len(joint):
        # there the rings turn about the bend's axis: a point on it is in both, and its
        # triangles have no area
        tri = vertices[quads[joint]]
        area = np.linalg.norm(np.cross(tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :]), axis=-1)
        keep = keep.copy()
        keep[joint] &= area > 1e-6 * (r[ring[joint]] * scale)[:, None, None] ** 2
    triangles = quads[keep].reshape(-1, 3)
    out = (vertices if exact else vertices.astype(np.float32), triangles.astype(np.int32), radial.reshape(-1, 3).astype(np.float32),
           len(counts))
    if curve_of:
        curves = np.flatnonzero(np.diff(offsets) >= 2)            # the curves _samples kept, in order
        ring_curve = curves[np.repeat(np.arange(len(counts)), counts)[ring]]
        out += (np.broadcast_to(ring_curve[:, None, None], quads.shape[:3])[keep],)
    if vertex_keys:     # each vertex's key k (v,) and place u (v,) towards key k + 1 (attributes)
        out += ((np.repeat(key, sides), np.repeat(u, sides)),)
    return out
