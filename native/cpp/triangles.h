// Per-frame triangle data in the layout the tracer reads.
//
// The triangles in the caller's order or, with spatial_order, in Morton order of their box
// centres (a triangle's position in the order is its slot). Partitioning and leaves read the
// arrays below through id arrays; unless triangles near in space are near in memory those
// reads miss the cache (1M diffuse rays, 2 threads: the dragon 10.4 -> 11.2-12.0 Mrays/s, San
// Francisco +1-4%, a randomly shuffled San Francisco 7.7 -> 9.5). The order costs ~10 ns per
// triangle to build (a 1M-triangle grid 12 -> 22 ms), so it pays only for frames that trace
// several rays per triangle: the caller decides. Three arrays indexed by slot:
//  - boxes: the triangle's AABB as lo[4], hi[4] (32 bytes, one AVX load), used by partitioning;
//  - tris:  the compact triangle, Afra's trick: each AABB already holds 6 of the 9 vertex
//           coordinates (per axis the smallest and largest), so only the middle coordinate per
//           axis and which vertex holds min/max/mid are stored (16 bytes);
//  - prim:  the caller's triangle index, which is what hits, masks, skips and ties use, so
//           results do not depend on the order;
// plus the id array of the non-degenerate slots that every trace call copies and reorders.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstddef>
#include <memory>
#include <vector>

namespace dacrt {

// Vertex j of a caller's index array (corner j % 3 of triangle j / 3) of V vertices. The
// bindings check every index, but the array is the caller's, read again with the GIL released,
// and another Python thread may rewrite it meanwhile: each index is read once and clamped, so
// a rewritten triangle is a wrong triangle, never a read outside the vertex array (V >= 1 once
// some index passed the check).
template <class T, class Index>
inline const T* vertex_of(const T* vertices, size_t V, const Index* indices, size_t j) {
    const uint32_t k = uint32_t(__atomic_load_n(indices + j, __ATOMIC_RELAXED));
    return vertices + 3 * std::min(size_t(k), V - 1);
}

struct alignas(32) Box {
    float lo[4];
    float hi[4];
};

struct CompactTri {
    float mid[3];
    // Per axis a (4 bits at 4*a): bits 0-1 = vertex holding the minimum, bits 2-3 = the maximum.
    uint32_t code;
};

struct Bounds3 {
    float lo[3], hi[3];
};

// An array the build writes every element of: allocated without zero-filling it first (a
// std::vector would write the 48 MB of a 1M-triangle frame twice, once on one core).
template <class T>
class BuiltArray {
  public:
    explicit BuiltArray(size_t n) : p_(new T[n]), n_(n) {}
    T* data() { return p_.get(); }
    const T* data() const { return p_.get(); }
    size_t size() const { return n_; }
    T& operator[](size_t i) { return p_[i]; }
    const T& operator[](size_t i) const { return p_[i]; }

  private:
    std::unique_ptr<T[]> p_;
    size_t n_;
};

struct TriangleSet {
    BuiltArray<Box> boxes;
    BuiltArray<CompactTri> tris;
    BuiltArray<uint32_t> prim;
    std::vector<uint32_t> valid_ids;  // the non-degenerate slots, ascending: the root of every trace
    Bounds3 bounds{};                 // AABB of the valid triangles
    Bounds3 centroid_bounds{};        // AABB of their box centres
    float abs_max = 0.0f;             // largest |coordinate| of any valid vertex
    // A small triangle's size: the lower quartile of the valid triangles' largest box extent,
    // from up to 1024 evenly spaced ones (dispatch.cpp: which ray origins count as far).
    float fine_extent = 0.0f;
    size_t num_degenerate = 0;

    // vertices: V x 3 floats (finite, checked by the caller); indices: M x 3, each < V.
    TriangleSet(const float* vertices, size_t num_vertices, const uint32_t* indices, size_t num_tris,
                bool spatial_order);

    // Moves valid slot order[i] to slot i (order: a permutation of valid_ids), the degenerate
    // slots after them: valid_ids becomes 0, 1, ... in place.
    void reorder(const uint32_t* order);
};

// Box centre, in a form that cannot overflow for coordinates near the float limits.
inline float centre(float lo, float hi) { return lo * 0.5f + hi * 0.5f; }

// Rebuild the three vertices of triangle i (x, y, z, 0 each) from its box and compact record.
inline void reconstruct(const Box& b, const CompactTri& c, float v[3][4]) {
    for (int a = 0; a < 3; ++a) {
        const unsigned code = (c.code >> (4 * a)) & 15u;
        const unsigned imin = code & 3u, imax = code >> 2;
        const unsigned imid = 3u - imin - imax;
        v[imin][a] = b.lo[a];
        v[imax][a] = b.hi[a];
        v[imid][a] = c.mid[a];
    }
    v[0][3] = v[1][3] = v[2][3] = 0.0f;
}

}  // namespace dacrt
