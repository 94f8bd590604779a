"""Coincident faces: triangles modelled twice, exactly (the same three float32 corners in any
order or winding: a Mirror modifier on a mesh already symmetric, a second Mirror, duplicated
faces or objects). DACRT renders them as one surface (a ray leaving one copy steps off both,
surfacetables.twins); Cycles' rays leaving one copy meet the other at zero distance, so it
renders them darker (a cube mirrored twice, every face copied, grey world, 1 bounce: Cycles
0.324, DACRT 0.425 as the cube mirrored once; README "Coincident faces"). Said, naming the
objects. Emissive copies have their own message (lightsetup, lights/coincident.py), so sets
holding an emitter are left to it.

Cheap: only the triangles whose order-free corner hash repeats (Triangles.twins, from the
table pass every frame makes) are compared, bit for bit; without coincident faces none are.
Never claimed where no ray could tell the copies apart: the export's own twins (a ray-type mix's
clear or holdout side, seen by other ray kinds than the original: scenedata.Material.clear_twin),
zero-area triangles, wholly clear copies (a ray passes them all, in both), and a hair or
Curves tube's own triangles rounded onto each other at a thin tip (lightsetup._user_copies)."""
from __future__ import annotations

import numpy as np

from .scenedata import VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW

_K = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], np.uint64)


def exact_groups(vertices, indices, candidates):
    """(rows, group): the triangles of mask candidates that repeat another of them exactly (the
    same three float32 corners, -0 as 0, in any order or winding), in no set order, and each
    one's set (0..G-1); empty arrays where none does. Sorted by an order-free key of the
    corners, each triangle then compared bit for bit with the first of its key (the few whose
    key another surface shares are sorted apart by their bits): a 1M-triangle grid copied whole
    (2M candidates) in ~0.6 s, where sorting the bits of all as rows had taken 2.2 s."""
    S = np.flatnonzero(candidates)
    if len(S) < 2:
        return S[:0], S[:0]
    v = np.asarray(vertices, np.float32) + np.float32(0.0)
    corners = np.asarray(indices)[S]                                        # (S, 3)
    if 3 * len(S) > len(v):         # (a vertex's hash, hashed once)
        h = _hash(v)[corners]
    else:
        h = _hash(v[corners])
    # the corners in an order of their own (by hash, ties by position; a tie between two
    # different corners of one triangle can only miss a copy), 9 words a row
    h0, h1, h2 = h[:, 0], h[:, 1], h[:, 2]
    rank = np.stack([(h0 > h1).astype(np.int8) + (h0 > h2), (h1 >= h0).astype(np.int8) + (h1 > h2),
                     (h2 >= h0).astype(np.int8) + (h2 >= h1)], axis=1)
    sorted_corners = np.empty_like(corners)
    np.put_along_axis(sorted_corners, rank.astype(np.intp), corners, axis=1)
    key = h.sum(axis=1, dtype=np.uint64)
    by = np.argsort(key)
    key, S, sorted_corners = key[by], S[by], sorted_corners[by]
    start = np.r_[True, key[1:] != key[:-1]]
    run = np.cumsum(start) - 1
    first = np.flatnonzero(start)
    # each corner's bits as x, y in one word and z (gathers of plain words: a gather of 3-word
    # rows had cost twice the rest)
    b = v.view(np.uint32)
    xy, z = np.ascontiguousarray(b[:, :2]).view(np.uint64).ravel(), b[:, 2]
    ref = sorted_corners[first[run]]
    same = ((xy[sorted_corners] == xy[ref]) & (z[sorted_corners] == z[ref])).all(axis=1)
    group = run
    if not same.all():        # keys shared by different surfaces: those runs by their bits
        mixed = np.isin(run, run[~same])
        bits = b[sorted_corners[mixed]].reshape(-1, 9)
        rows = np.ascontiguousarray(bits).view(np.dtype((np.void, 36))).ravel()
        _, sub = np.unique(rows, return_inverse=True)
        group = group.copy()
        group[mixed] = len(first) + sub.ravel()
    count = np.bincount(group)
    copied = count[group] > 1
    label = np.cumsum(count > 1) - 1
    return S[copied], label[group[copied]]


def _hash(xyz) -> np.ndarray:
    """(...,) uint64: a hash of float32 points (..., 3) by their bits (equal points, equal hash)."""
    return (xyz.view(np.uint32).astype(np.uint64) * _K).sum(axis=-1, dtype=np.uint64)


def said_copies(rows, group, area, visibility, emissive, tubes=None):
    """Mask (M,) of the triangles of exact_groups' (rows, group) a message can truly say render
    differently from Cycles: of positive area, in a set without an emitter (said by lightsetup)
    where two copies a ray kind sees alike tell apart: two seen by bounce rays (one's bounce
    ray meets the other), or two seen by shadow rays and one by camera rays (its shadow rays
    meet the other). The export's own twins (a ray-type mix's clear or holdout side) are seen
    by other ray kinds than their original, so never. A tube's own triangles of one placement
    count as one copy. tubes: (one_sided (M,), placement (M,)) or None."""
    said = np.zeros(len(area), bool)
    if not len(rows):
        return said
    G = int(group.max()) + 1
    vis = np.asarray(visibility)[rows]
    live = np.asarray(area)[rows] > 0
    lit = np.bincount(group, weights=np.asarray(emissive)[rows], minlength=G) > 0
    # distinct copies: a tube triangle counts as its placement, any other as itself
    ident = rows.astype(np.int64)
    if tubes is not None:
        one, place = tubes
        ident = np.where(np.asarray(one, bool)[rows], -1 - np.asarray(place, np.int64)[rows], ident)
    seen = {kind: _distinct(group[m], ident[m], G)
            for kind in (VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW) for m in [live & ((vis & kind) != 0)]}
    ok = ((seen[VIS_DIFFUSE] >= 2) | ((seen[VIS_SHADOW] >= 2) & (seen[VIS_CAMERA] >= 1))) & ~lit
    said[rows[live & ((vis & (VIS_CAMERA | VIS_DIFFUSE | VIS_SHADOW)) != 0) & ok[group]]] = True
    return said


def _distinct(group, ident, G):
    """Per set (G,), how many distinct identities its listed members have (an identity below 0:
    a tube placement's, which its triangles share; any other is one triangle's own)."""
    n = np.bincount(group[ident >= 0], minlength=G)
    shared = ident < 0
    if shared.any():
        pairs = np.unique(group[shared].astype(np.int64) * (int(-ident.min()) + 1) - ident[shared])
        n += np.bincount(pairs // (int(-ident.min()) + 1), minlength=G)
    return n


def wholly_clear(mats):
    """(materials,) bool: the materials whose faces every ray passes (transparency 1 in every
    channel, no opacity map)."""
    return (mats.transparency.min(axis=0) >= 1.0) & ~np.isin(np.arange(len(mats.transparent)),
                                                             [e[0] for e in mats.opacity])


def material_family(sd):
    """(materials,) int64: the user's material each of sd's materials is a build of (a material
    built per ray kind or depth has variants), itself where it is the user's."""
    return np.array([m.variant_of if m.variant_of >= 0 else i for i, m in enumerate(sd.materials)], np.int64)


def coincident_faces(sd, tri, mats) -> list:
    """The message (a list of 0 or 1 (level, text)) naming the objects whose non-emissive
    faces coincide exactly with other faces (sd: the SceneData tri was made of, naming the
    objects; tri: surfacetables.Triangles; mats: surfacetables.Materials)."""
    if not tri.twins.any():
        return []
    # wholly clear copies (a white Transparent BSDF) render alike in both: a ray passes them all
    clear = wholly_clear(mats)
    rows, group = exact_groups(tri.vertices, tri.indices, tri.twins & ~clear[tri.material])
    g = sd.geometry
    tubes = None if g.one_sided is None else \
        (g.one_sided, g.instance if g.instance is not None else g.object_index)
    # (a copy built for the deeper bounce rays (depth_class 2) is never met by the rays that meet
    # its first-bounce twin: one surface to bounce rays)
    vis = tri.visibility
    depth = np.array([getattr(m, 'depth_class', 0) for m in sd.materials], np.int8)
    if (depth == 2).any():
        vis = np.where(depth[np.asarray(tri.material)] == 2, vis & np.uint8(~VIS_DIFFUSE & 0xFF), vis).astype(vis.dtype)
    said = said_copies(rows, group, tri.area, vis, mats.emissive[tri.material], tubes)
    # (a material built per ray kind has a copy of each triangle per variant, in the same set:
    # counted once, as the user's triangle, and as the material it is a build of)
    family = material_family(sd)
    mat = family[np.asarray(tri.material)]
    said &= mat == np.asarray(tri.material)
    if not said.any():
        return []
    # (half-clear copies too: Mix(Diffuse 0.1, Transparent, 0.5) twice under a white world, K = 1:
    # Cycles 0.526, DACRT 0.55 as the single plane)
    text = (f"{int(said.sum())} triangles of {sd.named_objects(said)} coincide exactly with other triangles "
            "(the same three corners: duplicated faces, or a Mirror modifier on a mesh already symmetric): "
            "DACRT renders each set as one surface; Cycles' rays leaving one copy meet the other at zero "
            "distance, so it renders them darker (black with enough bounces)")
    # copies of different materials: the hit returns the copy listed first (exact ties)
    kept = said[rows]
    g, m = group[kept], mat[rows[kept]]
    one = np.zeros(int(group.max()) + 1, m.dtype)
    one[g] = m                          # (some member's material per set)
    if (m != one[g]).any():
        text += "; where the copies' materials differ, DACRT shows mostly the first-listed copy's"
    return [('INFO', text)]
