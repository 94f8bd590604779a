"""Triangle scenes for the tracer tests: random soups, closed meshes, grids of tiny triangles,
a ~100K-triangle mesh (the OBJ loader is tests/objfile.py, shared with the benchmark). Every generator returns (vertices float32 (V,3),
triangles int32 (M,3)) and is deterministic for a given numpy Generator / arguments."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..objfile import load_obj

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"  # sits beside the repository, not inside it
DRAGON_OBJ = SHARED / "scenes" / "stanford_dragon_100k" / "dragon.obj"


def _out(vertices, triangles):
    return (np.ascontiguousarray(vertices, dtype=np.float32),
            np.ascontiguousarray(triangles, dtype=np.int32).reshape(-1, 3))


def random_soup(rng: np.random.Generator, m: int, spread: float = 1.0, size: float = 0.2,
                center=(0.0, 0.0, 0.0)):
    """m independent triangles with centres uniform in a cube and vertices scattered by `size`."""
    c = rng.uniform(-spread, spread, (m, 1, 3)) + np.asarray(center)
    v = (c + rng.normal(0.0, size, (m, 3, 3))).reshape(-1, 3)
    return _out(v, np.arange(3 * m).reshape(m, 3))


def add_degenerates_and_duplicates(rng, vertices, triangles, n_degenerate: int, n_duplicate: int):
    """Insert zero-area triangles (repeated index, collinear points) and exact duplicates of
    existing triangles (same vertex indices) at random positions."""
    v = np.asarray(vertices, np.float32)
    t = np.asarray(triangles, np.int32)
    extra_t = []
    if n_degenerate:
        i = rng.integers(0, len(v), n_degenerate)
        j = rng.integers(0, len(v), n_degenerate)
        extra_t.append(np.stack([i, i, j], 1))  # repeated vertex
        # on a 1/64 grid so that a, a + step, a + 2 step are exactly collinear in float32
        a = np.round(v[rng.integers(0, len(v), n_degenerate)] * 64) / 64
        step = rng.integers(-3, 4, (n_degenerate, 3)).astype(np.float32) * np.float32(0.25)
        collinear = np.stack([a, a + step, a + 2 * step], 1).reshape(-1, 3)  # exact in float32
        extra_t.append(len(v) + np.arange(3 * n_degenerate).reshape(-1, 3))
        v = np.concatenate([v, collinear])
    if n_duplicate and len(t):
        extra_t.append(t[rng.integers(0, len(t), n_duplicate)])
    if extra_t:
        t = np.concatenate([t] + extra_t)
        t = t[rng.permutation(len(t))]
    return _out(v, t)


def unit_icosphere(subdivisions: int = 2):
    """Closed, watertight unit sphere in float64: vertices (V,3), triangles (M,3) int64 sharing
    vertex indices between neighbouring triangles, outward winding."""
    p = (1 + 5 ** 0.5) / 2
    verts = [(-1, p, 0), (1, p, 0), (-1, -p, 0), (1, -p, 0), (0, -1, p), (0, 1, p), (0, -1, -p),
             (0, 1, -p), (p, 0, -1), (p, 0, 1), (-p, 0, -1), (-p, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [np.asarray(x, float) / np.linalg.norm(x) for x in verts]
    f = faces
    for _ in range(subdivisions):
        mids = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in mids:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                mids[key] = len(v) - 1
            return mids[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return np.asarray(v), np.asarray(f, np.int64)


def icosphere(subdivisions: int = 2, radius: float = 1.0):
    """Closed, watertight sphere: shared vertex indices between neighbouring triangles."""
    v, f = unit_icosphere(subdivisions)
    return _out(v * radius, f)


def subdivided_cube(n: int = 4, half: float = 1.0):
    """Axis-aligned closed cube, each face an n x n grid of quads (two triangles each). Faces lie
    exactly on axis planes, so their bounding boxes are flat: a hard case for box tests."""
    g = np.linspace(-half, half, n + 1)
    verts, tris = [], []
    for axis in range(3):
        for side in (-half, half):
            a, b = [k for k in range(3) if k != axis]
            uu, vv = np.meshgrid(g, g, indexing="ij")
            p = np.zeros((n + 1, n + 1, 3))
            p[..., axis], p[..., a], p[..., b] = side, uu, vv
            base = sum(len(x) for x in verts)
            verts.append(p.reshape(-1, 3))
            idx = base + np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1)
            q0, q1, q2, q3 = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
            t = np.concatenate([np.stack([q0, q1, q2], -1).reshape(-1, 3),
                                np.stack([q0, q2, q3], -1).reshape(-1, 3)])
            if side < 0:
                t = t[:, ::-1]
            tris.append(t)
    v = np.concatenate(verts)
    t = np.concatenate(tris)
    # Merge the duplicated vertices along the cube's edges so the mesh is watertight by index.
    uniq, inverse = np.unique(np.round(v, 9), axis=0, return_inverse=True)
    return _out(uniq, inverse.reshape(-1)[t])


def torus(major: float = 1.0, minor: float = 0.35, nu: int = 24, nv: int = 12, bump: float = 0.0,
          rng: np.random.Generator | None = None):
    """Closed torus (nu x nv quads, 2*nu*nv triangles); `bump` adds radial noise."""
    a = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    b = np.linspace(0, 2 * np.pi, nv, endpoint=False)
    A, B = np.meshgrid(a, b, indexing="ij")
    r = minor * (1 + (bump * rng.uniform(-1, 1, A.shape) if bump else 0.0))
    v = np.stack([(major + r * np.cos(B)) * np.cos(A), (major + r * np.cos(B)) * np.sin(A),
                  r * np.sin(B)], -1).reshape(-1, 3)
    i = np.arange(nu)[:, None]
    j = np.arange(nv)[None, :]
    q0 = i * nv + j
    q1 = ((i + 1) % nu) * nv + j
    q2 = ((i + 1) % nu) * nv + (j + 1) % nv
    q3 = i * nv + (j + 1) % nv
    t = np.concatenate([np.stack(np.broadcast_arrays(q0, q1, q2), -1).reshape(-1, 3),
                        np.stack(np.broadcast_arrays(q0, q2, q3), -1).reshape(-1, 3)])
    return _out(v, t)


def tiny_grid(n: int = 40, cell: float = 1e-3, offset=(0.0, 0.0, 0.0), tilt: float = 0.0):
    """n x n cells of size `cell` (2*n*n tiny triangles) in a plane through `offset`, optionally
    tilted about the x axis by `tilt` radians (0 = exactly in the z = const plane)."""
    g = (np.arange(n + 1) - n / 2) * cell
    X, Y = np.meshgrid(g, g, indexing="ij")
    p = np.stack([X, Y * np.cos(tilt), Y * np.sin(tilt)], -1).reshape(-1, 3) + np.asarray(offset)
    idx = np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1)
    q0, q1, q2, q3 = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    t = np.concatenate([np.stack([q0, q1, q2], -1).reshape(-1, 3),
                        np.stack([q0, q2, q3], -1).reshape(-1, 3)])
    return _out(p, t)


def transformed(rng: np.random.Generator, vertices, triangles, scale: float = 1.0,
                shift: float = 0.0):
    """Random rotation, uniform scale and translation (keeps connectivity)."""
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    v = np.asarray(vertices, np.float64) @ q.T * scale + rng.uniform(-shift, shift, 3)
    return _out(v, triangles)


def generated_100k(seed: int = 7):
    """A closed, bumpy torus of exactly 100,000 triangles (250 x 200 quads)."""
    return torus(1.0, 0.4, 250, 200, bump=0.05, rng=np.random.default_rng(seed))


def mesh_100k(kind: str):
    """'dragon': the Stanford dragon from ../shared (None if absent); 'generated': built here."""
    if kind == "dragon":
        return load_obj(DRAGON_OBJ) if DRAGON_OBJ.exists() else None
    return generated_100k()


# Kinds of scenes drawn by the property-based tests: name -> builder(rng, size_hint).
def _soup(rng, k):
    return random_soup(rng, 20 + 60 * k, spread=1.0, size=rng.uniform(0.05, 0.4))


def _soup_dirty(rng, k):
    v, t = random_soup(rng, 20 + 40 * k, spread=1.0, size=0.3)
    return add_degenerates_and_duplicates(rng, v, t, 3 + k, 3 + k)


def _soup_far(rng, k):  # large coordinates far from the origin: precision stress
    return random_soup(rng, 20 + 40 * k, spread=50.0, size=20.0, center=(1000.0, -500.0, 250.0))


def _sphere(rng, k):
    v, t = icosphere(min(1 + k // 3, 4))
    return transformed(rng, v, t, scale=rng.uniform(0.5, 3.0), shift=1.0)


def _cube(rng, k):
    return subdivided_cube(1 + k, half=float(rng.choice([0.5, 1.0, 4.0])))


def _cube_rotated(rng, k):
    v, t = subdivided_cube(1 + k)
    return transformed(rng, v, t, scale=1.0, shift=0.5)


def _torus(rng, k):
    v, t = torus(1.0, 0.3, 8 + 4 * k, 6 + 2 * k, bump=0.1, rng=rng)
    return transformed(rng, v, t, scale=rng.uniform(0.5, 2.0), shift=1.0)


def _grid(rng, k):
    return tiny_grid(8 + 3 * k, cell=1e-3, offset=rng.uniform(-1, 1, 3),
                     tilt=float(rng.choice([0.0, 0.3])))


def _grid_far(rng, k):
    return tiny_grid(8 + 3 * k, cell=1e-2, offset=(100.0, 50.0, -20.0), tilt=0.0)


def _nested(rng, k):  # closed meshes inside each other: many occluders along each ray
    parts = [icosphere(2, 1.5), subdivided_cube(2 + k // 2, 0.6), torus(0.9, 0.15, 16, 8)]
    vs, ts, base = [], [], 0
    for v, t in parts:
        vs.append(v)
        ts.append(t + base)
        base += len(v)
    return transformed(rng, np.concatenate(vs), np.concatenate(ts), 1.0, 0.2)


SCENE_KINDS = {
    "soup": _soup, "soup_dirty": _soup_dirty, "soup_far": _soup_far, "sphere": _sphere,
    "cube": _cube, "cube_rotated": _cube_rotated, "torus": _torus, "grid": _grid,
    "grid_far": _grid_far, "nested": _nested,
}


def make_scene(kind: str, seed: int, size: int):
    """Deterministic scene of the given kind; size in 0..9 scales the triangle count."""
    return SCENE_KINDS[kind](np.random.default_rng(seed), size)
