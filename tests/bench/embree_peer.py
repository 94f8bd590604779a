"""The Embree peer, through the `embreex` package: robust-mode scene (as Cycles sets
RTC_SCENE_FLAG_ROBUST), BVH build timed apart from tracing, closest-hit and occlusion queries on
1 or more threads.

embreex's `run` loops rtcIntersect1/rtcOccluded1 on the calling thread with the GIL released, so
n threads = n Python threads, each tracing a contiguous share of the rays. If the installed
embreex's `run` takes a `threads` argument, that is used instead. Its BVH is built lazily by the
first `run`: build time = the one-ray warm-up `run` that commits the scene (on a device created
once beforehand; device start-up and embreex's slow mesh upload are timed apart).
embreex has tnear = 0; the ray generator pre-offsets origins.
"""

from __future__ import annotations

import inspect
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

try:
    from embreex import rtcore as _rtc
    from embreex import rtcore_scene as _rtcs
    from embreex.mesh_construction import TriangleMesh as _TriangleMesh
    IMPORT_ERROR = None
except ImportError as exc:  # reported by the benchmark's start-up check
    IMPORT_ERROR = exc


def version() -> str:
    return repr(_rtc.EmbreeDevice()).replace("Embree version:", "").strip()


class EmbreePeer:
    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        self.vertices = np.ascontiguousarray(vertices, np.float32)
        self.triangles = np.ascontiguousarray(triangles, np.int32)
        self.scene = None
        self._pool: ThreadPoolExecutor | None = None
        self._pool_size = 0
        self._native_threads = None
        # One device for all builds, as an application keeps it: its creation (thread pool
        # start-up, ISA detection) is timed apart and is not part of a BVH build.
        t0 = time.perf_counter()
        self.device = _rtc.EmbreeDevice()
        self.device_seconds = time.perf_counter() - t0

    def build(self) -> tuple[float, float]:
        """(Re)build from scratch; returns (upload seconds, BVH build seconds).

        Upload = embreex's TriangleMesh copying the arrays into Embree's buffers, which it does
        element by element at Python-object speed (~1 us per triangle): an artefact of the
        wrapper, not of Embree (Cycles shares or memcpy's its buffers), so it is reported apart.
        BVH build = the commit made by the one-ray warm-up `run`."""
        self.scene = None  # drop the previous scene before timing the new one
        t0 = time.perf_counter()
        scene = _rtcs.EmbreeScene(self.device, robust=True)
        _TriangleMesh(scene, self.vertices, self.triangles)
        t1 = time.perf_counter()
        scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commits
        t2 = time.perf_counter()
        self.scene = scene
        self._native_threads = "threads" in inspect.signature(scene.run).parameters
        return t1 - t0, t2 - t1

    @property
    def native_threads(self) -> bool:
        """True when embreex's own `run(threads=...)` is used instead of Python threads."""
        return bool(self._native_threads)

    def _executor(self, n: int) -> ThreadPoolExecutor:
        if self._pool is None or self._pool_size != n:
            if self._pool is not None:
                self._pool.shutdown()
            self._pool, self._pool_size = ThreadPoolExecutor(n), n
        return self._pool

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        self.scene = None

    def _run(self, org, dirs, tfar, threads: int, **kw):
        """Trace with `threads` threads; returns (list of per-share results, seconds).
        tfar is copied beforehand (some embreex versions write hit distances into it)."""
        n = len(org)
        if self._native_threads:
            tf = tfar.copy()
            t0 = time.perf_counter()
            res = self.scene.run(org, dirs, dists=tf, threads=threads, **kw)
            return [res], time.perf_counter() - t0
        cuts = np.linspace(0, n, threads + 1).astype(np.int64)
        shares = [(org[a:b], dirs[a:b], tfar[a:b].copy()) for a, b in zip(cuts[:-1], cuts[1:])]
        if threads == 1:
            t0 = time.perf_counter()
            res = [self.scene.run(*shares[0], **kw)]
            return res, time.perf_counter() - t0
        pool = self._executor(threads)
        t0 = time.perf_counter()
        futures = [pool.submit(self.scene.run, o, d, dists=t, **kw) for o, d, t in shares]
        res = [f.result() for f in futures]
        return res, time.perf_counter() - t0

    def intersect(self, org, dirs, tfar, threads: int = 1):
        """Closest hits: ((prim int32, t float32, u, v), seconds). Misses: prim -1, t inf."""
        res, sec = self._run(org, dirs, tfar, threads, query="INTERSECT", output=1)
        prim = np.concatenate([r["primID"] for r in res])
        t = np.concatenate([r["tfar"] for r in res])
        u = np.concatenate([r["u"] for r in res])
        v = np.concatenate([r["v"] for r in res])
        t = np.where(prim >= 0, t, np.float32(np.inf)).astype(np.float32)
        return (prim, t, u, v), sec

    def occluded(self, org, dirs, tfar, threads: int = 1):
        """Any hit in [0, tfar]: (bool array, seconds)."""
        res, sec = self._run(org, dirs, tfar, threads, query="OCCLUDED")
        return np.concatenate(res) == 0, sec
