"""Per-ray helper kernels for a renderer's shading side (native, threaded, GIL released).

The arithmetic between two traced batches: packing rays, reconstructing hit points, random
numbers and diffuse bounce directions. Vectors are (3, n) float32 structure-of-arrays (one
contiguous row per axis). Each kernel is one pass over its rays instead of numpy's one pass per
operation, so a renderer built on numpy keeps tracing, not array traffic, its main cost.
"""
from __future__ import annotations

import numpy as np

from . import _core
from . import RAY_DTYPE, HIT_DTYPE

__all__ = ["triangle_table", "hit_records", "repeated_keys", "coplanar_groups", "shifted_plane_keys", "corner_rows", "pixel_samples", "block_samples", "pack_rays", "surface", "uniform2", "cosine_scatter", "sample_triangles", "uniform_pick", "continue_paths", "nee_weight", "rough_rows", "rough_scale", "shadow_rays",
           "LightChoice", "next_event", "accumulate_masked", "noise_texture",
           "voronoi_texture"]

_F32 = np.float32


def _rows(a, rows: int, name: str, dtype=_F32) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype)
    if a.ndim != 2 or a.shape[0] != rows:
        raise ValueError(f"{name} must have shape ({rows}, n), got {a.shape}")
    return a


def _prim32(prim, name: str) -> np.ndarray:
    """prim as int32 for the kernels, refused (not wrapped) where a value does not fit."""
    prim = np.asarray(prim)
    if prim.size and prim.dtype.kind not in "iu":
        raise ValueError(f"{name} must be an integer array, got dtype {prim.dtype}")
    if prim.size and prim.dtype != np.int32:
        bad = np.flatnonzero((prim < -1) | (prim > np.iinfo(np.int32).max))
        if len(bad):
            raise ValueError(f"{name}[{bad[0]}] = {prim.flat[bad[0]]} is not a triangle index")
    return np.ascontiguousarray(prim, np.int32)


def _check_added_to(L) -> None:
    """L is added to in place, so it must be float32 and C-contiguous as it is (a converted copy
    would silently lose the result)."""
    if not isinstance(L, np.ndarray) or L.dtype != _F32 or not L.flags.c_contiguous or L.ndim != 2:
        raise ValueError("L must be a C-contiguous (3, N) float32 array (it is added to in place)")


def pack_rays(O, D, tfar, out: np.ndarray | None = None) -> np.ndarray:
    """RAY_DTYPE records from origins O and directions D (3, n) and lengths tfar (n,);
    ids are 0..n-1. out: an (n,) RAY_DTYPE array to fill (reused between batches)."""
    O = _rows(O, 3, "O")
    D = _rows(D, 3, "D")
    n = O.shape[1]
    tfar = np.ascontiguousarray(np.broadcast_to(np.asarray(tfar, _F32), (n,)))
    if out is None:
        out = np.empty(n, RAY_DTYPE)
    elif out.dtype != RAY_DTYPE or out.shape != (n,):
        raise ValueError(f"out must be an ({n},) RAY_DTYPE array, got {out.dtype} {out.shape}")
    _core.pack_rays(O, D, tfar, out)
    return out


def _triangles32(triangles, num_vertices: int) -> np.ndarray:
    """Vertex indices (M, 3) as int32, checked to be in [0, num_vertices) before the cast (which
    would wrap 2**32 + 1 to 1)."""
    t = np.asarray(triangles)
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"triangles must have shape (M, 3); got {t.shape}")
    if t.size == 0:
        return np.zeros((0, 3), np.int32)
    if t.dtype.kind not in "iu":
        raise ValueError(f"triangles must be an integer array of vertex indices; got dtype {t.dtype}")
    if t.dtype != np.int32 and (t.min() < 0 or t.max() >= num_vertices):  # int32: checked natively
        bad = (t < 0) | (t >= num_vertices)
        row = int(np.argmax(bad.any(axis=1)))
        raise ValueError(f"triangles[{row}] refers to vertex {int(t[row][bad[row]][0])} "
                         f"but there are {num_vertices} vertices")
    return np.ascontiguousarray(t, np.int32)


def repeated_keys(keys):
    """(n,) bool: the entries of keys (n,) uint64 that are not 0 and that another entry repeats
    (triangle_table's keys: the triangles with a coincident twin). One hash-table pass."""
    return _core.repeated_keys(np.ascontiguousarray(keys, np.uint64))


def coplanar_groups(keys, geo, triangles, candidates, max_group: int):
    """The triangles whose plane keys repeat among candidates (M,) bool, grouped: (rows, start)
    int64, group g being rows[start[g]:start[g + 1]], rows ascending within a group. keys (M,)
    uint64: triangle_table's plane_keys (coplanar.h: the normal up to sign in steps of 1/4096 a
    component and the offset n . v0 in steps of 1 / plane_inv_step); geo: that table's (15, M)
    rows (the normals read for the quad test); triangles (M, 3) int32. A quad's two triangles
    listed one after the other count as one key (alone in its plane, a quad is no group); groups
    of more than max_group triangles are left out. One threaded pass over the keys and a hash of
    the few that may repeat."""
    geo = _rows(geo, 15, "geo")
    t = np.ascontiguousarray(triangles, np.int32)    # (indices only compared, never followed)
    return _core.coplanar_groups(np.ascontiguousarray(keys, np.uint64), geo, t,
                                 np.ascontiguousarray(candidates, np.uint8), int(max_group))


def shifted_plane_keys(geo, candidates, inv_step: float):
    """(M,) uint64: for candidates (M,) bool, coplanar_groups' plane key of each triangle (geo:
    triangle_table's (15, M) rows, v0 and the unit normal read) on the grid shifted by half a bin
    in every component (the same float32 expressions as triangle_table's plane_keys, + 0.5 in
    each bin), 0 where a component falls out of range or is NaN and for the other triangles:
    the overlap check's second grid, where twins on either side of a first bin's edge meet."""
    geo = _rows(geo, 15, "geo")
    return _core.shifted_plane_keys(geo, np.ascontiguousarray(candidates, np.uint8), float(inv_step))


def triangle_table(vertices, triangles, offset_ulps: float, tiny: float = 2.0 ** -100, full=None, keys=None,
                   plane_keys=None, plane_inv_step: float = 0.0):
    """The (15, M) float32 table surface() and sample_triangles() read, and the areas (M,)
    float64, of triangles (M, 3) of vertices (V, 3): rows v0, v1 - v0, v2 - v0 (differences
    in double, rounded once), the unit geometric normal (0 for zero area) and the front-side
    self-intersection step along the normal: of offset_ulps ULPs of the triangle's largest
    |coordinate| (at least tiny) the share the hit point's error along the normal needs,
    sum_a |n_a| ulp(largest |coordinate a|) / ulp(largest) (a plane z = c: ULPs of c), or all of
    it for the triangles where full (M,) is true (those with a coincident twin). keys (M,)
    uint64, optional, is written: an odd order-free hash of each triangle's corners' bits (-0
    as 0; exact copies, in any corner order, have equal keys). plane_keys (M,) uint64, optional,
    is written: each triangle's plane key (coplanar_groups' input) of the v0 and normal it writes,
    the offset in steps of 1 / plane_inv_step (keep |n . v0| * plane_inv_step below 2^21)."""
    v = np.ascontiguousarray(vertices, _F32)
    t = _triangles32(triangles, len(v))
    if full is not None:
        full = np.ascontiguousarray(full, np.uint8)
    return _core.triangle_table(v, t, float(offset_ulps), float(tiny), full, keys, plane_keys, float(plane_inv_step))


def hit_records(geo, normals):
    """(M, 32) float32: per-triangle hit-point records of the table geo (15, M) and its corner
    normals (9, M) or None (native hitrecords.h): what a hit point reads of its triangle on two
    cache lines, with the per-triangle arithmetic done once. Kernels given them (records= of
    surface, continue_paths' surface tuple, shade_bounce's geo_records) give the same bits as
    from the rows; build them again after changing geo or normals."""
    return _core.hit_records(_rows(geo, 15, "geo"), None if normals is None else _rows(normals, 9, "normals"))


def _records(records):
    return None if records is None else np.ascontiguousarray(records, _F32)


def surface(geo, normals, hits, idx, D, records=None):
    """Hit points of the rays idx (all when None) from their hits (HIT_DTYPE, n) and
    directions D (3, n).

    geo (15, M): rows v0, v1 - v0, v2 - v0, unit geometric normal, front-side offset step;
    normals (9, M) (corner-0 normal, corner 1 - 0, corner 2 - 0) or None for flat shading;
    records: hit_records(geo, normals) or None (the rows: the same bits, slower).
    Returns P, ng, ns, P_off (3, k): geometric and shading normals facing the incoming ray
    (ns is ng when normals is None) and P stepped off the surface toward the ray's side."""
    geo = _rows(geo, 15, "geo")
    if normals is not None:
        normals = _rows(normals, 9, "normals")
    hits = np.asarray(hits)
    if hits.dtype != HIT_DTYPE:
        raise ValueError(f"hits must be a HIT_DTYPE array, got {hits.dtype}")
    hits = np.ascontiguousarray(hits)
    if idx is not None:
        idx = np.ascontiguousarray(idx, np.int64)
    out = _core.surface(geo, normals, hits, idx, _rows(D, 3, "D"), _records(records))
    P, ng, P_off = out[0:3], out[3:6], out[6:9]
    ns = ng if normals is None else out[9:12]
    return P, ng, ns, P_off


def uniform2(keys, ka: int, kb: int):
    """Two float32 uniforms in [0, 1) per path for key words keys (2, n) uint32 and the
    dimension words ka, kb (see the renderer's RandomStream, which this matches bit for bit)."""
    return _core.uniform2(_rows(keys, 2, "keys", np.uint32), int(ka), int(kb))


def uniform_pick(keys, ka: int, kb: int):
    """uniform2's two words as a float64 uniform with 32-bit resolution (a choice among many
    lights) and a float32 one (Russian roulette), per path."""
    return _core.uniform_pick(_rows(keys, 2, "keys", np.uint32), int(ka), int(kb))


def cosine_scatter(keys, ka: int, kb: int, ns, ng=None, origins=None, shading_offset=None):
    """Cosine-weighted directions around unit shading normals ns (3, n) from the random numbers
    of (keys, ka, kb): returns wi (3, n), pdf (n,) = cos/pi and ok (n,) bool, false where the
    direction is grazing or below the geometric normals ng (None: ns is the geometric normal).
    With origins (3, n) a fourth result: the bounce rays as RAY_DTYPE records (origins, wi,
    tfar inf, ids 0..n-1), written in the same pass.

    shading_offset = (freq (M,), prim (n,), thr (3, n)): Cycles' shadow terminator shading
    offset. Where ok and freq[prim] > 1, thr (float32, C-contiguous, scaled in place) is
    multiplied by shift_cos_in: cos(acos(c) freq) / c clamped at 0, c = ns . wi."""
    keys = _rows(keys, 2, "keys", np.uint32)
    ns = _rows(ns, 3, "ns")
    if ng is not None:
        ng = _rows(ng, 3, "ng")
    if shading_offset is not None:
        freq, prim, thr = shading_offset
        shading_offset = (np.ascontiguousarray(freq, _F32), _prim32(prim, "shading_offset prim"), thr)
    if origins is None:
        return _core.cosine_scatter(keys, int(ka), int(kb), ns, ng, None, None, shading_offset)
    rays = np.empty(keys.shape[1], RAY_DTYPE)
    wi, pdf, ok = _core.cosine_scatter(keys, int(ka), int(kb), ns, ng, _rows(origins, 3, "origins"), rays,
                                       shading_offset)
    return wi, pdf, ok, rays


def sample_triangles(geo, area, which, P, u1, u2):
    """Light samples on triangles which (n,) of geo (15, M) (rows as in surface(); area (M,)),
    seen from points P (3, n), from the uniforms u1, u2: uniform by solid angle where the
    triangle's longest edge exceeds the distance from P to its centroid, else uniform by area.

    Returns wi (3, n) unit directions toward the sampled points, dist (n,), the solid-angle pdf
    (n,) (0 where the point cannot be seen: edge-on or coincident) and target (3, n), the point
    stepped off the emitter toward P, where a shadow ray must end: along the offset row, by its
    length or, if longer, 8 ULPs of max(|P|, dist) (where a ray from P can drift)."""
    geo = _rows(geo, 15, "geo")
    P = _rows(P, 3, "P")
    return _core.sample_triangles(geo, np.ascontiguousarray(area, _F32), np.ascontiguousarray(which, np.int64), P,
                                  np.ascontiguousarray(u1, _F32), np.ascontiguousarray(u2, _F32))


def rough_rows(params, mat, rho, D, ns):
    """The rough diffuse table (11, n) float32 of n points (Cycles' Oren-Nayar, orennayar.h) for
    next_event's `rough` and rough_scale: material mat[i] (n,) has params[:, mat[i]] (4, M: a,
    b, Ebar the cos-weighted average of E, Eavg Cycles' fit of it; b 0: not rough), rho (3, n)
    its colour, D (3, n) the rays' directions, ns (3, n) the shading normals."""
    return _core.rough_rows(_rows(params, 4, "params"), np.ascontiguousarray(mat, np.int32), _rows(rho, 3, "rho"),
                            _rows(D, 3, "D"), _rows(ns, 3, "ns"))


def rough_scale(rows, wi, ns, thr):
    """thr (3, n) float32, in place: times the rough diffuse factor (Cycles' Oren-Nayar over the
    view-averaged albedo) of each point of rough_rows' table for directions wi (3, n) at ns
    (1 where the point is not rough)."""
    if thr.dtype != _F32 or not thr.flags.c_contiguous or thr.ndim != 2:
        raise ValueError("thr must be a C-contiguous (3, n) float32 array (scaled in place)")
    _core.rough_scale(_rows(rows, 11, "rows"), _rows(wi, 3, "wi"), _rows(ns, 3, "ns"), thr)


def nee_weight(ns, ng, wi, pdf, p_sel, thr, value):
    """Next-event estimation weights, in place: value (3, n) (light radiance / pdf) becomes
    thr x value x cos/pi x MIS / p_sel, with cos = ns.wi, the power heuristic against the cosine
    BSDF (pdf (n,) solid angle, inf for delta lights: weight 1) and light-selection probability
    p_sel (n,). thr (3, n) or None (1); ng (3, n) or None (ns is the geometric normal).
    Returns ok (n,) bool: the sample can contribute (in front of both normals, some positive
    channel); only those need a shadow ray."""
    if value.dtype != _F32 or not value.flags.c_contiguous or value.ndim != 2:
        raise ValueError("value must be a C-contiguous (3, n) float32 array (it is weighted in place)")
    opt = lambda a, name: None if a is None else _rows(a, 3, name)
    return _core.nee_weight(_rows(ns, 3, "ns"), opt(ng, "ng"), _rows(wi, 3, "wi"),
                            np.ascontiguousarray(pdf, _F32), np.ascontiguousarray(p_sel, _F32), opt(thr, "thr"),
                            value)


def shadow_rays(O, wi, dist, target, idx, shorten: float = 1.0):
    """RAY_DTYPE shadow rays for the samples idx (k,) (ids 0..k-1): from O[:, idx] along
    wi / dist, or, where target (3, n) is given and not NaN, toward target over that distance
    times shorten. Returns (rays, valid): valid[j] is False for zero-length rays (their record
    has tfar 0 and is never occluded; discard them)."""
    idx = np.ascontiguousarray(idx, np.int64)
    out = np.empty(len(idx), RAY_DTYPE)
    valid = _core.shadow_rays(_rows(O, 3, "O"), _rows(wi, 3, "wi"), np.ascontiguousarray(dist, _F32),
                              None if target is None else _rows(target, 3, "target"), idx, float(shorten), out)
    return out, valid


class LightChoice:
    """What next_event() picks a light from: R lamp records (dacrt.lamps layout) as entries
    0..R-1, then T emissive triangles (tri_geo (15, T) rows as in surface(), tri_area (T,),
    tri_emission (3, T) radiance; None: no triangles) as entries R..R+T-1, then the
    environment map (a dacrt.lamps.EnvironmentMap; None: none) as entry R+T. Per entry: cdf
    (the choice: entry = first with cdf > u), prob (its probability), no_mis (sampled without
    MIS, weight 1, as a delta light) and shadow (its samples need a shadow ray). Arrays are
    converted once here, not per call.

    tree (a dacrt.lamps.LightTree whose keys are entries; None: none): many-light sampling. Its
    members share one slot of cdf (the first member in entry order holds the mass, the others
    none) and each has prob = that mass; a pick in the slot is passed on to the tree at the
    shadow ray's origin with the shading normal, so a member's selection probability is prob x
    the tree's pdf there.

    tri_prim (T,) int32 (None: not known): the triangle each emissive triangle is, in the
    numbering of next_event's prim: a point on an emissive triangle is not lit by it (a plane
    emits nothing into itself; the sample adds nothing and traces no ray)."""

    def __init__(self, records, cdf, prob, no_mis, shadow, tri_geo=None, tri_area=None, tri_emission=None,
                 environment=None, tree=None, tri_prim=None):
        self.records = np.ascontiguousarray(np.asarray(records, _F32).reshape(-1, _core.LAMP_RECORD_WIDTH))
        self.cdf = cdf
        self.prob = np.ascontiguousarray(prob, _F32)
        self.no_mis = np.ascontiguousarray(no_mis, np.bool_)
        self.shadow = np.ascontiguousarray(shadow, np.bool_)
        self.tri_geo = None if tri_geo is None else _rows(tri_geo, 15, "tri_geo")
        self.tri_area = None if tri_area is None else np.ascontiguousarray(tri_area, _F32)
        self.tri_emission = None if tri_emission is None else _rows(tri_emission, 3, "tri_emission")
        self.tri_prim = None if tri_prim is None else _prim32(tri_prim, "tri_prim")
        if environment is not None and not isinstance(environment, _core.EnvironmentMap):
            raise ValueError(f"environment must be a dacrt.lamps.EnvironmentMap or None, got {type(environment).__name__}")
        self.environment = environment
        if tree is not None and not isinstance(tree, _core.LightTree):
            raise ValueError(f"tree must be a dacrt.lamps.LightTree or None, got {type(tree).__name__}")
        self.tree = tree

    @property
    def cdf(self) -> np.ndarray:
        """The choice's cdf, a read-only float64 copy: its runs (choiceruns.h) are built once
        from it, so it is replaced (lights.cdf = ...), not changed in place."""
        return self._cdf

    @cdf.setter
    def cdf(self, cdf):
        self._cdf = np.array(cdf, np.float64, order="C")
        self._cdf.flags.writeable = False
        self._runs = None

    @property
    def runs(self):
        """(run_cdf, run_entry): the cdf by runs of equal values (_core.choice_runs), which the
        kernels search with a tree instead of every entry; built on first use, once per cdf
        (building them reads every entry: a million emissive triangles in a tree had been a
        scan of ~1M doubles in every kernel call)."""
        if self._runs is None:
            self._runs = _core.choice_runs(self._cdf)
        return self._runs

    @property
    def entries(self) -> int:
        return (len(self.records) + (0 if self.tri_geo is None else self.tri_geo.shape[1])
                + (self.environment is not None))


def next_event(lights: LightChoice, P, P_off, ns, ng, thr, keys, ka: int, kb: int, pick=None, prim=None,
               shorten: float = 1.0, skip_work: bool = True, terminator=None, linking=None, entry=None,
               point=None, bump=None, rough=None):
    """Next-event estimation at n shading points in one pass: pick a light per point (entry 0
    when pick is None, else the entry the uniform pick (n,) float64 falls in), sample it with
    the uniforms of keys (2, n) and dimension words (ka, kb) (the same numbers as uniform2),
    weight the sample as nee_weight with ng None (in front of the shading normal ns (3, n) is
    enough, as in Cycles: below the geometric normal ng (3, n; None: ns) the shadow ray decides;
    throughput thr (3, n) or None) and make its shadow ray as shadow_rays (from P_off (3, n);
    toward a triangle's target point, times shorten). P (3, n): the surface points.

    terminator (needs prim): Cycles' shadow terminator of the points' triangles, a tuple
    (geo (15, M) triangle table, normals (9, M) corner rows, cutoff (M,) geometry offset (0:
    none), freq (M,) shading offset's frequency multiplier 1 / (1 - offset / 2), u, v (n,)
    barycentrics; freq, or cutoff with normals, u and v, may be None): a shadow ray near the
    terminator leaves from the point lifted onto the smooth surface (and, below ng, no longer
    skips its triangle: skip -1), and a sample's value is multiplied by shift_cos_in where
    freq > 1.

    linking = (light_set (entries,) uint8 0..63, receivers (n,) uint64): light linking; a point
    is lit by the entry it picked only where bit light_set[entry] of its receivers is set
    (otherwise the sample adds nothing and traces no ray, as a light that does not reach it).

    entry: an (n,) int32 array filled in place with the entry each point picked (for routing
    the light by its source, e.g. light groups).

    point: a (3, n) float32 array filled in place, for the points that picked an emissive
    triangle, with the point sampled on it (the shadow ray's target, a few ULPs in front of the
    triangle), e.g. to read a textured emission there; other columns are left as they were.

    bump (4, n): for normal-mapped points, ns being the mapped normal, the smooth normal before
    the map (rows 0-2; equal to ns where there is no map) and the material's Bump Map
    Correction (row 3, 0 or 1): each sample is multiplied by Cycles' bump shadowing term
    (bump_shadowing: 0 below the smooth surface, the GGX softening with correction).

    rough (11, n): rough diffuse points (Cycles' Oren-Nayar; orennayar.h, rows from
    addon/roughdiffuse.vertex_rows; b (row 4) 0 where a point is Lambertian): each sample's
    value is multiplied by that BSDF's value over the view-averaged albedo the throughput holds.

    Returns value (3, n) (each sample's contribution), contrib (n,) bool (it adds to the image
    unless its shadow ray is occluded), rays (m,) RAY_DTYPE (ids 0..m-1, in point order), send
    (m,) int64 (the point of each ray), skip (m,) int32 (prim[send], the triangle each ray
    leaves; None without prim) and how many samples could not contribute (no ray traced).
    skip_work False: every sample that is not zero-length gets its ray (value 0 where it cannot
    contribute), the reference the skips are tested against."""
    P = _rows(P, 3, "P")
    n = P.shape[1]
    if entry is not None and not (isinstance(entry, np.ndarray) and entry.dtype == np.int32
                                  and entry.flags.c_contiguous and entry.flags.writeable):
        raise ValueError("entry must be a writeable C-contiguous int32 array (written in place)")
    if point is not None and not (isinstance(point, np.ndarray) and point.dtype == np.float32
                                  and point.flags.c_contiguous and point.flags.writeable):
        raise ValueError("point must be a writeable C-contiguous float32 array (written in place)")
    value = np.empty((3, n), _F32)
    contrib = np.empty(n, np.bool_)
    rays = np.empty(n, RAY_DTYPE)
    send = np.empty(n, np.int64)
    skip = None if prim is None else np.empty(n, np.int32)
    opt = lambda a, name: None if a is None else _rows(a, 3, name)
    m, skipped = _core.next_event(
        lights.records, lights.cdf, lights.prob, lights.no_mis, lights.shadow, lights.tri_geo, lights.tri_area,
        lights.tri_emission, lights.environment, P, _rows(P_off, 3, "P_off"), _rows(ns, 3, "ns"), opt(ng, "ng"), opt(thr, "thr"),
        _rows(keys, 2, "keys", np.uint32), int(ka), int(kb),
        None if pick is None else np.ascontiguousarray(pick, np.float64),
        None if prim is None else _prim32(prim, "prim"), float(shorten), bool(skip_work),
        value, contrib, rays, send, skip, _terminator(terminator),
        None if linking is None else (np.ascontiguousarray(linking[0], np.uint8),
                                      np.ascontiguousarray(linking[1], np.uint64)), entry, point,
        None if bump is None else _rows(bump, 4, "bump"), lights.tree, lights.tri_prim,
        None if rough is None else _rows(rough, 11, "rough"), None if lights.tree is None else lights.runs)
    return value, contrib, rays[:m], send[:m], None if skip is None else skip[:m], skipped


def shade_bounce(lights: LightChoice, hits, hit, live, albedo, thr, u_rr, geo, normals, D, pid, keys, pick,
                 nee_words, shorten: float = 1.0, skip_work: bool = True, scatter_words=None, rough=None,
                 records=None, draw=None):
    """A diffuse path vertex in one native pass, block by block: continue_paths(hits, hit, live,
    albedo, thr, u_rr, surface=(geo, normals, D), take=(pid, keys, pick)), then next_event at
    the survivors (lights, their P, P_off, ns, ng (None where normals is None), thr, keys,
    pick and prim, dimension words nee_words = (ka, kb), shorten, skip_work; no terminator,
    linking or bump) and, with scatter_words = (ka, kb), cosine_scatter(keys, ka, kb, ns, ng,
    origins=P_off) of the survivors: the same bits as those three calls. rough = (materials
    (M,) of the triangles, params (4, m), colours (3, m)) or None: rough diffuses, as
    rough_rows' table of the survivors in next_event's rough and rough_scale after the scatter.
    records: hit_records(geo, normals) or None (as surface()). hit None: the hits are the records
    with prim >= 0 (the pass reads prim anyway; the caller then makes no flags from them).
    draw = (ka, kb, pick, roulette) or None: the pass draws the uniforms uniform_pick(keys, ka,
    kb) gives, instead of taking them as arrays (u_rr and pick must then be None): with
    roulette its second as u_rr, with pick its first as the survivors' pick; the same bits,
    without the arrays' writes and reads or a call per bounce.

    Returns (black, roulette, (thr, (P, ng, ns, P_off), prim, pid, keys, pick), (value, contrib,
    rays, send, skip, skipped) as next_event's, (wi, pdf, ok, rays) as cosine_scatter's or None
    without scatter_words)."""
    hits = np.asarray(hits)
    if hits.dtype != HIT_DTYPE:
        raise ValueError(f"hits must be a HIT_DTYPE array, got {hits.dtype}")
    ka, kb = scatter_words if scatter_words is not None else (0, 0)
    if draw is not None:
        if u_rr is not None or pick is not None:
            raise ValueError("draw takes the place of u_rr and pick: give those as None")
        draw = (int(draw[0]), int(draw[1]), bool(draw[2]), bool(draw[3]))
    black, rr, paths, nee, bsdf = _core.shade_bounce(
        lights.records, lights.cdf, lights.prob, lights.no_mis, lights.shadow, lights.tri_geo, lights.tri_area,
        lights.tri_emission, lights.environment, lights.tree, lights.tri_prim, np.ascontiguousarray(hits),
        None if hit is None else np.ascontiguousarray(hit, np.bool_), np.ascontiguousarray(live, np.bool_),
        _rows(albedo, 3, "albedo"),
        None if thr is None else _rows(thr, 3, "thr"), None if u_rr is None else np.ascontiguousarray(u_rr, _F32),
        _rows(geo, 15, "geo"), None if normals is None else _rows(normals, 9, "normals"), _rows(D, 3, "D"),
        np.ascontiguousarray(pid, np.int64), _rows(keys, 2, "keys", np.uint32),
        None if pick is None else np.ascontiguousarray(pick, np.float64), int(nee_words[0]), int(nee_words[1]),
        float(shorten), bool(skip_work), scatter_words is not None, int(ka), int(kb), RAY_DTYPE,
        None if rough is None else (np.ascontiguousarray(rough[0], np.int32), _rows(rough[1], 4, "rough params"),
                                    _rows(rough[2], 3, "rough colours")), _records(records),
        None if lights.tree is None else lights.runs, draw)
    thr_out, surf, prim, pid_out, keys_out, pick_out = paths
    ng = surf[3:6]
    points = (surf[0:3], ng, ng if normals is None else surf[9:12], surf[6:9])
    value, contrib, rays, send, skip, m, skipped = nee
    return (black, rr, (thr_out, points, prim, pid_out, keys_out, pick_out),
            (value, contrib, rays[:m], send[:m], skip[:m], skipped), bsdf)


def _terminator(t):
    if t is None:
        return None
    geo, normals, cutoff, freq, u, v = t
    f32 = lambda a: np.ascontiguousarray(a, _F32)
    opt = lambda a: None if a is None else f32(a)
    return (f32(geo), opt(normals), opt(cutoff), opt(freq), opt(u), opt(v))


def accumulate_masked(L, pid, values, mask, clamp: float = np.inf) -> None:
    """L[:, pid[i]] += values[:, i] where mask[i] (n,) bool; pid (n,) distinct columns of L (every
    one, masked or not); L (3, N) float32 C-contiguous, values (3, n). clamp: each value is
    scaled down to an absolute channel sum of at most clamp first (Cycles' sample clamp; inf:
    none)."""
    _check_added_to(L)
    _core.accumulate_masked(L, np.ascontiguousarray(pid, np.int64), _rows(values, 3, "values"),
                            np.ascontiguousarray(mask, np.bool_), float(clamp))


def gather_emission(hits, hit, emission, emissive, tri_prob, area, geo, O, D, thr, pdf, pid, L,
                    clamp: float = np.inf, tree=None, tri_key=None, N=None, receivers=None) -> int:
    """Add the emission that rays meet on emissive triangles to L (3, N) in place (two-sided).

    Rays i with hit[i] (hit None: every ray that met a triangle, read from hits in place, so the
    caller makes no flags) whose triangle hits['prim'][i] has emissive[prim] (bool (M,)) add
    emission[:, prim] ((3, M) radiance) x thr[:, i] (None: 1) x, when tri_prob (M,) is given
    (BSDF rays), the power-heuristic weight against light-sampling that triangle,
    1 / (1 + (tri_prob pdf_light / pdf)^2) with pdf (n,) the rays' BSDF pdf and pdf_light the
    solid-angle pdf sample_triangles has from the ray origin O (3, n) for the direction D (3, n),
    into column pid[i] (distinct), clamped as accumulate_masked's. With a light tree
    (dacrt.lamps.LightTree) and tri_key (M,) int32 (a triangle's key in it, or -1), a member's
    selection probability is tri_prob x the tree's pdf at O with N (3, n), the normal the rays'
    vertices sampled lights with, and receivers (n,) uint64 (light linking: the receiver masks
    of their objects; None: every set).
    Returns how many rays met emission."""
    _check_added_to(L)
    return _core.gather_emission(hits, None if hit is None else np.ascontiguousarray(hit, np.bool_),
                                 _rows(emission, 3, "emission"),
                                 np.ascontiguousarray(emissive, np.bool_),
                                 None if tri_prob is None else np.ascontiguousarray(tri_prob, _F32),
                                 np.ascontiguousarray(area, _F32), _rows(geo, 15, "geo"), _rows(O, 3, "O"),
                                 _rows(D, 3, "D"),
                                 None if thr is None else _rows(thr, 3, "thr"),
                                 None if pdf is None else np.ascontiguousarray(pdf, _F32),
                                 np.ascontiguousarray(pid, np.int64), L, float(clamp), tree,
                                 None if tri_key is None else np.ascontiguousarray(tri_key, np.int32),
                                 None if N is None else _rows(N, 3, "N"),
                                 None if receivers is None else np.ascontiguousarray(receivers, np.uint64))


def camera_rays(ortho: bool, frame, rx, ry, records: bool = False, lens=None, sheared: bool = False):
    """Rays through raster positions rx, ry (n,) of a camera frame (27 float32: camera-to-world
    rotation row-major (9), position (3), orthographic origin base (3), raster -> viewplane
    map sx0, sx_scale, sy0, sy_scale (4), tan(fov / 2), clip start, clip range, then depth of
    field: aperture radius (0: pinhole), focus distance, blades (< 3: round), blade rotation,
    1 / aperture ratio): origins and unit directions (3, n) on the clip-start plane, tmax (n,)
    to the clip-end plane, and with records=True their RAY_DTYPE records (ids 0..n-1) from the
    same pass. lens: (u, v) uniforms (n,) picking each ray's lens point when the aperture is
    open (Cycles' thin lens); without them every ray is a pinhole ray. sheared: the rotation's
    columns are not orthogonal (a camera under a rotated, non-uniformly scaled parent); then
    each world direction is normalised after it and the clip distances are laid along it, as
    Cycles does, instead of starting on the sheared image of the clip-start plane."""
    rx = np.ascontiguousarray(rx, _F32)
    rays = np.empty(len(rx), RAY_DTYPE) if records else None
    lu, lv = (None, None) if lens is None else (np.ascontiguousarray(lens[0], _F32), np.ascontiguousarray(lens[1], _F32))
    O, D, tmax = _core.camera_rays(bool(ortho), np.ascontiguousarray(frame, _F32), rx,
                                   np.ascontiguousarray(ry, _F32), rays, lu, lv, bool(sheared))
    return (O, D, tmax, rays) if records else (O, D, tmax)


def sample_sums(values, weights=None):
    """values (..., S) summed over their last axis in float64, sample 0 first: the film's
    per-pixel sums of a block of S samples. weights (S,): each sample's factor (None: 1).
    Values are taken as float32 (the samples' own precision). One threaded pass."""
    return _core.sample_sums(np.ascontiguousarray(values, _F32),
                             None if weights is None else np.asarray(weights, np.float64))


def take_columns(idx, *arrays):
    """[a[..., idx] for a in arrays] in one threaded pass: arrays are (n,) or (rows, n) with the
    same n (any 1, 2, 4 or 8-byte dtype); idx (k,) indexes their last axis. None stays None."""
    idx = np.ascontiguousarray(idx, np.int64)
    return _refill(arrays, _core.take_columns(idx, _present(arrays)))


def drop_columns(keep, *arrays, rays=None):
    """In place, the columns where keep (n,) bool is false dropped from per-path arrays ((n,) or
    (rows, n), C-contiguous, writeable, not sharing memory; None stays None) and from the
    RAY_DTYPE records rays (None: none): the kept columns move forward in order, the moved
    records' ids become their new positions. The same as take_columns(np.flatnonzero(keep),
    ...) and records packed again, but only the columns past the first drop move and nothing
    is allocated. Returns the arrays' (rows, m) views of their buffers' first m columns, and
    rays[:m] last when rays is given."""
    keep = np.ascontiguousarray(keep, np.bool_)
    m = _core.drop_columns(keep, [a for a in arrays if a is not None], rays)   # (no copies: in place)
    out = [None if a is None else a[:m] if a.ndim == 1 else a.reshape(-1)[:a.shape[0] * m].reshape(a.shape[0], m)
           for a in arrays]
    return out + [rays[:m]] if rays is not None else out


def _present(arrays):
    """The arrays that are not None, C-contiguous, for a native call that takes columns."""
    return [np.ascontiguousarray(a) for a in arrays if a is not None]


def _refill(arrays, taken):
    """taken (one result per array that is not None) with None back where arrays had None."""
    taken = iter(taken)
    return [None if a is None else next(taken) for a in arrays]


def face_normals(vertices, triangles):
    """Unit geometric normals (M, 3) float32 of triangles (M, 3) of float64 vertices (V, 3),
    computed in double, by the winding (v1 - v0) x (v2 - v0), and good (M,): False (normal 0)
    for zero-area or non-finite triangles. One threaded pass."""
    v = np.ascontiguousarray(vertices, np.float64)
    return _core.face_normals(v, _triangles32(triangles, len(v)))


def transform_points(points, linear, offset, out):
    """out (k, n, 3) float32 or float64 = points (n, 3) through k 3x3 maps linear (k, 3, 3) plus
    offset (k, 3) (None: none); each component ((l0 x + l1 y) + l2 z) + o in float64, rounded once
    to out's dtype. Written in place and returned. One threaded pass."""
    p = np.ascontiguousarray(points, np.float32)
    lin = np.ascontiguousarray(linear, np.float64)
    off = None if offset is None else np.ascontiguousarray(offset, np.float64)
    _core.transform_points(p, lin, off, out)
    return out


def corner_rows(per_corner):
    """(M, 3, c) per-corner values -> (3c, M) float32 rows: corner 0, corner 1 - corner 0,
    corner 2 - corner 0 (what barycentric interpolation reads). One threaded pass."""
    return _core.corner_rows(np.ascontiguousarray(per_corner, _F32))


def island_roots(vertex_count: int, edges) -> np.ndarray:
    """(vertex_count,) int64: each vertex's root in Cycles' disjoint set (util/disjoint_set.h)
    after joining edges ((m, 2) vertex indices) in their order, union by rank with path
    compression, as attr_create_random_per_island numbers a mesh's islands. ValueError for an
    index outside 0..vertex_count-1."""
    e = np.asarray(edges).reshape(-1, 2)
    if e.size and (e.min() < 0 or e.max() >= vertex_count):
        raise ValueError(f"edges index vertices outside 0..{int(vertex_count) - 1}")
    return _core.island_roots(int(vertex_count), np.ascontiguousarray(e, np.int32))


def normals_flat(normals, geo, tol: float) -> bool:
    """Whether every corner normal of normals (M, 3, 3) is within tol of its triangle's geometric
    normal (geo rows 9:12, geo as triangle_table makes it)."""
    return bool(_core.normals_flat(np.ascontiguousarray(normals, _F32), _rows(geo, 15, "geo"), float(tol)))


def pixel_samples(pixel, sample, width: int, k0: int, k1: int, ka: int, kb: int, table):
    """Camera samples for (pixel, sample) pairs (n,) (pixel = y * width + x, both < 2**32):
    the path keys (2, n) uint32 (splitmix64 of pixel << 32 | sample keyed by the 64-bit words
    k0, k1) and the raster positions rx, ry (n,) = pixel corner + a pixel-filter offset per axis,
    looked up in the inverse-CDF table (linear interpolation) with the uniforms of the key and
    dimension words ka, kb; sample 0 with 0.5 instead (the pixel centre, as Cycles)."""
    return _core.pixel_samples(np.ascontiguousarray(pixel, np.int64), np.ascontiguousarray(sample, np.int64),
                               int(width), int(k0), int(k1), int(ka), int(kb), np.ascontiguousarray(table, _F32))


def block_samples(pixels, s0: int, ns: int, width: int, k0: int, k1: int, ka: int, kb: int, table):
    """pixel_samples of a pixel-major block, every pixel of pixels (P,) for the samples s0 ..
    s0 + ns - 1 (path i: pixel pixels[i // ns], sample s0 + i % ns), the same numbers as
    pixel_samples(np.repeat(pixels, ns), np.tile(np.arange(s0, s0 + ns), P), ...) without
    those two arrays (and their checks, per pixel here instead of per path)."""
    return _core.block_samples(np.ascontiguousarray(pixels, np.int64), int(s0), int(ns), int(width), int(k0), int(k1),
                               int(ka), int(kb), np.ascontiguousarray(table, _F32))


def continue_paths(hits, hit, live, albedo, thr=None, u_rr=None, surface=None, take=()):
    """Which paths go on after a vertex, and with what throughput.

    hits (n,) HIT_DTYPE; hit (n,) bool: the ray hit a surface that shades; live (M,) bool per
    triangle: not black; albedo (3, M); thr (3, n) path throughput before this vertex (None: 1);
    u_rr (n,) uniforms for Russian roulette (None: no roulette), survival probability
    q = min(sqrt(max channel of thr), 1) as Cycles. Returns (idx (k,) int64 of the survivors,
    their throughput albedo[prim] x thr / q (3, k), paths ended on black surfaces, paths ended
    by roulette).

    surface = (geo, normals, D) or (geo, normals, D, records) and take (per-path arrays, (n,) or
    (rows, n), None kept None) ask for more of the survivors in the same native pass: the return
    then ends with (P, ng, ns, P_off) as surface(geo, normals, hits, idx, D, records) gives them (None without
    surface), their triangles prim (k,) int32 (None without surface) and the columns idx of
    each array of take, as take_columns(idx, *take)."""
    hits = np.asarray(hits)
    if hits.dtype != HIT_DTYPE:
        raise ValueError(f"hits must be a HIT_DTYPE array, got {hits.dtype}")
    geo = normals = D = records = None
    if surface is not None:
        geo, normals, D, *rest = surface
        records = rest[0] if rest else None
        geo, D = _rows(geo, 15, "geo"), _rows(D, 3, "D")
        if normals is not None:
            normals = _rows(normals, 9, "normals")
    idx, thr_out, black, rr, surf, prim, taken = _core.continue_paths(
        np.ascontiguousarray(hits), np.ascontiguousarray(hit, np.bool_), np.ascontiguousarray(live, np.bool_),
        _rows(albedo, 3, "albedo"), None if thr is None else _rows(thr, 3, "thr"),
        None if u_rr is None else np.ascontiguousarray(u_rr, _F32), geo, normals, D, _present(take),
        _records(records))
    if surface is None and not take:
        return idx, thr_out, black, rr
    points = None
    if surf is not None:
        ng = surf[3:6]
        points = (surf[0:3], ng, ng if normals is None else surf[9:12], surf[6:9])
    return idx, thr_out, black, rr, points, prim, _refill(take, taken)


NOISE_TYPES = {'FBM': 0, 'MULTIFRACTAL': 1, 'HYBRID_MULTIFRACTAL': 2, 'RIDGED_MULTIFRACTAL': 3,
               'HETERO_TERRAIN': 4}


def _per_point(v):
    """A texture parameter as the kernels take it: float32 (1,) for one value, (n,) per point."""
    return np.ascontiguousarray(np.atleast_1d(np.asarray(v, _F32)).reshape(-1))


def noise_texture(points, scale, detail, roughness, lacunarity, distortion, normalize: bool, color: bool,
                  kind: str = 'FBM', offset=0.0, gain=1.0):
    """Cycles' Noise Texture at unscaled points (n, d): d 1 (W), 2 (x, y), 3 (x, y, z) or
    4 (x, y, z, W): (fac (n,), colour (n, 3) or None).
    Parameters: one value, or one per point (n,). Perlin noise on Bob Jenkins' lookup3 hash,
    octaves summed as Cycles' noise_fbm (the fractional octave mixed in; normalize: fBM only)
    or its multifractals (kind, a NOISE_TYPES name, reading offset and gain where Cycles does),
    the colour's other channels at Cycles' seeded offsets; float32 in Cycles' order. One
    threaded pass."""
    if kind not in NOISE_TYPES:
        raise ValueError(f"kind must be one of {', '.join(NOISE_TYPES)}, got {kind!r}")
    param = _per_point
    return _core.noise_texture(np.ascontiguousarray(points, _F32), param(scale), param(detail), param(roughness),
                               param(lacunarity), param(distortion), bool(normalize), bool(color),
                               NOISE_TYPES[kind], param(offset), param(gain))


VORONOI_TEXTURE_METRICS = {'EUCLIDEAN': 0, 'MANHATTAN': 1, 'CHEBYCHEV': 2, 'MINKOWSKI': 3}
VORONOI_FEATURES = {'F1': 0, 'F2': 1, 'SMOOTH_F1': 2, 'DISTANCE_TO_EDGE': 3, 'N_SPHERE_RADIUS': 4}


def voronoi_texture(points, scale, detail, roughness, lacunarity, smoothness, exponent, randomness,
                    feature: str = 'F1', metric: str = 'EUCLIDEAN', normalize: bool = False):
    """Cycles' Voronoi Texture node (svm_node_tex_voronoi) at unscaled points (n, d): d 1 (W),
    2 (x, y), 3 (x, y, z) or 4 (x, y, z, W). Parameters: one value or one per point (n,),
    clamped as Cycles clamps them (Detail to [0, 15], Roughness and Randomness to [0, 1],
    Smoothness / 2 to [0, 0.5]). feature: a VORONOI_FEATURES name; metric: a
    VORONOI_TEXTURE_METRICS name (1D reads none). Returns (distance (n,), colour (n, 3), position
    (n, 4): x, y, z and W, radius (n,)): what the feature gives, zeros elsewhere (Distance to Edge
    a distance only, N-Sphere Radius a radius only). F1, Smooth F1 and F2 summed over Detail's
    octaves as Cycles' fractal_voronoi_x_fx, Distance to Edge as fractal_voronoi_distance_to_edge;
    float32 in Cycles' order. One threaded pass."""
    if metric not in VORONOI_TEXTURE_METRICS:
        raise ValueError(f"metric must be one of {', '.join(VORONOI_TEXTURE_METRICS)}, got {metric!r}")
    if feature not in VORONOI_FEATURES:
        raise ValueError(f"feature must be one of {', '.join(VORONOI_FEATURES)}, got {feature!r}")
    param = _per_point
    return _core.voronoi_texture(np.ascontiguousarray(points, _F32), param(scale), param(detail), param(roughness),
                                 param(lacunarity), param(smoothness), param(exponent), param(randomness),
                                 VORONOI_FEATURES[feature], VORONOI_TEXTURE_METRICS[metric], bool(normalize))


def byte_texels(buf, byte_floats, associate: bool = False, floats: bool = True):
    """An 8-bit image's texels from Blender's float buffer buf (..., c), c in 1..4 (its values
    k/255), or from its bytes (uint8 buf): (rgba (..., 4) float32 with grey and alpha expanded
    (from bytes: byte_floats[k]; None unless `floats`), bytes (..., 4) uint8 rint(255 rgba),
    those associated as Cycles does in bytes (c a / 255) or None, exact: whether every colour
    value is byte_floats[its byte], Blender's own float for it). One threaded pass."""
    table = np.ascontiguousarray(byte_floats, _F32)
    buf = np.ascontiguousarray(buf, np.uint8 if np.asarray(buf).dtype == np.uint8 else _F32)
    return _core.byte_texels(buf, table, bool(associate), bool(floats))


def byte_lookup(k8, table, rgba) -> None:
    """rgba[..., :3] = table[k8[..., :3]] in place: bytes (..., 4) uint8 to floats by a (256,)
    table (rgba (..., 4) float32, alpha untouched). One threaded pass."""
    _core.byte_lookup(np.ascontiguousarray(k8, np.uint8), np.ascontiguousarray(table, _F32), rgba)
