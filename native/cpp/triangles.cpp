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

// One thread's share of the build: its triangles' boxes and records, which of them are
// degenerate, and the bounds of its valid ones (min/max merge in any order to the same bits).
struct Part {
    Bounds3 bounds, centroid_bounds;
    float abs_max = 0.0f;
    size_t degenerate = 0;
};

void build_range(const float* V, const uint32_t* I, size_t b, size_t e, Box* boxes, CompactTri* tris,
                 uint8_t* bad, Part& part) {
    // Bounds in locals: through `part` every box store could alias them, which turned the
    // min/max updates into a chain of stores and reloads.
    float lo[3], hi[3], clo[3], chi[3], abs_max = 0.0f;
    size_t degenerate_count = 0;
    for (int k = 0; k < 3; ++k) {
        lo[k] = clo[k] = INFINITY;
        hi[k] = chi[k] = -INFINITY;
    }
    for (size_t i = b; i < e; ++i) {
        const float* p[3] = {V + 3 * size_t(I[3 * i]), V + 3 * size_t(I[3 * i + 1]), V + 3 * size_t(I[3 * i + 2])};
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
        boxes[i] = bx;
        tris[i] = c;
        bad[i] = degenerate(p[0], p[1], p[2]);
        if (bad[i]) {
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
// every frame).
TriangleSet::TriangleSet(const float* V, size_t num_vertices, const uint32_t* I, size_t M)
    : boxes(M), tris(M) {
    (void)num_vertices;
    const int T = threads_for(M, size_t(1) << 15);
    std::vector<Part> parts(static_cast<size_t>(T));
    BuiltArray<uint8_t> bad(M);  // every element written by build_range
    run_workers(T, [&](int w) {
        build_range(V, I, M * size_t(w) / size_t(T), M * size_t(w + 1) / size_t(T), boxes.data(), tris.data(),
                    bad.data(), parts[size_t(w)]);
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
    for (size_t i = 0; i < M; ++i) {
        *out = uint32_t(i);
        out += !bad[i];
    }
    valid_ids.pop_back();
}

}  // namespace dacrt
