// Builds the per-frame triangle arrays (see triangles.h).
#include "triangles.h"

#include <algorithm>
#include <cmath>

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

TriangleSet::TriangleSet(const float* V, size_t num_vertices, const uint32_t* I, size_t M)
    : boxes(M), tris(M) {
    (void)num_vertices;
    valid_ids.reserve(M);
    for (int k = 0; k < 3; ++k) {
        bounds.lo[k] = centroid_bounds.lo[k] = INFINITY;
        bounds.hi[k] = centroid_bounds.hi[k] = -INFINITY;
    }
    for (size_t i = 0; i < M; ++i) {
        const float* p[3] = {V + 3 * size_t(I[3 * i]), V + 3 * size_t(I[3 * i + 1]),
                             V + 3 * size_t(I[3 * i + 2])};
        Box& b = boxes[i];
        CompactTri& c = tris[i];
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
            b.lo[a] = p[imin][a];
            b.hi[a] = p[imax][a];
            c.mid[a] = p[imid][a];
            c.code |= (imin | (imax << 2)) << (4 * a);
        }
        b.lo[3] = b.hi[3] = 0.0f;
        if (degenerate(p[0], p[1], p[2])) {
            ++num_degenerate;
            continue;
        }
        valid_ids.push_back(uint32_t(i));
        for (int a = 0; a < 3; ++a) {
            bounds.lo[a] = std::min(bounds.lo[a], b.lo[a]);
            bounds.hi[a] = std::max(bounds.hi[a], b.hi[a]);
            const float cen = centre(b.lo[a], b.hi[a]);
            centroid_bounds.lo[a] = std::min(centroid_bounds.lo[a], cen);
            centroid_bounds.hi[a] = std::max(centroid_bounds.hi[a], cen);
            abs_max = std::max(abs_max, std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a])));
        }
    }
}

}  // namespace dacrt
