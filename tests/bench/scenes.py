"""Benchmark scenes: triangle geometry plus the camera that frames it and the light region that
shadow rays aim at.

Two sources:
- real scenes from `../shared/scenes` beside the repository (dragon 100K, San Francisco 268K,
  bunny 69K, Sibenik 74K, Suzanne 1K), loaded with the OBJ loader and cached as .npz under
  bench-out/cache so later runs skip the text parsing;
- generated scenes `room<N>k` (e.g. room10k, room250k): a closed, tessellated room holding a field
  of displaced spheres, about N thousand triangles, built from code and deterministic. They are
  what the benchmark uses when ../shared is absent.
Any other argument is taken as a path to an .obj file (or a folder holding one), framed from
outside with +Y up.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..objfile import load_obj

REPO = Path(__file__).resolve().parents[2]
SHARED_SCENES = REPO.parent / "shared" / "scenes"
OUT = REPO / "bench-out"

_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass
class Camera:
    """Pinhole camera: eye, look-at target, up vector, vertical field of view in degrees."""
    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    vfov: float = 50.0


@dataclass
class Light:
    """Parallelogram region corner + s*edge1 + t*edge2 (s, t in [0,1]) that shadow rays aim at."""
    corner: np.ndarray
    edge1: np.ndarray
    edge2: np.ndarray


@dataclass
class Scene:
    name: str
    vertices: np.ndarray      # float32 (V,3)
    triangles: np.ndarray     # int32 (M,3)
    camera: Camera
    light: Light
    source: str               # file path, or "generated"
    load_seconds: float = 0.0
    notes: dict = field(default_factory=dict)

    @property
    def num_triangles(self) -> int:
        return len(self.triangles)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        v = self.vertices[np.unique(self.triangles)] if len(self.triangles) else self.vertices
        return v.min(0).astype(np.float64), v.max(0).astype(np.float64)


# --------------------------------------------------------------------------- framing helpers

def _basis(up_axis: str, azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit up vector and unit direction from the target towards the eye."""
    u = _AXES[up_axis]
    a, b = (u + 1) % 3, (u + 2) % 3          # horizontal axes, right-handed with up
    az, el = np.radians(azimuth), np.radians(elevation)
    up = np.zeros(3)
    up[u] = 1.0
    back = np.zeros(3)
    back[a], back[b], back[u] = np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)
    return up, back


def frame_outside(points, up_axis="y", azimuth=30.0, elevation=20.0, vfov=40.0,
                  aspect=1.6, zoom=1.0) -> Camera:
    """Camera outside the points' box looking at its centre, just far enough that every point
    is in view (zoom > 1 moves in and crops the edges, to fill the frame with geometry)."""
    up, back = _basis(up_axis, azimuth, elevation)
    lo, hi = points.min(0).astype(np.float64), points.max(0).astype(np.float64)
    c = (lo + hi) / 2
    fwd = -back
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    cup = np.cross(right, fwd)
    tv = np.tan(np.radians(vfov) / 2) * zoom
    th = tv * aspect
    p = points[:: max(1, len(points) // 50_000)].astype(np.float64) - c
    # depth of a point from the eye = dist + p.fwd; in view if |p.right| <= th*depth etc.
    depth_off = p @ fwd
    dist = max(np.max(np.abs(p @ right) / th - depth_off),
               np.max(np.abs(p @ cup) / tv - depth_off)) * 1.02
    return Camera(eye=c + back * dist, target=c, up=up, vfov=vfov)


def light_above(lo, hi, up_axis="y", height=0.5, size=0.5) -> Light:
    """Horizontal rectangle above the box: `height` x the box's vertical extent above its top,
    `size` x its horizontal extents, centred."""
    u = _AXES[up_axis]
    a, b = (u + 1) % 3, (u + 2) % 3
    ext = hi - lo
    c = (lo + hi) / 2
    corner = c.copy()
    corner[u] = hi[u] + height * max(ext[u], 1e-3)
    e1, e2 = np.zeros(3), np.zeros(3)
    e1[a], e2[b] = size * ext[a], size * ext[b]
    corner[a] -= e1[a] / 2
    corner[b] -= e2[b] / 2
    return Light(corner=corner, edge1=e1, edge2=e2)


# --------------------------------------------------------------------------- generated room

def _grid(origin, e1, e2, n):
    """n x n quads (2n^2 triangles) tessellating the parallelogram origin + s e1 + t e2."""
    s = np.linspace(0.0, 1.0, n + 1)
    S, T = np.meshgrid(s, s, indexing="ij")
    v = origin + S[..., None] * e1 + T[..., None] * e2
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + (n + 1), a + 1, a + n + 2
    f = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return v.reshape(-1, 3), f


def _blob(center, radius, n, phase):
    """Cube-sphere with n x n quads per cube face (12 n^2 triangles), radially displaced by a
    smooth function of direction so it is lumpy rather than round. Seams between cube faces get
    bit-identical vertex positions, so the surface is closed."""
    verts, faces, base = [], [], 0
    for axis in range(3):
        for sign in (-1.0, 1.0):
            o, e1, e2 = np.zeros(3), np.zeros(3), np.zeros(3)
            o[axis] = sign
            o[(axis + 1) % 3] = -1.0
            o[(axis + 2) % 3] = -1.0
            e1[(axis + 1) % 3] = 2.0
            e2[(axis + 2) % 3] = 2.0
            if sign < 0:  # keep the winding outward on both sides
                e1, e2 = e2, e1
            v, f = _grid(o, e1, e2, n)
            verts.append(v)
            faces.append(f + base)
            base += len(v)
    v = np.concatenate(verts)
    d = v / np.linalg.norm(v, axis=1, keepdims=True)
    bump = (0.12 * np.sin(5 * d[:, 0] + phase) * np.sin(4 * d[:, 1] + 2 * phase)
            + 0.05 * np.sin(17 * d[:, 2] + 3 * phase) * np.cos(13 * d[:, 0]))
    return center + d * (radius * (1.0 + bump))[:, None], np.concatenate(faces)


def generate_room(target: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """A closed 10 x 4 x 8 room (Y up) with tessellated walls and a jittered field of lumpy
    spheres, about `target` triangles (within a few percent)."""
    rng = np.random.default_rng(seed)
    W, H, D = 10.0, 4.0, 8.0
    g = max(2, int(round(np.sqrt(0.08 * target / 12))))            # walls: ~8% of the budget
    walls = [
        ((0, 0, 0), (W, 0, 0), (0, 0, D)), ((0, H, 0), (0, 0, D), (W, 0, 0)),   # floor, ceiling
        ((0, 0, 0), (0, H, 0), (W, 0, 0)), ((0, 0, D), (W, 0, 0), (0, H, 0)),   # back, front
        ((0, 0, 0), (0, 0, D), (0, H, 0)), ((W, 0, 0), (0, H, 0), (0, 0, D)),   # left, right
    ]
    verts, faces, base = [], [], 0
    for o, e1, e2 in walls:
        v, f = _grid(np.array(o, float), np.array(e1, float), np.array(e2, float), g)
        verts.append(v)
        faces.append(f + base)
        base += len(v)
    rest = max(target - 12 * g * g, 12)
    nx, nz = (4, 3) if target < 50_000 else (8, 6)                  # number of blobs
    m = nx * nz
    n = max(1, int(round(np.sqrt(rest / (12 * m)))))
    for ix in range(nx):
        for iz in range(nz):
            r = rng.uniform(0.3, 0.6) * (8.0 / nx) / 2.2
            cx = (ix + 0.5) / nx * (W - 2) + 1 + rng.uniform(-0.2, 0.2)
            cz = (iz + 0.5) / nz * (D - 2) + 1 + rng.uniform(-0.2, 0.2)
            cy = r * rng.uniform(0.8, 2.5)                           # some sink into the floor
            v, f = _blob(np.array([cx, cy, cz]), r, n, rng.uniform(0, 2 * np.pi))
            verts.append(v)
            faces.append(f + base)
            base += len(v)
    return (np.concatenate(verts).astype(np.float32),
            np.concatenate(faces).astype(np.int32))


def _room_scene(name: str, target: int) -> Scene:
    t0 = time.perf_counter()
    v, f = generate_room(target)
    cam = Camera(eye=np.array([0.6, 2.6, 7.4]), target=np.array([6.5, 0.6, 2.5]),
                 up=np.array([0.0, 1.0, 0.0]), vfov=65.0)
    light = Light(corner=np.array([3.5, 3.9, 3.0]), edge1=np.array([3.0, 0, 0]),
                  edge2=np.array([0, 0, 2.0]))
    return Scene(name, v, f, cam, light, "generated", time.perf_counter() - t0)


# --------------------------------------------------------------------------- real scenes

# name -> (path under ../shared/scenes, up axis, framing). Framing "outside" = azimuth, elevation,
# vfov of a camera fitted to the bounds; "inside" = explicit camera and light (interiors).
REAL = {
    "dragon": ("stanford_dragon_100k/dragon.obj", "y", dict(azimuth=25, elevation=15)),
    "san_francisco": ("sionna_san_francisco/san_francisco_merged.obj", "z",
                      dict(azimuth=200, elevation=30, zoom=2.2)),
    "bunny": ("stanford_bunny/stanford-bunny.obj", "y", dict(azimuth=20, elevation=15)),
    "suzanne": ("suzanne/suzanne.obj", "y", dict(azimuth=0, elevation=10)),
    "sibenik": ("sibenik/sibenik.obj", "y",
                dict(camera=Camera(eye=np.array([-16.0, -11.0, 0.0]),
                                   target=np.array([0.0, -9.0, 0.0]),
                                   up=np.array([0.0, 1.0, 0.0]), vfov=70.0),
                     light=Light(corner=np.array([-8.0, 0.0, -3.0]),
                                 edge1=np.array([10.0, 0, 0]), edge2=np.array([0, 0, 6.0])))),
}


def _cached_obj(path: Path) -> tuple[np.ndarray, np.ndarray, bool]:
    """Load an OBJ, through an .npz cache keyed by the file's path, size and mtime."""
    st = path.stat()
    key = re.sub(r"[^A-Za-z0-9_.-]", "_", str(path.resolve()))[-80:]
    cache = OUT / "cache" / f"{key}-{st.st_size}-{int(st.st_mtime)}.npz"
    if cache.exists():
        try:
            with np.load(cache) as z:
                return z["vertices"], z["triangles"], True
        except (OSError, ValueError, KeyError):
            pass  # a broken cache entry is simply rebuilt
    v, f = load_obj(path)
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(".tmp.npz")
        np.savez(tmp, vertices=v, triangles=f)
        tmp.replace(cache)
    except OSError:
        pass  # read-only checkout: no cache, still works
    return v, f, False


def _file_scene(name: str, path: Path, up_axis: str, framing: dict) -> Scene:
    t0 = time.perf_counter()
    v, f, cached = _cached_obj(path)
    if len(f) == 0:
        raise ValueError(f"{path}: no faces, nothing to trace")
    scene = Scene(name, v, f, None, None, str(path), 0.0, {"from_cache": cached})
    lo, hi = scene.bounds()
    if "camera" in framing:
        scene.camera, scene.light = framing["camera"], framing["light"]
    else:
        used = v[np.unique(f)]
        scene.camera = frame_outside(used, up_axis, **framing)
        scene.light = light_above(lo, hi, up_axis)
    scene.load_seconds = time.perf_counter() - t0
    return scene


def available() -> list[str]:
    """Names accepted by load_scene (room<N>k takes any N)."""
    names = [n for n, (p, _, _) in REAL.items() if (SHARED_SCENES / p).exists()]
    return ["room10k", "room100k", "room250k"] + names


def default_names() -> list[str]:
    """~10K, ~100K and ~250K triangles: real scenes where ../shared is present."""
    if all((SHARED_SCENES / REAL[n][0]).exists() for n in ("dragon", "san_francisco")):
        return ["room10k", "dragon", "san_francisco"]
    return ["room10k", "room100k", "room250k"]


def _resolve(spec: str):
    """Check a scene argument without loading it: returns a loader taking no arguments."""
    m = re.fullmatch(r"room(\d+)k", spec)
    if m:
        n = int(m.group(1))
        if not 1 <= n <= 20_000:
            raise ValueError(f"scene {spec!r}: room size must be 1k..20000k triangles")
        return lambda: _room_scene(spec, n * 1000)
    if spec in REAL:
        rel, up, framing = REAL[spec]
        path = SHARED_SCENES / rel
        if not path.exists():
            raise ValueError(f"scene {spec!r} needs {path}, which does not exist "
                             f"(the shared scenes folder sits beside the repository)")
        return lambda: _file_scene(spec, path, up, framing)
    path = Path(spec)
    if path.is_dir():
        objs = sorted(path.glob("*.obj"))
        if len(objs) != 1:
            raise ValueError(f"scene folder {path} must hold exactly one .obj file "
                             f"(found {len(objs)})")
        path = objs[0]
    if path.suffix.lower() == ".obj" and path.is_file():
        return lambda: _file_scene(path.stem, path, "y", dict(azimuth=30, elevation=20))
    raise ValueError(f"unknown scene {spec!r}: use one of {', '.join(available())}, "
                     f"room<N>k, or a path to an .obj file")


def check_scene(spec: str) -> None:
    """Raise ValueError now if `spec` names no loadable scene (before a long run starts)."""
    _resolve(spec)


def load_scene(spec: str) -> Scene:
    """A scene by name (see available()) or by path to an .obj file / a folder holding one."""
    return _resolve(spec)()
