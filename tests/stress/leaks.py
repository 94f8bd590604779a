"""Watertightness rays and leak counting, for DACRT and (for comparison) Embree.

Two kinds of rays, each aimed exactly at a vertex or at a point of an edge of a mesh:
- inside rays: from points inside a closed, star-shaped mesh (icosphere, subdivided cube, a double
  fan of 1,000 thin triangles around each apex) towards every vertex and one point per edge.
  Any miss is a leak. Rays from the centre towards a vertex are exact in float32 when the centre
  is the origin (the direction *is* the vertex), e.g. the +z axis through the fan's apex.
- crossing rays: through interior vertices and edges of any mesh (closed or open, the real
  scenes too), from both sides, along a direction in which every triangle around the target
  faces the same way (their projections along the ray then cover a neighbourhood of the target,
  with a margin). Such a ray must hit one of those triangles at the target's distance (or an
  occluder before it); a miss, or a first hit clearly beyond the target, means it slipped
  through the surface: a leak.
Targets whose neighbourhood is too small for float32 at their coordinates (fewer than ~1,000
ulps across) are left out, so every counted leak is a genuine one.
"""

from __future__ import annotations

import os
import zlib
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache

import dacrt
import numpy as np

from ..native import scenes
from ..objfile import load_obj

SCENES_DIR = scenes.SHARED / "scenes"
REAL_SCENES = {  # name -> OBJ path under ../shared/scenes (bmw27 is a .blend: needs bpy)
    "cornellbox": "cornellbox_mcguire/CornellBox-Original.obj",
    "suzanne": "suzanne/suzanne.obj",
    "bunny": "stanford_bunny/stanford-bunny.obj",
    "sibenik": "sibenik/sibenik.obj",
    "dragon": "stanford_dragon_100k/dragon.obj",
    "san_francisco": "sionna_san_francisco/san_francisco_merged.obj",
}
T_SLACK = 1e-3  # a first hit beyond (1 + T_SLACK) x the target distance passed through the surface
MARGIN = 0.05   # min cosine between the ray and every triangle around its target


def fan_bicone(n: int = 1000, radius: float = 1.0, height: float = 1.0):
    """Closed double fan: a ring of n vertices joined to an apex above and one below, 2n thin
    triangles (apex angle 2 pi / n) meeting in two vertices of valence n."""
    a = 2 * np.pi * np.arange(n) / n
    ring = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(n)], 1)
    v = np.concatenate([ring, [[0.0, 0.0, height], [0.0, 0.0, -height]]])
    i = np.arange(n)
    j = (i + 1) % n
    top = np.stack([i, j, np.full(n, n)], 1)
    bottom = np.stack([j, i, np.full(n, n + 1)], 1)
    return np.ascontiguousarray(v, np.float32), np.ascontiguousarray(
        np.concatenate([top, bottom]), np.int32)


CLOSED_MESHES = {
    "icosphere": lambda: scenes.icosphere(4, 1.0),
    "cube": lambda: scenes.subdivided_cube(16, 1.0),
    "fan1000": lambda: fan_bicone(1000),
}


def real_scene_path(name: str):
    return SCENES_DIR / REAL_SCENES[name]


@lru_cache(maxsize=8)
def real_scene(name: str):
    """(vertices, triangles) of a real scene, or None when ../shared/scenes lacks it."""
    path = real_scene_path(name)
    if not path.exists():
        return None
    v, t = load_obj(path)
    v.setflags(write=False)
    t.setflags(write=False)
    return v, t


@dataclass
class RaySet:
    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    org: np.ndarray       # (N,3) float32
    dirs: np.ndarray      # (N,3) float32
    t_expect: np.ndarray  # (N,) float64 distance to the target in units of dir; inf: any hit

    def __len__(self):
        return len(self.org)

    def tfar(self):
        """tfar for occluded(): just past the target (inf for inside rays)."""
        return np.where(np.isfinite(self.t_expect), self.t_expect * (1 + T_SLACK),
                        np.inf).astype(np.float32)


def concat(name, sets):
    sets = [s for s in sets if len(s)]
    return RaySet(name, sets[0].vertices, sets[0].triangles,
                  np.concatenate([s.org for s in sets]), np.concatenate([s.dirs for s in sets]),
                  np.concatenate([s.t_expect for s in sets]))


def placed(vertices, scale: float, offset: float):
    return (np.asarray(vertices, np.float64) * scale + offset).astype(np.float32)


def inside_rays(name, v, t, scale, offset, rng, origins_per_target=2):
    """From the centre (exactly aimed) and from random interior points towards every vertex
    and one random point per edge. The meshes are star-shaped around their centre."""
    vv = v.astype(np.float64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    w = rng.random((len(e), 1))
    targets = np.concatenate([vv, vv[e[:, 0]] * w + vv[e[:, 1]] * (1 - w)])
    centre = np.full(3, offset, np.float64)
    orgs = [np.broadcast_to(centre, targets.shape)]
    for _ in range(origins_per_target - 1):
        orgs.append(centre + rng.uniform(-0.3, 0.3, targets.shape) * scale)
    org = np.concatenate(orgs).astype(np.float32)
    tg = np.tile(targets, (origins_per_target, 1)).astype(np.float32)
    dirs = tg - org  # float32 arithmetic: exact for the centre at 0 (dir = target)
    keep = np.any(dirs != 0, axis=1)
    return RaySet(name, v, t, org[keep], dirs[keep], np.full(int(keep.sum()), np.inf))


def grazing_rays(name, v, t, rng, heights=(1e-2, 1e-3, 1e-4, 1e-5)):
    """Rays from just inside a closed convex mesh, nearly parallel to a face, out through that
    face's vertices and a point of each of its edges. The origin lies a height (relative to the
    mesh's size) below a random point of the face, so the ray grazes the face (the sine of its
    angle is about height / distance) and meets the neighbour across the edge at a healthy
    angle, or grazes a coplanar neighbour. Rounding decides which triangle the float test
    picks; none may let the ray out, so any miss is a leak."""
    vv = v.astype(np.float64)
    p = vv[t]                                             # (M, 3 corners, 3)
    n = _unit(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    centre = vv.mean(axis=0)
    q_w = rng.dirichlet([4.0, 4.0, 4.0], len(t))         # well inside the face
    q = np.einsum("mk,mka->ma", q_w, p)
    n = n * np.sign(np.einsum("ma,ma->m", n, q - centre))[:, None]  # outward
    size = np.abs(vv - centre).max()
    e_w = rng.uniform(0.05, 0.95, (len(t), 3, 1))
    edge_pts = p * e_w + p[:, [1, 2, 0]] * (1 - e_w)
    targets = np.concatenate([p, edge_pts], axis=1)      # (M, 6, 3)
    h = np.asarray(heights)[rng.integers(0, len(heights), (len(t), 6))] * size
    org = q[:, None, :] - h[..., None] * n[:, None, :]
    org32 = org.reshape(-1, 3).astype(np.float32)
    dirs = (targets.reshape(-1, 3) - org32.astype(np.float64)).astype(np.float32)
    return RaySet(name, v, t, org32, dirs, np.full(len(org32), np.inf))


def _unit(x):
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _topology(v, t):
    """Interior manifold edges (two consistently oriented triangles) and the vertices all of
    whose edges are such; unit normals of non-degenerate triangles."""
    vv = v.astype(np.float64)
    p0, p1, p2 = vv[t[:, 0]], vv[t[:, 1]], vv[t[:, 2]]
    cr = np.cross(p1 - p0, p2 - p0)
    area = np.linalg.norm(cr, axis=1)
    good_tri = area > 0
    normal = np.where(good_tri[:, None], cr / np.where(area > 0, area, 1.0)[:, None], 0.0)
    m = len(t)
    src = np.concatenate([t[:, 0], t[:, 1], t[:, 2]]).astype(np.int64)
    dst = np.concatenate([t[:, 1], t[:, 2], t[:, 0]]).astype(np.int64)
    tri = np.tile(np.arange(m), 3)
    nv = len(v)
    key = np.minimum(src, dst) * nv + np.maximum(src, dst)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    count = np.diff(np.r_[start, len(ks)])
    a_idx, b_idx = order[start], order[np.minimum(start + 1, len(ks) - 1)]
    pair = (count == 2) & (src[a_idx] == dst[b_idx]) & (dst[a_idx] == src[b_idx]) \
        & good_tri[tri[a_idx]] & good_tri[tri[b_idx]] & (tri[a_idx] != tri[b_idx])
    # vertices: every incident edge must be a good pair
    bad_vertex = np.zeros(nv, bool)
    bad_keys = ks[start[~pair]]
    bad_vertex[bad_keys // nv] = True
    bad_vertex[bad_keys % nv] = True
    bad_vertex[t[~good_tri].ravel()] = True
    used = np.zeros(nv, bool)
    used[t.ravel()] = True
    edges = np.stack([src[a_idx[pair]], dst[a_idx[pair]]], 1)
    edge_tris = np.stack([tri[a_idx[pair]], tri[b_idx[pair]]], 1)
    return normal, edges, edge_tris, used & ~bad_vertex


def _tilted(rng, base, margin_of):
    """A direction near `base` (random tilt) where all triangles around the target still face
    it with MARGIN, else `base` itself; returns (direction, its margin)."""
    d = _unit(base + 0.4 * _unit(rng.normal(size=base.shape)))
    d = np.where((margin_of(d) > MARGIN)[:, None], d, base)
    return d, margin_of(d)


def crossing_rays(name, v, t, rng, max_targets=None, both_sides=True):
    """Rays through interior vertices and edge points along directions in which all triangles
    around the target face one way (see the module docstring); from both sides."""
    vv = v.astype(np.float64)
    normal, edges, edge_tris, interior = _topology(v, t)
    sets_o, sets_d, sets_t = [], [], []

    # vertices: sum of incident unit normals; margin = min over incident triangles
    m = len(t)
    vid = t.ravel().astype(np.int64)
    tid = np.repeat(np.arange(m), 3)
    nsum = np.zeros((len(v), 3))
    np.add.at(nsum, vid, normal[tid])
    cand = np.flatnonzero(interior & (np.linalg.norm(nsum, axis=1) > 0))
    if max_targets and len(cand) > max_targets:
        cand = np.sort(rng.choice(cand, max_targets, replace=False))
    if len(cand):
        def vertex_margin(direction):
            full = np.zeros((len(v), 3))
            full[cand] = direction
            worst = np.full(len(v), np.inf)
            np.minimum.at(worst, vid, np.einsum("ij,ij->i", full[vid], normal[tid]))
            return worst[cand]
        d, marg = _tilted(rng, _unit(nsum[cand]), vertex_margin)
        elen = np.full(len(v), np.inf)  # neighbourhood size: shortest incident edge
        for a, b in ((0, 1), (1, 2), (2, 0)):
            ln = np.linalg.norm(vv[t[:, a]] - vv[t[:, b]], axis=1)
            np.minimum.at(elen, t[:, a], ln)
            np.minimum.at(elen, t[:, b], ln)
        size = elen[cand] * marg
        ok = (marg > MARGIN) & (size > 1e-4 * np.max(np.abs(vv[cand]), axis=1))
        sets_o.append(vv[cand[ok]])
        sets_d.append(d[ok])
        sets_t.append(0.5 * elen[cand[ok]])

    # edges: a random point of each interior edge
    if len(edges):
        sel = np.arange(len(edges))
        if max_targets and len(sel) > max_targets:
            sel = np.sort(rng.choice(sel, max_targets, replace=False))
        e, et = edges[sel], edge_tris[sel]
        n1, n2 = normal[et[:, 0]], normal[et[:, 1]]
        base = n1 + n2
        okb = np.linalg.norm(base, axis=1) > 1e-6
        e, n1, n2, base = e[okb], n1[okb], n2[okb], _unit(base[okb])
        d, marg = _tilted(rng, base, lambda x: np.minimum(np.einsum("ij,ij->i", x, n1),
                                                          np.einsum("ij,ij->i", x, n2)))
        a, b = vv[e[:, 0]], vv[e[:, 1]]
        w = rng.uniform(0.02, 0.98, (len(e), 1))
        p = a * w + b * (1 - w)
        length = np.linalg.norm(b - a, axis=1)
        ok = (marg > MARGIN) & (length * np.minimum(w, 1 - w)[:, 0] * marg >
                                1e-4 * np.max(np.abs(p), axis=1))
        sets_o.append(p[ok])
        sets_d.append(d[ok])
        sets_t.append(0.5 * length[ok])

    target = np.concatenate(sets_o) if sets_o else np.zeros((0, 3))
    nrm = np.concatenate(sets_d) if sets_d else np.zeros((0, 3))
    dist = np.concatenate(sets_t) if sets_t else np.zeros(0)
    orgs, dirs, ts = [], [], []
    for side in ((1.0, -1.0) if both_sides else (1.0,)):
        o = (target + side * dist[:, None] * nrm).astype(np.float32)
        # aimed from the float32 origin: exact through a vertex whenever target - o is a
        # float32 (most rays); within rounding of the target otherwise
        dd = (target - o.astype(np.float64)).astype(np.float32)
        # distance to the target along the float32 ray, in units of its direction
        tt = np.einsum("ij,ij->i", target - o.astype(np.float64), dd.astype(np.float64)) / \
            np.einsum("ij,ij->i", dd.astype(np.float64), dd.astype(np.float64))
        orgs.append(o)
        dirs.append(dd)
        ts.append(tt)
    return RaySet(name, v, t, np.concatenate(orgs), np.concatenate(dirs), np.concatenate(ts))


# The stress run's ray sets: every closed mesh at every placement (scale, offset), inside and
# crossing rays; the real scenes' crossing rays (up to REAL_TARGETS vertices and as many edges).
PLACEMENTS = [(1.0, 0.0), (1e-4, 0.0), (1e4, 0.0), (1.0, 1e5), (1e3, 1e5), (1e-30, 0.0),
              (1e18, 0.0)]
REAL_TARGETS = 60_000


def seeded_rng(*key):
    return np.random.default_rng(zlib.crc32(repr(key).encode()))


def closed_sets(name, scale, offset):
    v0, t = CLOSED_MESHES[name]()
    v = placed(v0, scale, offset)
    label = f"{name} x{scale:g} +{offset:g}"
    return [inside_rays(label + " inside", v, t, scale, offset, seeded_rng(name, scale, offset)),
            crossing_rays(label + " crossing", v, t, seeded_rng(name, scale, offset, 1))]


def real_set(name, max_targets):
    vt = real_scene(name)
    if vt is None:
        return None
    return crossing_rays(name, *vt, seeded_rng(name), max_targets=max_targets)


@lru_cache(maxsize=1)
def watertight_sets():
    """(ray sets, names of real scenes that are absent)."""
    sets = [s for name in CLOSED_MESHES for sc, off in PLACEMENTS
            for s in closed_sets(name, sc, off)]
    missing = []
    for name in REAL_SCENES:
        rs = real_set(name, REAL_TARGETS)
        if rs is None:
            missing.append(name)
        else:
            sets.append(rs)
    return [s for s in sets if len(s)], missing


def leaks(prim, t, t_expect):
    """Leak mask: a miss, or a first hit clearly beyond the target."""
    return (prim < 0) | (np.isfinite(t_expect) & (t > t_expect * (1 + T_SLACK)))


@contextmanager
def isa_env(isa):
    old = os.environ.get("DACRT_ISA")
    os.environ["DACRT_ISA"] = isa
    try:
        yield
    finally:
        if old is None:
            del os.environ["DACRT_ISA"]
        else:
            os.environ["DACRT_ISA"] = old


def dacrt_leaks(rs: RaySet, isa: str, partition: str, threads: int, module=dacrt):
    """(intersect leak mask, occluded leak mask) of DACRT (or another build of it, `module`)
    for the ray set."""
    with isa_env(isa):
        scene = module.Scene(rs.vertices, rs.triangles, partition=partition)
        hits = scene.intersect(module.make_rays(rs.org, rs.dirs), threads=threads)
        occ = scene.occluded(module.make_rays(rs.org, rs.dirs, rs.tfar()), threads=threads)
    return leaks(hits["prim"], hits["t"], rs.t_expect), ~occ


def describe(rs: RaySet, mask, what):
    i = np.flatnonzero(mask)
    if len(i) == 0:
        return f"{rs.name}: no leaks in {len(rs)} rays ({what})"
    k = i[0]
    return (f"{rs.name} [{what}]: {len(i)} of {len(rs)} rays leaked, e.g. org="
            f"{rs.org[k].tolist()} dir={rs.dirs[k].tolist()} target distance={rs.t_expect[k]!r}")


def embree_leaks(rs: RaySet):
    """Leak mask of Embree (embreex, robust mode) on the same rays, or None if unavailable."""
    try:
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        return None
    scene = rtcs.EmbreeScene(robust=True)
    TriangleMesh(scene, np.ascontiguousarray(rs.vertices, np.float32),
                 np.ascontiguousarray(rs.triangles, np.int32))
    out = scene.run(np.ascontiguousarray(rs.org), np.ascontiguousarray(rs.dirs), output=1)
    return leaks(np.asarray(out["primID"]), np.asarray(out["tfar"]), rs.t_expect)
