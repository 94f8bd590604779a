"""dacrt.shading.island_roots (native/cpp/islands.cpp) against a plain Python disjoint set
written from Cycles' util/disjoint_set.h: union by rank in edge order, path compression. The
roots, not just the partition, must agree, since Random Per Island hashes the root's index."""

import numpy as np
import pytest

import dacrt.shading


def _reference_roots(vertex_count, edges):
    parent, rank = list(range(vertex_count)), [0] * vertex_count

    def find(x):
        root = x
        while parent[root] != root:
            root = parent[root]
        while parent[x] != root:
            parent[x], x = root, parent[x]
        return root

    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra == rb:
            continue
        if rank[ra] < rank[rb]:
            ra, rb = rb, ra
        parent[rb] = ra
        if rank[ra] == rank[rb]:
            rank[ra] += 1
    return [find(v) for v in range(vertex_count)]


@pytest.mark.parametrize('seed', range(6))
def test_roots_follow_cycles_disjoint_set_in_edge_order(seed):
    rng = np.random.default_rng(seed)
    v = int(rng.integers(1, 400))
    # a mix of chains, stars and random joins, in shuffled order: roots depend on the order
    m = int(rng.integers(0, 3 * v))
    edges = rng.integers(0, v, size=(m, 2))
    if v > 3:
        chain = np.stack([np.arange(v // 2), np.arange(1, v // 2 + 1)], 1)
        edges = np.concatenate([edges, chain[rng.permutation(len(chain))]])
    got = dacrt.shading.island_roots(v, edges)
    assert got.dtype == np.int64 and got.shape == (v,)
    assert got.tolist() == _reference_roots(v, edges.tolist())


def test_order_decides_the_root():
    """The same three edges in two orders: one island, rooted at another vertex."""
    a = dacrt.shading.island_roots(4, [[0, 1], [2, 3], [1, 2]])
    b = dacrt.shading.island_roots(4, [[2, 3], [0, 1], [3, 1]])
    assert len(set(a.tolist())) == 1 and len(set(b.tolist())) == 1
    assert a[0] == 0 and b[0] == 2


def test_no_edges_and_bad_indices():
    assert dacrt.shading.island_roots(3, np.zeros((0, 2), np.int32)).tolist() == [0, 1, 2]
    with pytest.raises(ValueError, match="outside"):
        dacrt.shading.island_roots(3, [[0, 3]])
    with pytest.raises(ValueError, match="outside"):
        dacrt.shading.island_roots(3, [[-1, 0]])
