#include "islands.h"

#include <utility>
#include <vector>

namespace dacrt {

namespace {

// Cycles' DisjointSet::find: the root, then every node on the way pointed at it.
uint32_t find(std::vector<uint32_t>& parent, uint32_t x) {
    uint32_t root = x;
    while (parent[root] != root) root = parent[root];
    while (parent[x] != root) {
        const uint32_t next = parent[x];
        parent[x] = root;
        x = next;
    }
    return root;
}

}  // namespace

void island_roots(size_t V, const int32_t* edges, size_t m, int64_t* roots) {
    std::vector<uint32_t> parent(V);
    std::vector<uint8_t> rank(V, 0);  // (a rank reaches at most log2 V)
    for (size_t v = 0; v < V; ++v) parent[v] = uint32_t(v);
    for (size_t e = 0; e < m; ++e) {
        uint32_t a = find(parent, uint32_t(edges[2 * e])), b = find(parent, uint32_t(edges[2 * e + 1]));
        if (a == b) continue;
        if (rank[a] < rank[b]) std::swap(a, b);  // Cycles' join: the higher rank's root stays
        parent[b] = a;
        if (rank[a] == rank[b]) ++rank[a];
    }
    for (size_t v = 0; v < V; ++v) roots[v] = find(parent, uint32_t(v));
}

}  // namespace dacrt
