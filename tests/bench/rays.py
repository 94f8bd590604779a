"""Benchmark ray sets: camera rays, diffuse-bounce rays and shadow rays of one scene, as a path
tracer makes them, all as float32 (org, dir, tfar) arrays ready for both tracers.

- camera: pinhole camera, 640x400 pixels, jittered, in progressive passes (pass-major, scanline
  order inside a pass), as many passes as needed for the requested count; a last partial pass
  takes pixels evenly spread over the image.
- diffuse: from the first hits of the camera rays (hit point from float64 barycentrics), origin
  pushed off the surface along the geometric normal facing the incoming side with the Ray
  Tracing Gems ch. 6 offset (neither tracer takes a tnear, so origins must be pre-offset),
  cosine-distributed around that normal. If there are fewer hits than rays wanted, the hit
  points are reused pass after pass with fresh directions.
- shadow: from the same offset hit points towards uniform points of the scene's light region,
  finite tfar = distance to the light point; only pairs a renderer would trace (light in
  front of the surface) are kept.
First hits come from a caller-supplied intersect function (the Embree peer), so generation
does not depend on the tracer under test.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .scenes import Camera, Light, Scene

RAY_DTYPE = np.dtype([("org", "<f4", (3,)), ("dir", "<f4", (3,)), ("tfar", "<f4"),
                      ("id", "<u4")])  # the tracer's 32-byte record, spelled out from its API
WIDTH, HEIGHT = 640, 400

# Ray Tracing Gems ch. 6 (Wächter & Binder), as in Cycles' ray_offset().
_ORIGIN, _FLOAT_SCALE, _INT_SCALE = 1.0 / 32.0, 1.0 / 65536.0, 256.0


@dataclass
class RaySet:
    kind: str                 # "camera" | "diffuse" | "shadow"
    query: str                # "intersect" | "occluded"
    org: np.ndarray           # float32 (N,3)
    dir: np.ndarray           # float32 (N,3)
    tfar: np.ndarray          # float32 (N,)

    def __len__(self) -> int:
        return len(self.org)

    def records(self) -> np.ndarray:
        """The rays as the tracer's RAY_DTYPE records, ids 0..N-1 in array order."""
        r = np.empty(len(self), RAY_DTYPE)
        r["org"], r["dir"], r["tfar"] = self.org, self.dir, self.tfar
        r["id"] = np.arange(len(self), dtype=np.uint32)
        return r


def offset_origin(p: np.ndarray, n: np.ndarray) -> np.ndarray:
    """RTG ch. 6 offset of float32 points p along unit normals n: a few hundred ULPs in integer
    space far from the origin, a fixed float step near it. Returns float32 (N,3)."""
    p = np.ascontiguousarray(p, np.float32)
    n32 = n.astype(np.float32)
    of_i = (np.float32(_INT_SCALE) * n32).astype(np.int32)       # truncates toward 0, as C does
    p_i = (p.view(np.int32) + np.where(p < 0, -of_i, of_i)).view(np.float32)
    near = np.abs(p) < np.float32(_ORIGIN)
    return np.where(near, p + np.float32(_FLOAT_SCALE) * n32, p_i).astype(np.float32)


def _normalize(d: np.ndarray) -> np.ndarray:
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def camera_rays(cam: Camera, n: int, rng: np.random.Generator) -> RaySet:
    fwd = _normalize(np.asarray(cam.target, float) - cam.eye)
    right = _normalize(np.cross(fwd, cam.up))
    up = np.cross(right, fwd)
    tv = np.tan(np.radians(cam.vfov) / 2)
    th = tv * WIDTH / HEIGHT
    k = np.arange(n)
    P = WIDTH * HEIGHT
    pix = k % P                                                    # pass-major, scanline order
    full = (n // P) * P                 # a last partial pass spreads over the whole image (a small
    if full < n:                        # --rays had traced only the top scanlines)
        pix[full:] = (np.arange(n - full) * P) // (n - full)
    x = (pix % WIDTH + rng.random(n)) / WIDTH * 2 - 1
    y = 1 - (pix // WIDTH + rng.random(n)) / HEIGHT * 2
    d = fwd + (x * th)[:, None] * right + (y * tv)[:, None] * up
    org = np.broadcast_to(np.asarray(cam.eye, np.float32), (n, 3)).copy()
    return RaySet("camera", "intersect", org, _normalize(d).astype(np.float32),
                  np.full(n, np.inf, np.float32))


def _cosine_dirs(nrm: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Cosine-distributed unit directions around unit normals (N,3)."""
    m = len(nrm)
    r1, r2 = rng.random(m), rng.random(m)
    helper = np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = _normalize(np.cross(nrm, helper))
    b = np.cross(nrm, t)
    phi, s = 2 * np.pi * r1, np.sqrt(r2)
    d = (s * np.cos(phi))[:, None] * t + (s * np.sin(phi))[:, None] * b \
        + np.sqrt(np.maximum(1 - r2, 0.0))[:, None] * nrm
    return _normalize(d)


@dataclass
class Surface:
    """First hits of camera rays: offset origins and geometric normals facing the camera."""
    org: np.ndarray           # float32 (H,3), already offset
    normal: np.ndarray        # float64 (H,3) unit
    hit_fraction: float


def first_hits(scene: Scene, cam: RaySet, prim, u, v) -> Surface:
    hit = prim >= 0
    if not hit.any():
        raise ValueError(f"scene {scene.name!r}: the camera sees no geometry, so there are no "
                         f"bounce or shadow rays to make")
    tri = scene.triangles[prim[hit]]
    p0, p1, p2 = (scene.vertices[tri[:, i]].astype(np.float64) for i in range(3))
    bu, bv = u[hit].astype(np.float64)[:, None], v[hit].astype(np.float64)[:, None]
    p = (1 - bu - bv) * p0 + bu * p1 + bv * p2
    ng = np.cross(p1 - p0, p2 - p0)
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)  # hit triangles have non-zero area
    ng = np.where((np.einsum("ij,ij->i", ng, cam.dir[hit]) > 0)[:, None], -ng, ng)
    return Surface(offset_origin(p, ng), ng, float(hit.mean()))


def diffuse_rays(surf: Surface, n: int, rng: np.random.Generator) -> RaySet:
    k = np.arange(n) % len(surf.org)                 # reuse hit points pass after pass
    d = _cosine_dirs(surf.normal[k], rng)
    return RaySet("diffuse", "intersect", surf.org[k], d.astype(np.float32),
                  np.full(n, np.inf, np.float32))


def shadow_rays(surf: Surface, light: Light, n: int, rng: np.random.Generator) -> RaySet:
    orgs, dirs, tfars, have, start = [], [], [], 0, 0
    for _ in range(64):                      # rejection of back-facing pairs; bounded retries
        m = 2 * (n - have) + 1024
        k = (start + np.arange(m)) % len(surf.org)
        start += m
        s, t = rng.random((2, m, 1))
        target = light.corner + s * light.edge1 + t * light.edge2
        o = surf.org[k].astype(np.float64)
        d = target - o
        dist = np.linalg.norm(d, axis=1)
        keep = (np.einsum("ij,ij->i", d, surf.normal[k]) > 0) & (dist > 0)
        orgs.append(surf.org[k][keep])
        dirs.append(d[keep] / dist[keep, None])
        tfars.append(dist[keep])
        have += int(keep.sum())
        if have >= n:
            break
    if have == 0:
        raise ValueError("no surface point seen by the camera faces the light region: "
                         "no shadow rays to make")
    org = np.concatenate(orgs)[:n]
    k = np.arange(n) % len(org)              # (only if almost nothing faces the light)
    return RaySet("shadow", "occluded", org[k],
                  np.concatenate(dirs)[:n][k].astype(np.float32),
                  np.concatenate(tfars)[:n][k].astype(np.float32))


IntersectFn = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple]


def make_ray_sets(scene: Scene, n: int, intersect: IntersectFn, seed: int = 1):
    """Camera, diffuse and shadow RaySets of n rays each, plus the camera hit fraction.
    `intersect(org, dir, tfar) -> (prim, t, u, v)` finds the camera rays' first hits."""
    rng = np.random.default_rng(seed)
    cam = camera_rays(scene.camera, n, rng)
    prim, _, u, v = intersect(cam.org, cam.dir, cam.tfar)
    surf = first_hits(scene, cam, prim, u, v)
    return [cam, diffuse_rays(surf, n, rng), shadow_rays(surf, scene.light, n, rng)], surf
