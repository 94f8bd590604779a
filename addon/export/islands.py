"""Cycles' Random Per Island (the Geometry node's output, the standard attribute
'random_per_island'): each triangle's island, the set of vertices its mesh's edges join, hashed
from the index of the set's representative, as Cycles' attr_create_random_per_island computes it
at sync: a disjoint set joined edge by edge in the mesh's stored edge order (union by rank, path
compression: util/disjoint_set.h), whose root for a vertex of the triangle is hashed by
hash_uint_to_float. Which vertex is the root depends on that order and those rules, so they are
followed exactly (a component labelling would give other roots, other numbers)."""

from __future__ import annotations

import numpy as np

from ..procedural import hash_uint_to_float


def island_roots(vertex_count, edges):
    """(vertex_count,) int64: each vertex's root in Cycles' DisjointSet after joining `edges`
    ((m, 2) vertex indices) in order."""
    parents = list(range(vertex_count))
    ranks = [0] * vertex_count

    def find(x):
        root = x
        while parents[root] != root:
            root = parents[root]
        while parents[x] != root:
            parents[x], x = root, parents[x]
        return root

    for a, b in np.asarray(edges, np.int64).reshape(-1, 2).tolist():
        ra, rb = find(a), find(b)
        if ra == rb:
            continue
        if ranks[ra] < ranks[rb]:
            ra, rb = rb, ra
        parents[rb] = ra
        if ranks[ra] == ranks[rb]:
            ranks[ra] += 1
    return np.array([find(v) for v in range(vertex_count)], np.int64)


def random_per_island(vertex_count, edges, triangles):
    """(nt,) float32 Random Per Island of triangles ((nt, 3) vertex indices; every corner of a
    triangle is in its island, so any gives its root)."""
    roots = island_roots(vertex_count, edges)
    tris = np.asarray(triangles, np.int64).reshape(-1, 3)
    return hash_uint_to_float(roots[tris[:, 0]].astype(np.uint32))
