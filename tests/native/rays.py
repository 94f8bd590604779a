"""Ray batches for the tracer tests: random rays inside and outside the scene bounds, camera
bundles, diffuse-bounce rays leaving surfaces, axis-aligned rays with zero (and -0.0) direction
components and origins on bounding-box planes, with finite or infinite tfar.

Generators return (org, dir, tfar) as float32 arrays; `to_rays` packs them into the 32-byte ray
record spelled out here from the API spec (not taken from dacrt, so the tests also check it)."""

from __future__ import annotations

import numpy as np

RAY_DTYPE = np.dtype([("org", "<f4", (3,)), ("dir", "<f4", (3,)), ("tfar", "<f4"),
                      ("id", "<u4")])
HIT_DTYPE = np.dtype([("t", "<f4"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")])


def to_rays(org, dirs, tfar=np.inf, ids=None) -> np.ndarray:
    n = len(org)
    r = np.zeros(n, RAY_DTYPE)
    r["org"], r["dir"] = org, dirs
    r["tfar"] = tfar
    r["id"] = np.arange(n) if ids is None else ids
    return r


def _bounds(vertices):
    if len(vertices) == 0:
        return np.zeros(3), np.ones(3)
    return vertices.min(0).astype(np.float64), vertices.max(0).astype(np.float64)


def _unit(rng, n):
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def random_rays(rng, vertices, triangles, n):
    """Origins uniform in the bounds grown 2x (about 1/8 inside), directions uniform with random
    lengths between 0.1 and 10 (the API does not require unit directions)."""
    lo, hi = _bounds(vertices)
    c, h = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-3)
    o = c + rng.uniform(-2, 2, (n, 3)) * h
    d = _unit(rng, n) * 10 ** rng.uniform(-1, 1, (n, 1))
    return o, d


def camera_rays(rng, vertices, triangles, n):
    """A pinhole camera outside the bounds looking at the scene: a coherent bundle."""
    lo, hi = _bounds(vertices)
    c = (lo + hi) / 2
    radius = max(np.linalg.norm(hi - lo) / 2, 1e-3)
    eye = c + _unit(rng, 1)[0] * radius * rng.uniform(1.5, 4.0)
    fwd = c + rng.normal(0, 0.1 * radius, 3) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 0.0, 1.0] if abs(fwd[2]) < 0.9 else [1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    w = max(1, int(np.sqrt(n)))
    hgt = max(1, n // w)
    sx, sy = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, (np.arange(hgt) + 0.5) / hgt * 2 - 1)
    tan = np.tan(np.radians(rng.uniform(20, 60)) / 2)
    d = fwd + (sx.reshape(-1, 1) * right + sy.reshape(-1, 1) * up) * tan
    return np.broadcast_to(eye, d.shape).copy(), d


def bounce_rays(rng, vertices, triangles, n):
    """Diffuse-bounce rays: origins at random points of random non-degenerate triangles, offset
    off the surface along the normal, cosine-distributed directions on the offset side."""
    v = vertices.astype(np.float64)
    t = triangles
    p0, p1, p2 = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    nrm = np.cross(p1 - p0, p2 - p0)
    length = np.linalg.norm(nrm, axis=1)
    good = np.flatnonzero(length > 0)
    if len(good) == 0:
        return random_rays(rng, vertices, triangles, n)
    k = good[rng.integers(0, len(good), n)]
    a, b = rng.uniform(size=(2, n, 1))
    flip = a + b > 1
    a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
    pts = p0[k] + a * (p1[k] - p0[k]) + b * (p2[k] - p0[k])
    nk = nrm[k] / length[k, None] * rng.choice([-1.0, 1.0], (n, 1))
    lo, hi = _bounds(vertices)
    scale = max(np.abs(lo).max(), np.abs(hi).max(), 1.0)
    o = pts + nk * scale * 1e-4
    # cosine-weighted hemisphere around nk
    r1, r2 = rng.uniform(size=(2, n, 1))
    tang = np.cross(nk, np.where(np.abs(nk[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    bit = np.cross(nk, tang)
    phi = 2 * np.pi * r1
    d = (np.cos(phi) * np.sqrt(r2)) * tang + (np.sin(phi) * np.sqrt(r2)) * bit + np.sqrt(
        np.maximum(1 - r2, 0.0)) * nk
    return o, d


def axis_rays(rng, vertices, triangles, n):
    """Directions with zero components (+-0.0 alike): along axes, diagonals in coordinate
    planes; half of the origins lie exactly on a bounding-box or vertex coordinate plane."""
    lo, hi = _bounds(vertices)
    c, h = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-3)
    o = c + rng.uniform(-1.5, 1.5, (n, 3)) * h
    planes = np.concatenate([lo[None], hi[None], vertices[rng.integers(0, max(1, len(vertices)),
                                                                      4)].astype(np.float64)]) \
        if len(vertices) else np.stack([lo, hi])
    on_plane = rng.uniform(size=n) < 0.5
    axis = rng.integers(0, 3, n)
    src = planes[rng.integers(0, len(planes), n), axis]
    o[np.arange(n)[on_plane], axis[on_plane]] = src[on_plane]
    d = rng.choice([-1.0, 0.0, 1.0], (n, 3)) * 10 ** rng.uniform(-1, 1, (n, 1))
    zero = np.all(d == 0, axis=1)
    d[zero, rng.integers(0, 3, zero.sum())] = 1.0
    neg_zero = (d == 0) & (rng.uniform(size=d.shape) < 0.5)
    d[neg_zero] = -0.0
    # Aim a quarter of them at the scene centre along one axis so they do hit something.
    aim = rng.uniform(size=n) < 0.25
    ax = rng.integers(0, 3, n)
    for i in np.flatnonzero(aim):
        o[i] = c + rng.uniform(-1, 1, 3) * h
        o[i, ax[i]] = c[ax[i]] - 3 * h[ax[i]]
        d[i] = 0.0
        d[i, ax[i]] = 1.0
    return o, d


RAY_KINDS = {"random": random_rays, "camera": camera_rays, "bounce": bounce_rays,
             "axis": axis_rays}
TFAR_KINDS = ("inf", "finite", "mixed")


def make_tfar(rng, kind, vertices, n):
    lo, hi = _bounds(vertices)
    extent = np.linalg.norm(hi - lo) + 1e-3
    if kind == "inf":
        return np.full(n, np.inf, np.float32)
    finite = rng.uniform(0, 2 * extent, n) * rng.choice([0.1, 1.0, 10.0], n)
    if kind == "finite":
        return finite.astype(np.float32)
    pick = rng.uniform(size=n)
    tf = np.where(pick < 0.5, np.inf, finite)
    tf[pick > 0.97] = 0.0  # t in (0, 0] is empty: these rays can never hit
    return tf.astype(np.float32)


def make_rays(kind: str, tfar_kind: str, vertices, triangles, n: int, seed: int):
    """(org, dir, tfar) float32 arrays; deterministic for the arguments."""
    rng = np.random.default_rng(seed)
    o, d = RAY_KINDS[kind](rng, np.asarray(vertices), np.asarray(triangles), n)
    o = np.asarray(o, np.float32)
    d = np.asarray(d, np.float32)
    bad = np.all(d == 0, axis=1)  # after rounding to float32: never hand out a zero direction
    d[bad] = np.float32(1.0)
    return o, d, make_tfar(rng, tfar_kind, np.asarray(vertices), len(o))
