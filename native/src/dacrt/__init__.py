"""DACRT: divide-and-conquer ray tracing of incoherent ray batches, no acceleration structure.

The algorithm of Afra, "Incoherent Ray Tracing without Acceleration Structures" (EG 2012):
ray filtering that reorders 32-byte ray records in place, object partitioning of a triangle id
array (spatial median or binned SAH, chosen by the ray/triangle ratio), W rays x 1 triangle
watertight leaf tests, SIMD kernels per instruction set chosen at run time.

This module owns the public Python API and its argument checks; the work happens in `_core`.
Nothing built for tracing outlives a Scene object: a frame builds one, traces, drops it.
"""
from __future__ import annotations

import contextlib
import os

import numpy as np

from . import _core

__all__ = ["RAY_DTYPE", "HIT_DTYPE", "Scene", "make_rays", "isa", "supported_isas", "thread_limit", "PARTITIONS",
           "Cancelled", "CANCEL_POLL_SECONDS"]

RAY_DTYPE = np.dtype([("org", "<f4", (3,)), ("dir", "<f4", (3,)), ("tfar", "<f4"), ("id", "<u4")])
HIT_DTYPE = np.dtype([("t", "<f4"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")])
assert RAY_DTYPE.itemsize == 32 and HIT_DTYPE.itemsize == 16

PARTITIONS = ("adaptive", "median", "sah")
ROBUST = _core.ROBUST
# Raised by Scene.intersect / occluded when their `cancel` callable said stop.
Cancelled = _core.Cancelled
# How often a trace asks its `cancel` callable (seconds, on the calling thread): a renderer's
# Esc is then honoured within a batch, not after it (tests set 0: at every step).
CANCEL_POLL_SECONDS = 0.05


def supported_isas() -> list:
    """Instruction sets this CPU can run, weakest first (e.g. ['portable', 'avx2', 'avx512'])."""
    return list(_core.supported_isas())


def _requested_isa() -> str:
    return os.environ.get("DACRT_ISA", "").strip().lower()


def isa() -> str:
    """The instruction set the next trace call uses: DACRT_ISA if set (checked), else the best."""
    return _core.check_isa(_requested_isa())


@contextlib.contextmanager
def thread_limit(limit: int):
    """Within the block, every native pass this thread calls (shading kernels, and traces not
    given a thread count) uses at most `limit` threads (0 or less: no limit); the previous limit
    after it. A renderer told to use fewer cores (Blender's Threads: Fixed) sets it for its
    frame; other threads keep their own."""
    before = _core.thread_limit()
    _core.set_thread_limit(max(0, int(limit)))
    try:
        yield
    finally:
        _core.set_thread_limit(before)


def _float32(a, name: str) -> np.ndarray:
    """a as float32; a finite value that float32 cannot hold is an error, not a silent inf."""
    a = np.asarray(a)
    if a.dtype.kind == "c":     # numpy would drop the imaginary part, with only a warning
        raise ValueError(f"{name} must be real numbers; got dtype {a.dtype}")
    if a.dtype == np.float32 or a.dtype.kind not in "fiu":
        return np.asarray(a, dtype=np.float32)
    with np.errstate(over="ignore"):
        a32 = a.astype(np.float32)
    bad = np.isfinite(a) & ~np.isfinite(a32)
    if bad.any():
        at = np.unravel_index(int(np.argmax(bad)), a.shape)
        where = f"[{at[0]}]" if len(at) else ""
        raise ValueError(f"{name}{where} = {a[at].tolist()!r} is too large to be represented in float32")
    return a32


def make_rays(org, dir, tfar=np.inf) -> np.ndarray:
    """Build a RAY_DTYPE array from (N,3) origins and directions; ids are 0..N-1. tfar: a
    scalar or one per ray (a finite tfar beyond float32's range becomes inf: the same rays)."""
    org = _float32(org, "org")
    dir = _float32(dir, "dir")
    if org.ndim != 2 or org.shape[1] != 3 or dir.shape != org.shape:
        raise ValueError(f"org and dir must both have shape (N, 3); got {org.shape} and {dir.shape}")
    tfar = np.asarray(tfar)
    if tfar.dtype.kind == "c":
        raise ValueError(f"tfar must be real numbers; got dtype {tfar.dtype}")
    if tfar.ndim > 1 or (tfar.ndim == 1 and tfar.shape != (len(org),)):
        raise ValueError(f"tfar must be a scalar or have shape ({len(org)},); got {tfar.shape}")
    rays = np.empty(len(org), RAY_DTYPE)
    rays["org"] = org
    rays["dir"] = dir
    with np.errstate(over="ignore"):
        rays["tfar"] = tfar
    rays["id"] = np.arange(len(org), dtype=np.uint32)
    return rays


def _as_vertices(vertices) -> np.ndarray:
    v = np.asarray(vertices)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must have shape (V, 3); got {v.shape}")
    if v.dtype.kind != "f":
        raise ValueError(f"vertices must be a floating-point array (float32 preferred); got dtype {v.dtype}")
    if v.dtype != np.float32:
        with np.errstate(over="ignore"):
            v32 = v.astype(np.float32)
        bad = np.isfinite(v).all(axis=1) & ~np.isfinite(v32).all(axis=1)
        if bad.any():
            raise ValueError(f"vertices[{int(np.argmax(bad))}] is too large to be represented in float32")
        v = v32
    return np.ascontiguousarray(v)


def _as_triangles(triangles, num_vertices: int) -> np.ndarray:
    t = np.asarray(triangles)
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"triangles must have shape (M, 3); got {t.shape}")
    if t.dtype.kind not in "iu":
        raise ValueError(f"triangles must be an integer array of vertex indices; got dtype {t.dtype}")
    if t.size:
        lo, hi = t.min(), t.max()
        if lo < 0:
            row = int(np.argmax((t < 0).any(axis=1)))
            raise ValueError(f"triangles[{row}] has a negative vertex index ({t[row].tolist()})")
        if hi >= num_vertices:
            row = int(np.argmax((t >= num_vertices).any(axis=1)))
            raise ValueError(f"triangles[{row}] refers to vertex {int(t[row].max())} "
                             f"but there are only {num_vertices} vertices")
    return np.ascontiguousarray(t, dtype=np.uint32)


def _check_rays(rays) -> None:
    if not isinstance(rays, np.ndarray):
        raise ValueError(f"rays must be a numpy array of dtype dacrt.RAY_DTYPE; got {type(rays).__name__}")
    if rays.dtype != RAY_DTYPE:
        raise ValueError(f"rays must have dtype dacrt.RAY_DTYPE {RAY_DTYPE.descr}; got {rays.dtype}")
    if rays.ndim != 1:
        raise ValueError(f"rays must be a 1-D array; got shape {rays.shape}")
    if not rays.flags.c_contiguous:
        raise ValueError("rays must be C-contiguous (they are reordered in place; pass np.ascontiguousarray(rays))")
    if not rays.flags.writeable:
        raise ValueError("rays must be writeable (they are reordered in place)")


_INT32_MAX = 2**31 - 1


def _check_threads(threads) -> int:
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)):
        raise ValueError(f"threads must be an integer (0 = all cores); got {threads!r}")
    if threads < 0:
        raise ValueError(f"threads must be >= 0 (0 = all cores); got {threads}")
    if threads > _INT32_MAX:
        raise ValueError(f"threads must be at most {_INT32_MAX} (0 = all cores); got {threads}")
    return int(threads)


def _leaf_threshold(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= _INT32_MAX:
        raise ValueError(f"{name} must be an integer in 1..{_INT32_MAX}; got {value!r}")
    return int(value)


def _cancel(cancel):
    """(callable or None, poll interval) for the native trace."""
    if cancel is not None and not callable(cancel):
        raise TypeError(f"cancel must be a callable returning true to stop, or None; got {cancel!r}")
    return cancel, float(CANCEL_POLL_SECONDS)


class Scene:
    """A triangle soup ready to be traced. Building it costs one pass over the triangles.

    vertices: (V,3) float array; triangles: (M,3) integer vertex indices. Both are copied into
    the tracer's own layout; degenerate (zero-area) triangles are accepted and never hit.

    keep_top: keep the splits of the triangle partition (of every node of more than ~16
    triangles that some batch reaches; they depend on the triangles, not on the rays) from one
    call to the next while the partition settings stay the same, so the later batches of a frame
    skip them; any batch, however small, adds to them. Results are identical either way; a
    renderer makes one Scene per frame, so nothing outlives the frame.

    masks (optional): one uint8 of visibility bits per triangle. A call given `visible` traces
    only the triangles whose mask shares a bit with it, as if the others were not in the scene;
    so one scene (and one kept top) serves ray kinds that see slightly different subsets, e.g.
    camera rays that must not see a light-emitting card that bounce rays do see.

    spatial_order: store the triangles in Morton order of their centres, so triangles near in
    space are near in memory. Tracing gets faster when the mesh's own order is not spatially
    coherent (the dragon's scan order: +5-17% by ray kind; a shuffled mesh: +25%), but building the scene
    costs more (~10 ns per triangle, +65% on San Francisco), so it pays for frames that trace
    several rays per triangle. Results are identical either way.
    """

    def __init__(self, vertices, triangles, partition: str = "adaptive", leaf_size: int | None = None,
                 sah_ratio: float = 128.0, chunk_rays: int = 0, keep_top: bool = False, leaf_rays: int = 32,
                 masks=None, spatial_order: bool = False):
        v = _as_vertices(vertices)
        t = _as_triangles(triangles, len(v))
        if masks is not None:
            m = np.asarray(masks)
            if m.shape != (len(t),) or m.dtype != np.uint8:
                raise ValueError(f"masks must be a uint8 array of one entry per triangle (shape ({len(t)},)); "
                                 f"got shape {m.shape} dtype {m.dtype}")
            masks = np.ascontiguousarray(m)
        self._has_masks = masks is not None
        self._core = _core.NativeScene(v, t, bool(keep_top), masks, bool(spatial_order))
        self.partition = partition
        self.leaf_size = leaf_size
        self.leaf_rays = leaf_rays
        self.sah_ratio = sah_ratio
        self.chunk_rays = chunk_rays
        self.last_stats: dict = {}

    # Settings, checked on assignment so a typo fails where it is made.
    @property
    def partition(self) -> str:
        return self._partition

    @partition.setter
    def partition(self, value: str) -> None:
        if not isinstance(value, str) or value.lower() not in PARTITIONS:
            raise ValueError(f"partition must be one of {PARTITIONS}; got {value!r}")
        self._partition = value.lower()

    @property
    def leaf_size(self) -> int | None:
        """A node with at most this many triangles is a leaf: its active rays are tested
        against all its triangles. None (the default): 8, measured best on every kernel
        (`last_stats['leaf_size']` says which a call used)."""
        return self._leaf_size

    @leaf_size.setter
    def leaf_size(self, value: int | None) -> None:
        self._leaf_size = None if value is None else _leaf_threshold("leaf_size", value)

    @property
    def leaf_rays(self) -> int:
        """A node with at most this many active rays is a leaf too."""
        return self._leaf_rays

    @leaf_rays.setter
    def leaf_rays(self, value: int) -> None:
        self._leaf_rays = _leaf_threshold("leaf_rays", value)

    @property
    def sah_ratio(self) -> float:
        return self._sah_ratio

    @sah_ratio.setter
    def sah_ratio(self, value: float) -> None:
        value = float(value)
        with np.errstate(over="ignore"):
            representable = np.isfinite(np.float32(value))
        if not representable or value < 0:  # the tracer compares in float32
            raise ValueError(f"sah_ratio must be a finite number >= 0 that float32 holds "
                             f"(<= {float(np.finfo(np.float32).max):.4g}); got {value!r}")
        self._sah_ratio = value

    @property
    def chunk_rays(self) -> int:
        """Rays per independently traced chunk (0 = automatic: one per thread): a tuning knob."""
        return self._chunk_rays

    @chunk_rays.setter
    def chunk_rays(self, value: int) -> None:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value < 2**64:
            raise ValueError(f"chunk_rays must be an integer in 0..2**64-1 (0 = automatic); got {value!r}")
        self._chunk_rays = int(value)

    @property
    def num_triangles(self) -> int:
        return self._core.num_triangles

    @property
    def num_degenerate(self) -> int:
        return self._core.num_degenerate

    @property
    def bounds(self):
        """((xmin, ymin, zmin), (xmax, ymax, zmax)) of the non-degenerate triangles."""
        return self._core.bounds

    def _args(self, threads):
        return (_check_threads(threads), _requested_isa(), PARTITIONS.index(self._partition),
                self._leaf_size or 0, self._leaf_rays, self._sah_ratio, self._chunk_rays)

    def _skip(self, skip, n: int, checked: bool = False):
        if skip is None:
            return None
        s = np.asarray(skip)
        if s.shape != (n,) or s.dtype.kind not in "iu":
            raise ValueError(f"skip must be an integer array of one triangle index per ray id (shape ({n},)); "
                             f"got shape {s.shape} dtype {s.dtype}")
        if checked and s.dtype == np.int32 and s.flags.c_contiguous:
            return s  # the caller's word: no min/max pass (the tracer only compares the entries)
        m = self._core.num_triangles
        if n and (s.min() < -1 or s.max() >= m):  # before the int32 cast, which wraps 2**32 to 0
            i = int(np.argmax((s < -1) | (s >= m)))
            raise ValueError(f"skip[{i}] = {int(s[i])} is not a triangle index (-1 = none, 0..{m - 1})")
        return np.ascontiguousarray(s, dtype=np.int32)

    def _visible(self, visible) -> int:
        if visible is None:
            return 0
        if isinstance(visible, bool) or not isinstance(visible, (int, np.integer)) or not 1 <= visible <= 255:
            raise ValueError(f"visible must be an integer in 1..255 (bits of the triangle masks); got {visible!r}")
        if not self._has_masks:
            raise ValueError("visible was given but this Scene was made without masks")
        return int(visible)

    def intersect(self, rays: np.ndarray, threads: int = 0, skip=None, visible=None, cancel=None, *,
                  skip_checked: bool = False) -> np.ndarray:
        """Closest hit with t in (0, tfar] for every ray; returns HIT_DTYPE indexed by ray id
        (a miss: prim -1, t = inf, u = v = 0, whatever its tfar).

        rays is reordered in place and each hit ray's tfar becomes its hit distance. Ties at
        equal t go to the lowest triangle index. threads: 0 = all cores; a count above the
        machine's hardware threads is capped there (results never depend on it). skip
        (optional, by ray id): a triangle index the ray ignores, e.g. the one it leaves (-1:
        none), as Cycles skips the origin primitive.
        visible (optional): only triangles whose mask has one of these bits (see Scene).
        cancel (optional): a callable asked on the calling thread about every
        CANCEL_POLL_SECONDS while the rays are traced (with the GIL; the trace runs without
        it); when it returns true the trace stops within a recursion step and raises Cancelled
        (the rays are left reordered, no hits are returned). Its exceptions propagate.
        skip_checked: the caller vouches for skip's range (-1 or a triangle index, e.g. prims of
        this scene's own hits), so a C-contiguous int32 skip is passed without the min/max pass
        over it (a renderer's every batch: ~1% of a small scene's render); an entry outside the
        range then skips nothing, as the tracer only compares triangles against it. Other
        dtypes are checked as before.
        """
        _check_rays(rays)
        args = self._args(threads)
        skip = self._skip(skip, len(rays), skip_checked)
        vis = self._visible(visible)
        hits = np.empty(len(rays), HIT_DTYPE)
        self.last_stats = self._core.intersect(rays, hits, skip, *args, vis, *_cancel(cancel))
        return hits

    def occluded(self, rays: np.ndarray, threads: int = 0, skip=None, visible=None, cancel=None, *,
                 skip_checked: bool = False) -> np.ndarray:
        """True for every ray (by id) that hits anything with t in (0, tfar).

        rays is reordered in place; the tfar of occluded rays is overwritten (negative).
        skip, visible, cancel, skip_checked: as for intersect().
        """
        _check_rays(rays)
        args = self._args(threads)
        skip = self._skip(skip, len(rays), skip_checked)
        vis = self._visible(visible)
        out = np.empty(len(rays), np.uint8)
        self.last_stats = self._core.occluded(rays, out, skip, *args, vis, *_cancel(cancel))
        return out.view(np.bool_)

from . import shading  # noqa: E402  (per-ray helper kernels; needs the names above)
from . import lamps  # noqa: E402  (analytic lamp kernels)
from . import images  # noqa: E402  (per-point image lookups)
