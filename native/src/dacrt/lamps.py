"""Analytic lamps as native per-ray kernels (threaded, GIL released).

A lamp is a record of RECORD_WIDTH float32 (layout: `record_layout()`, documented field by field
in native/cpp/lamps.h): point (delta, sphere, or a disk facing the point), spot (a point lamp
with a smooth or hard elliptical cone), sun (delta direction or uniform cone), area (rectangle or
ellipse, optional spread) and a uniform background. A renderer passes all its lamps as one
(R, RECORD_WIDTH) array, so sampling and gathering every lamp is one pass over the rays instead
of one numpy pass per lamp and operation. Vectors are (3, n) float32 structure-of-arrays.
An equirectangular environment map is a light of its own (`environment_map`; its mapping,
tables and pdf are documented in native/cpp/environment.h), sampled in proportion to its
radiance.
Units and formulas follow the renderer's Python lamp classes (Cycles' conventions), which the
tests compare these kernels against.
"""
from __future__ import annotations

import numpy as np

from . import _core
from .shading import _check_added_to
from . import HIT_DTYPE as _HIT_DTYPE  # (set before the package imports this module)

__all__ = ["RECORD_WIDTH", "KINDS", "record_layout", "lamp_sample", "lamp_gather", "ies_register", "ies_lookup", "ies_live", "IesProfile", "IES_MAX_TABLES", "EnvironmentMap", "texel_stats", "LightTree", "light_tree",
           "environment_map"]

RECORD_WIDTH = int(_core.LAMP_RECORD_WIDTH)
# kind codes (field 'kind'); shape codes per kind (field 'shape')
KINDS = {"POINT": 0, "SPOT": 1, "SUN": 2, "AREA": 3, "BACKGROUND": 4}

_F32 = np.float32


def record_layout() -> dict:
    """Field name -> (offset, width) in float32 of a lamp record, as the native struct has it."""
    return {k: tuple(v) for k, v in _core.lamp_record_layout().items()}


def _f32(a) -> np.ndarray:
    return np.ascontiguousarray(a, _F32)


def _f32_1d(a) -> np.ndarray:
    """a as float32 without a copy where it is one already, any stride (lamp_gather reads a
    view of the hit records' t in place); else a contiguous float32 copy."""
    a = np.asarray(a)
    return a if a.dtype == _F32 and a.ndim == 1 else np.ascontiguousarray(a, _F32)


def _records(records) -> np.ndarray:
    r = np.ascontiguousarray(records, _F32)
    if r.ndim != 2 or r.shape[1] != RECORD_WIDTH:
        raise ValueError(f"records must have shape (R, {RECORD_WIDTH}), got {r.shape}")
    return r


def _index32(a, limit: int, name: str) -> np.ndarray:
    """int32 copy of an integer array; values outside [0, limit) become -1 (so none can wrap
    into range on the conversion)."""
    a = np.asarray(a)
    if a.size == 0:
        a = a.astype(np.int32)                     # np.asarray([]) is float64
    if a.dtype.kind not in "iu":
        raise ValueError(f"{name} must be an integer array, got dtype {a.dtype}")
    if a.dtype != np.int32:
        a = np.where((a >= 0) & (a < limit), a, -1)
    return np.ascontiguousarray(a, np.int32)


def lamp_sample(records, entry, P, u1, u2, out=None):
    """Light samples toward points P (3, n) with uniforms u1, u2 (n,): sample i uses lamp
    records[entry[i]] when 0 <= entry[i] < R; other samples are left as they are in `out`
    (another sampler, e.g. emissive triangles, fills them).

    out: (wi (3, n), dist (n,), value (3, n), pdf (n,)), C-contiguous float32 arrays written in
    place; None: new arrays, zero for samples without a lamp. Returns those four arrays: unit
    direction toward the lamp, shadow-ray length (inf at infinity), value = radiance / pdf (RGB,
    0 where the lamp cannot reach the point) and the solid-angle pdf (inf for delta lamps)."""
    records = _records(records)
    P = _f32(P)
    if P.ndim != 2 or P.shape[0] != 3:
        raise ValueError(f"P must have shape (3, n), got {P.shape}")
    n = P.shape[1]
    if out is None:
        out = (np.zeros((3, n), _F32), np.zeros(n, _F32), np.zeros((3, n), _F32), np.zeros(n, _F32))
    wi, dist, value, pdf = out
    _core.lamp_sample(records, _index32(entry, len(records), "entry"), P, _f32(u1), _f32(u2), wi, dist, value, pdf)
    return wi, dist, value, pdf


def lamp_gather(records, lamps, O, D, t_surf, miss, pid, L, thr=None, pdf_bsdf=None, lamp_prob=None,
                clamp: float = np.inf, tree=None, lamp_key=None, N=None, receivers=None) -> None:
    """Add to L (3, N) float32, in place, what rays (O, D) (3, n) see of the lamps
    records[lamps] (lamps: record indices, in the order their light is added).

    A finite lamp counts where the ray meets it at t < t_surf (n,) (the surface hit, or the
    ray's length); a lamp at infinity (sun, background) counts where miss (n,) bool is set, or,
    given the tracer's hit records (n,) (HIT_DTYPE) as miss, where their prim < 0, read in place
    (the caller then makes no flags); miss may be None where no lamp is at infinity: nothing
    else reads it.
    Lamps are not geometry: a ray collects every lamp it passes. L[:, pid[i]] += thr x Le x w
    (pid (n,) distinct column indices; thr (3, n) path throughput or None = 1). For BSDF rays
    give lamp_prob (R,) (each record's light-selection probability) and pdf_bsdf (n,): w is the
    power heuristic 1 / (1 + (lamp_prob pdf_lamp / pdf_bsdf)^2) against light sampling; camera
    rays give neither (w = 1). clamp: each lamp's contribution to a ray is scaled down to an
    absolute channel sum of at most clamp (Cycles' sample clamp; inf: none). With a light tree
    (LightTree) and lamp_key (R,) int32 (a record's key in it, or -1), a member's selection
    probability is lamp_prob x the tree's pdf at the ray's origin with N (3, n), the normal its
    vertex sampled lights with, and receivers (n,) uint64 (light linking: the receiver mask of
    that vertex's object; None: every set)."""
    _check_added_to(L)
    records = _records(records)
    lamps = np.asarray(lamps)
    if lamps.size == 0:
        lamps = lamps.astype(np.int32)             # np.asarray([]) is float64
    if lamps.dtype.kind not in "iu":
        raise ValueError(f"lamps must be an integer array of record indices, got dtype {lamps.dtype}")
    if lamps.size and (lamps.min() < 0 or lamps.max() >= len(records)):
        raise ValueError(f"lamps must be record indices 0..{len(records) - 1}, got {lamps.tolist()}")
    pid = np.asarray(pid)
    if pid.dtype.kind not in "iu":
        raise ValueError(f"pid must be an integer array of columns of L, got dtype {pid.dtype}")
    miss = None if miss is None else np.asarray(miss)
    if miss is not None and miss.dtype != np.bool_ and miss.dtype != _HIT_DTYPE:
        raise ValueError(f"miss must be a bool array or the tracer's hit records (HIT_DTYPE), got dtype {miss.dtype}")
    opt = lambda a: None if a is None else _f32(a)
    _core.lamp_gather(records, np.ascontiguousarray(lamps, np.int32), opt(lamp_prob), _f32(O), _f32(D), _f32_1d(t_surf),
                      None if miss is None else np.ascontiguousarray(miss), opt(thr), opt(pdf_bsdf),
                      np.ascontiguousarray(pid, np.int64), L,
                      float(clamp), tree, None if lamp_key is None else np.ascontiguousarray(lamp_key, np.int32),
                      opt(N), None if receivers is None else np.ascontiguousarray(receivers, np.uint64))


EnvironmentMap = _core.EnvironmentMap
LightTree = _core.LightTree


def light_tree(lo, hi, axis, cos_o, cos_e, energy, key, group=None, set=None, radius=None) -> LightTree:
    """A light tree (many-light sampling, native/cpp/lighttree.h) over m lights: boxes lo, hi
    (3, m), emission cones (unit axis (3, m), cos of the spread cos_o (m,), -1 for every
    direction, and of the falloff beyond it cos_e (m,)), energy (m,) > 0 (on-axis intensity:
    irradiance energy / d^2 at distance d) and distinct keys (m,) >= 0 (e.g. light-choice
    entries). tree.sample(P (3, n), u (n,) float64, N=None) gives each point's key and its
    probability (N (3, n): the points' unit normals; lights below their horizon are not picked);
    tree.pdf(P, key, N=None) that probability for given keys (0 for non-members). group (m,) >= 0 or None:
    lights with the same group form one leaf, within which a point picks by energy alone (e.g.
    the triangles of one emissive object). set (m,) uint8 0..63 or None: light linking's light
    set of each light; sample and pdf then take receivers (n,) uint64, each point's receiver
    mask (bit s: lit by set s), and never pick a light of a set the point is not lit by.
    radius (m,) >= 0 (inf: none) or None: each light's own bounding sphere about its box's centre,
    which a leaf of that light alone takes where it is tighter than the box's (a tilted area
    light's box holds a sphere up to sqrt(3)x its own)."""
    f32 = lambda a: np.ascontiguousarray(a, np.float32)
    return LightTree(f32(lo), f32(hi), f32(axis), f32(cos_o), f32(cos_e), np.ascontiguousarray(energy, np.float64),
                     np.ascontiguousarray(key, np.int32), None if group is None else np.ascontiguousarray(group, np.int32),
                     None if set is None else np.ascontiguousarray(set, np.uint8),
                     None if radius is None else f32(radius))


def environment_map(rgb, to_map=None, interpolation: str = "Linear", srgb: bool = False, scale=None) -> EnvironmentMap:
    """An environment light from rgb (h, w, 3 or more channels, the first three RGB: an image's
    RGBA is taken as it is, its alpha unread) float32 linear radiance (row 0 at the bottom, the
    -Z pole) times scale ((3,), the strength; None: 1), or uint8 bytes k read as float32
    k x 1/255 (an 8-bit image's, as the export's floats of them), the orthogonal to_map (3, 3) taking
    world directions to the map's frame (None: identity) and 'Linear' (bilinear) or 'Closest'
    lookup. With srgb, rgb is sRGB-encoded (as Cycles keeps an 8-bit image): lookups blend it,
    decode the blend and multiply by scale, and the map is sampled by its decoded texels. A NaN
    or infinite texel channel reads 0 in every lookup blending it in (as Cycles' film drops its
    NaN blend) and as 0 in the importance. The tables are built on all threads, the same bits on
    any number of them.

    The object offers eval(D (3, n)) -> (radiance (3, n), solid-angle pdf (n,)),
    sample(u1, u2 (n,)) -> (wi (3, n), radiance / pdf (3, n), pdf (n,)) and
    gather(prob, D, miss, thr, pdf_bsdf, pid, L, clamp=inf): what rays that missed everything
    see, added to L (3, N) in place, MIS-weighted against sampling the map with probability
    prob (0: camera rays, weight 1; then pdf_bsdf is None), each ray's contribution clamped as
    lamp_gather's."""
    if interpolation not in ("Linear", "Closest"):
        raise ValueError(f"interpolation must be 'Linear' or 'Closest', got {interpolation!r}")
    m = np.eye(3) if to_map is None else to_map
    rgb = np.ascontiguousarray(rgb, np.uint8 if getattr(rgb, 'dtype', None) == np.uint8 else _F32)
    return _core.EnvironmentMap(rgb, np.ascontiguousarray(m, _F32),
                                interpolation == "Closest", bool(srgb),
                                None if scale is None else np.ascontiguousarray(scale, _F32).reshape(3))


def texel_stats(texels):
    """(how many texels hold a non-finite RGB value, whether a finite RGB value is negative,
    whether any RGB value is above 0) of float32 texels (..., channels >= 3, RGB first): one
    threaded pass, no temporaries."""
    return _core.texel_stats(np.ascontiguousarray(texels, _F32))


IesProfile = _core.IesProfile
IES_MAX_TABLES = int(_core.IES_MAX_TABLES)


def ies_register(h, v, intensity) -> "IesProfile":
    """Registers an IES profile table (h (H,), v (V,) radians in any order as Cycles reads them,
    not NaN where an axis has one; intensity (H, V), any values: where Cycles' lookup gives NaN or
    inf, 0): a
    handle (IesProfile) whose .id (also int(handle)) a point/spot/area lamp record's `ies` field
    names. The table lives while a handle does: identical tables share one slot, counted; the
    last handle's release frees it, and a record naming a freed id is refused. Keep the handle as
    long as its records are used. At most IES_MAX_TABLES distinct tables live at once."""
    return _core.ies_register(_f32(h), _f32(v), _f32(intensity))


def ies_lookup(profile, h, v) -> np.ndarray:
    """Cycles' kernel_ies_interp of a live profile (an IesProfile, or its id) at angle pairs (h[i], v[i])."""
    if not isinstance(profile, IesProfile):
        profile = int(profile)
    return _core.ies_lookup(profile, _f32(h), _f32(v))


def ies_live() -> int:
    """How many distinct IES tables are alive (held by a handle) now."""
    return int(_core.ies_live())
