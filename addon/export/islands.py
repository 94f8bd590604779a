"""Cycles' Random Per Island (the Geometry node's output, the standard attribute
'random_per_island'): each triangle's island, the set of vertices its mesh's edges join, hashed
from the index of the set's representative, as Cycles' attr_create_random_per_island computes it
at sync: a disjoint set joined edge by edge in the mesh's stored edge order (union by rank, path
compression: util/disjoint_set.h), whose root for a vertex of the triangle is hashed by
hash_uint_to_float. Which vertex is the root depends on that order and those rules, so they are
followed exactly (a component labelling would give other roots, other numbers): native/cpp/islands.cpp."""

from __future__ import annotations

import dacrt.shading
import numpy as np

from ..procedural import hash_uint_to_float


def random_per_island(vertex_count, edges, triangles):
    """(nt,) float32 Random Per Island of triangles ((nt, 3) vertex indices; every corner of a
    triangle is in its island, so any gives its root)."""
    roots = dacrt.shading.island_roots(vertex_count, edges)     # (one native pass: 1M edges in Python took ~1 s)
    tris = np.asarray(triangles, np.int64).reshape(-1, 3)
    return hash_uint_to_float(roots[tris[:, 0]].astype(np.uint32))
