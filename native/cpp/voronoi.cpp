// Cycles' Voronoi F1 (see voronoi.h): every operation in Cycles' order, in float32.
#include "voronoi.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>

#include "parallel.h"

namespace dacrt {

namespace {

// Cycles' PCG hashes (util/hash.h hash_pcg3d_i / hash_pcg2d_i: signed, wrapping; done in
// unsigned arithmetic, the same bits; >> on the signed value is arithmetic).
inline int32_t sra16(uint32_t v) { return int32_t(v) >> 16; }

inline void pcg3d(const int32_t k[3], float out[3]) {
    uint32_t x = uint32_t(k[0]) * 1664525u + 1013904223u;
    uint32_t y = uint32_t(k[1]) * 1664525u + 1013904223u;
    uint32_t z = uint32_t(k[2]) * 1664525u + 1013904223u;
    x += y * z;
    y += z * x;
    z += x * y;
    x ^= uint32_t(sra16(x));
    y ^= uint32_t(sra16(y));
    z ^= uint32_t(sra16(z));
    x += y * z;
    y += z * x;
    z += x * y;
    const float s = 1.0f / float(0x7FFFFFFFu);
    out[0] = float(int32_t(x & 0x7FFFFFFFu)) * s;
    out[1] = float(int32_t(y & 0x7FFFFFFFu)) * s;
    out[2] = float(int32_t(z & 0x7FFFFFFFu)) * s;
}

inline void pcg2d(const int32_t k[2], float out[2]) {
    uint32_t x = uint32_t(k[0]) * 1664525u + 1013904223u;
    uint32_t y = uint32_t(k[1]) * 1664525u + 1013904223u;
    x += y * 1664525u;
    y += x * 1664525u;
    x ^= uint32_t(sra16(x));
    y ^= uint32_t(sra16(y));
    x += y * 1664525u;
    y += x * 1664525u;
    const float s = 1.0f / float(0x7FFFFFFFu);
    out[0] = float(int32_t(x & 0x7FFFFFFFu)) * s;
    out[1] = float(int32_t(y & 0x7FFFFFFFu)) * s;
}

// voronoi_distance_bound (which point is nearest) and voronoi_distance (how far it is).
template <int D>
inline float bound(const float* a, const float* b, int metric) {
    float d[D];
    for (int c = 0; c < D; ++c) d[c] = a[c] - b[c];
    if (metric == VORONOI_EUCLIDEAN) {
        float s = d[0] * d[0];
        for (int c = 1; c < D; ++c) s = s + d[c] * d[c];
        return s;
    }
    float s = std::fabs(d[0]);
    for (int c = 1; c < D; ++c) s = metric == VORONOI_MANHATTAN ? s + std::fabs(d[c]) : std::max(s, std::fabs(d[c]));
    return s;
}

template <int D>
inline float distance(const float* a, const float* b, int metric) {
    const float s = bound<D>(a, b, metric);
    return metric == VORONOI_EUCLIDEAN ? std::sqrt(s) : s;
}

// An integer cell the way Cycles' make_int3(floor(x)) converts (0 beyond int's range).
inline int32_t cell_of(float f) { return std::fabs(f) < 2.1e9f ? int32_t(f) : 0; }

template <int D>
void f1_point(const float* p, float randomness, int metric, float* dist, float* col, float* pos) {
    float cellf[3] = {0, 0, 0}, local[3] = {0, 0, 0};
    int32_t cell[3] = {0, 0, 0};
    for (int c = 0; c < D; ++c) {
        cellf[c] = std::floor(p[c]);
        local[c] = p[c] - cellf[c];
        cell[c] = std::isfinite(cellf[c]) ? cell_of(cellf[c]) : 0;
    }
    float best = FLT_MAX, target[3] = {0, 0, 0};
    int32_t target_off[3] = {0, 0, 0};
    const int kz = D == 3 ? 1 : 0;
    for (int k = -kz; k <= kz; ++k)
        for (int j = -1; j <= 1; ++j)
            for (int i = -1; i <= 1; ++i) {
                const int32_t off[3] = {i, j, k};
                int32_t c[3];
                for (int a = 0; a < 3; ++a) c[a] = int32_t(uint32_t(cell[a]) + uint32_t(off[a]));
                float h[3];
                if (D == 3) pcg3d(c, h); else pcg2d(c, h);
                float point[3];
                for (int a = 0; a < D; ++a) point[a] = float(off[a]) + h[a] * randomness;
                const float d = bound<D>(point, local, metric);
                if (d < best) {
                    best = d;
                    for (int a = 0; a < 3; ++a) target_off[a] = off[a];
                    for (int a = 0; a < D; ++a) target[a] = point[a];
                }
            }
    *dist = distance<D>(target, local, metric);
    int32_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = int32_t(uint32_t(cell[a]) + uint32_t(target_off[a]));
    if (D == 2) c[2] = 0;           // hash_int2_to_float3: the cell with z 0
    pcg3d(c, col);
    for (int a = 0; a < 3; ++a) pos[a] = a < D ? target[a] + cellf[a] : 0.0f;
}

}  // namespace

void voronoi_f1(const float* p, size_t n, int dims, const float* randomness, size_t randomness_n, int metric,
                float* distance, float* color, float* position) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float r = std::min(std::max(randomness[randomness_n == 1 ? 0 : i], 0.0f), 1.0f);
            if (dims == 3)
                f1_point<3>(p + 3 * i, r, metric, distance + i, color + 3 * i, position + 3 * i);
            else
                f1_point<2>(p + 2 * i, r, metric, distance + i, color + 3 * i, position + 3 * i);
        }
    }, size_t(1) << 12);
}

}  // namespace dacrt
