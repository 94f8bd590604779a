// A mesh's islands as Cycles numbers them (util/disjoint_set.h, attr_create_random_per_island):
// a disjoint set over the vertices joined edge by edge in the mesh's stored order, union by
// rank with path compression. Which vertex ends as an island's root depends on that order and
// those rules, and Random Per Island hashes the root's index, so they are followed exactly.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

// roots[v] = the root of vertex v after joining edges (m pairs of vertex indices < V, in
// order). Sequential: each union depends on the ones before it.
void island_roots(size_t V, const int32_t* edges, size_t m, int64_t* roots);

}  // namespace dacrt
