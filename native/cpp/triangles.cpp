// Builds the per-frame triangle arrays (see triangles.h).
#include "triangles.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "parallel.h"

namespace dacrt {

// Zero area in exact arithmetic on the float inputs. In double, differences of floats and their
// products are exact unless the exponents are far apart, so a nonzero double cross product
// means a real triangle; only a zero one is confirmed in long double (64-bit mantissa).
// A triangle flagged here can never be hit; anything else is left to the watertight test.
template <class T>
static bool zero_cross(const float* a, const float* b, const float* c) {
    T e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = T(b[k]) - T(a[k]);
        e2[k] = T(c[k]) - T(a[k]);
    }
    return e1[1] * e2[2] - e1[2] * e2[1] == 0 && e1[2] * e2[0] - e1[0] * e2[2] == 0 &&
           e1[0] * e2[1] - e1[1] * e2[0] == 0;
}

static bool degenerate(const float* a, const float* b, const float* c) {
    return zero_cross<double>(a, b, c) && zero_cross<long double>(a, b, c);
}

namespace {

// Spreads the low 5 bits of x to every third bit.
uint32_t spread3(uint32_t x) {
    x &= 31u;
    x = (x | (x << 8)) & 0x0000F00Fu;
    x = (x | (x << 4)) & 0x000C30C3u;
    x = (x | (x << 2)) & 0x00249249u;
    return x;
}

// Morton order needs a frame before the triangles are built: the box of all vertices (an
// unused far vertex only coarsens the order, never changes a result).
Bounds3 vertex_bounds(const float* V, size_t nv) {
    std::vector<Bounds3> part(size_t(threads_for(nv, size_t(1) << 16)));
    run_workers(int(part.size()), [&](int w) {
        const size_t b = nv * size_t(w) / part.size(), e = nv * size_t(w + 1) / part.size();
        Bounds3 r;
        for (int a = 0; a < 3; ++a) { r.lo[a] = INFINITY; r.hi[a] = -INFINITY; }
        for (size_t i = b; i < e; ++i)
            for (int a = 0; a < 3; ++a) {
                r.lo[a] = std::min(r.lo[a], V[3 * i + a]);
                r.hi[a] = std::max(r.hi[a], V[3 * i + a]);
            }
        part[size_t(w)] = r;
    });
    Bounds3 r = part[0];
    for (const Bounds3& q : part)
        for (int a = 0; a < 3; ++a) { r.lo[a] = std::min(r.lo[a], q.lo[a]); r.hi[a] = std::max(r.hi[a], q.hi[a]); }
    return r;
}

// Pass 1, triangles [b, e): the Morton key of each box centre's cell, k <= 5 bits per axis of
// the vertex bounds (a NaN from an overflowed extent lands in cell 0), with the triangle index
// in the low 32 bits.
void key_range(const float* V, size_t nv, const uint32_t* I, size_t b, size_t e, const Bounds3& vb, int k,
               uint64_t* keys) {
    const float top = float((1 << k) - 1);
    float scale[3];
    for (int a = 0; a < 3; ++a) {
        const float ext = vb.hi[a] - vb.lo[a], sc = top / ext;
        scale[a] = ext > 0.0f && std::isfinite(sc) ? sc : 0.0f;
    }
    for (size_t i = b; i < e; ++i) {
        const float* p[3] = {vertex_of(V, nv, I, 3 * i), vertex_of(V, nv, I, 3 * i + 1), vertex_of(V, nv, I, 3 * i + 2)};
        uint32_t key = 0;
        for (int a = 0; a < 3; ++a) {
            const float lo = std::min(p[0][a], std::min(p[1][a], p[2][a]));
            const float hi = std::max(p[0][a], std::max(p[1][a], p[2][a]));
            const float f = (centre(lo, hi) - vb.lo[a]) * scale[a];
            key |= spread3(uint32_t(f > 0.0f ? (f < top ? f : top) : 0.0f)) << a;
        }
        keys[i] = uint64_t(key) << 32 | i;
    }
}

// Sorts keys (key << 32 | triangle) by their `bits`-bit key: one stable counting pass, each
// thread counting and then scattering its own contiguous share, so equal keys keep the
// caller's triangle order and the result does not depend on the thread count.
void counting_sort(BuiltArray<uint64_t>& keys, int bits) {
    const size_t digits = size_t(1) << bits, n = keys.size();
    const int T = threads_for(n, size_t(1) << 16);
    BuiltArray<uint64_t> out(n);
    std::vector<uint32_t> start(size_t(T) * digits, 0u);
    const uint64_t* src = keys.data();
    run_workers(T, [&](int w) {
        uint32_t* c = start.data() + size_t(w) * digits;
        for (size_t i = n * size_t(w) / size_t(T), e = n * size_t(w + 1) / size_t(T); i < e; ++i) ++c[src[i] >> 32];
    });
    uint32_t sum = 0;  // digit-major, then thread: thread w's keys of a digit follow w - 1's
    for (size_t d = 0; d < digits; ++d)
        for (int w = 0; w < T; ++w) {
            uint32_t& c = start[size_t(w) * digits + d];
            const uint32_t m = c;
            c = sum;
            sum += m;
        }
    run_workers(T, [&](int w) {
        uint32_t* c = start.data() + size_t(w) * digits;
        for (size_t i = n * size_t(w) / size_t(T), e = n * size_t(w + 1) / size_t(T); i < e; ++i)
            out[c[src[i] >> 32]++] = src[i];
    });
    std::swap(keys, out);
}

// One thread's share of pass 2: the bounds of its valid triangles (min/max merge in any order
// to the same bits) and how many were degenerate.
struct Part {
    Bounds3 bounds, centroid_bounds;
    float abs_max = 0.0f;
    size_t degenerate = 0;
};

// Pass 2, slots [b, e): box, compact record and caller's index of the triangle in the low 32
// bits of order[s] (no order: slot s is triangle s), and whether it is degenerate.
void build_range(const float* V, size_t nv, const uint32_t* I, const uint64_t* order, size_t b, size_t e, Box* boxes,
                 CompactTri* tris, uint32_t* prim, uint8_t* bad, Part& part) {
    // Bounds in locals: through `part` every box store could alias them, which turned the
    // min/max updates into a chain of stores and reloads.
    float lo[3], hi[3], clo[3], chi[3], abs_max = 0.0f;
    size_t degenerate_count = 0;
    for (int k = 0; k < 3; ++k) {
        lo[k] = clo[k] = INFINITY;
        hi[k] = chi[k] = -INFINITY;
    }
    for (size_t s = b; s < e; ++s) {
        const uint32_t i = order ? uint32_t(order[s]) : uint32_t(s);
        const float* p[3] = {vertex_of(V, nv, I, 3 * size_t(i)), vertex_of(V, nv, I, 3 * size_t(i) + 1),
                             vertex_of(V, nv, I, 3 * size_t(i) + 2)};
        Box bx;
        CompactTri c;
        c.code = 0;
        for (int a = 0; a < 3; ++a) {
            // Ties resolve to the lowest vertex index; min and max vertex differ even when
            // all three coordinates are equal, so the middle one is well defined.
            unsigned imin = 0, imax = 0;
            for (unsigned j = 1; j < 3; ++j) {
                if (p[j][a] < p[imin][a]) imin = j;
                if (p[j][a] > p[imax][a]) imax = j;
            }
            if (imin == imax) imax = (imin + 1) % 3;
            const unsigned imid = 3u - imin - imax;
            bx.lo[a] = p[imin][a];
            bx.hi[a] = p[imax][a];
            c.mid[a] = p[imid][a];
            c.code |= (imin | (imax << 2)) << (4 * a);
        }
        bx.lo[3] = bx.hi[3] = 0.0f;
        boxes[s] = bx;
        tris[s] = c;
        prim[s] = i;
        bad[s] = degenerate(p[0], p[1], p[2]);
        if (bad[s]) {
            ++degenerate_count;
            continue;
        }
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], bx.lo[a]);
            hi[a] = std::max(hi[a], bx.hi[a]);
            const float cen = centre(bx.lo[a], bx.hi[a]);
            clo[a] = std::min(clo[a], cen);
            chi[a] = std::max(chi[a], cen);
            abs_max = std::max(abs_max, std::max(std::fabs(bx.lo[a]), std::fabs(bx.hi[a])));
        }
    }
    for (int k = 0; k < 3; ++k) {
        part.bounds.lo[k] = lo[k];
        part.bounds.hi[k] = hi[k];
        part.centroid_bounds.lo[k] = clo[k];
        part.centroid_bounds.hi[k] = chi[k];
    }
    part.abs_max = abs_max;
    part.degenerate = degenerate_count;
}

}  // namespace

// Threaded: a 1M-triangle frame spent ~30 ms here on one core (an animation rebuilds it
// every frame). The Morton order adds ~10 ns per triangle (keys, a sort, and the build's
// reads of the caller's arrays in that order). Degenerate triangles keep their slots (they are never
// traced: valid_ids skips them).
TriangleSet::TriangleSet(const float* V, size_t num_vertices, const uint32_t* I, size_t M, bool spatial_order)
    : boxes(M), tris(M), prim(M) {
    BuiltArray<uint64_t> order(spatial_order ? M : 0);  // every element written by key_range
    if (spatial_order) {
        const Bounds3 vb = vertex_bounds(V, num_vertices);
        // Cells of ~32 triangles, at most 32^3: an order within a cell's few KB matters little
        // (its triangles share cache lines either way), and one counting pass then sorts.
        int k = 1;
        while (k < 5 && (size_t(1) << (3 * k)) * 32 < M) ++k;
        parallel_for(M, [&](size_t b, size_t e) { key_range(V, num_vertices, I, b, e, vb, k, order.data()); }, size_t(1) << 15);
        counting_sort(order, 3 * k);
    }

    const int T = threads_for(M, size_t(1) << 15);
    std::vector<Part> parts(static_cast<size_t>(T));
    BuiltArray<uint8_t> bad(M);  // every element written by build_range
    run_workers(T, [&](int w) {
        build_range(V, num_vertices, I, spatial_order ? order.data() : nullptr, M * size_t(w) / size_t(T),
                    M * size_t(w + 1) / size_t(T), boxes.data(), tris.data(), prim.data(), bad.data(),
                    parts[size_t(w)]);
    });
    for (int k = 0; k < 3; ++k) {
        bounds.lo[k] = centroid_bounds.lo[k] = INFINITY;
        bounds.hi[k] = centroid_bounds.hi[k] = -INFINITY;
    }
    for (const Part& part : parts) {
        num_degenerate += part.degenerate;
        abs_max = std::max(abs_max, part.abs_max);
        for (int a = 0; a < 3; ++a) {
            bounds.lo[a] = std::min(bounds.lo[a], part.bounds.lo[a]);
            bounds.hi[a] = std::max(bounds.hi[a], part.bounds.hi[a]);
            centroid_bounds.lo[a] = std::min(centroid_bounds.lo[a], part.centroid_bounds.lo[a]);
            centroid_bounds.hi[a] = std::max(centroid_bounds.hi[a], part.centroid_bounds.hi[a]);
        }
    }
    valid_ids.resize(M - num_degenerate + 1);  // + 1: the branch-free append writes one ahead
    uint32_t* out = valid_ids.data();
    for (size_t s = 0; s < M; ++s) {
        *out = uint32_t(s);
        out += !bad[s];
    }
    valid_ids.pop_back();
    const size_t nv = valid_ids.size(), samples = std::min<size_t>(nv, 1024);
    std::vector<float> extent(samples);
    for (size_t k = 0; k < samples; ++k) {
        const Box& bx = boxes[valid_ids[k * nv / samples]];
        extent[k] = std::max(bx.hi[0] - bx.lo[0], std::max(bx.hi[1] - bx.lo[1], bx.hi[2] - bx.lo[2]));
    }
    if (samples) {
        std::nth_element(extent.begin(), extent.begin() + samples / 4, extent.end());
        fine_extent = extent[samples / 4];
    }
}

// Two passes over the slots, the second gathering the records (threaded: a 1M-triangle frame's
// 52 MB). Bounds, extents and the degenerate count are those of the same set of triangles.
void TriangleSet::reorder(const uint32_t* order) {
    const size_t M = boxes.size(), nv = valid_ids.size();
    std::vector<uint32_t> from(M);
    std::vector<uint8_t> valid(M, 0);
    for (size_t i = 0; i < nv; ++i) {
        from[i] = order[i];
        valid[order[i]] = 1;
    }
    for (size_t s = 0, j = nv; s < M; ++s)
        if (!valid[s]) from[j++] = uint32_t(s);
    BuiltArray<Box> b(M);
    BuiltArray<CompactTri> t(M);
    BuiltArray<uint32_t> p(M);
    parallel_for(M, [&](size_t lo, size_t hi) {
        for (size_t i = lo; i < hi; ++i) {
            const uint32_t s = from[i];
            b[i] = boxes[s];
            t[i] = tris[s];
            p[i] = prim[s];
        }
    }, size_t(1) << 16);
    std::swap(boxes, b);
    std::swap(tris, t);
    std::swap(prim, p);
    for (size_t i = 0; i < nv; ++i) valid_ids[i] = uint32_t(i);  // in place: its size is read unlocked
}

}  // namespace dacrt
