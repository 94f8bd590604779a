// Diffuse (Lambertian) bounce directions and the renderer's random numbers (see shading.h).
#include <algorithm>
#include <cmath>

#include "parallel.h"
#include "random.h"
#include "shading.h"

namespace dacrt {

namespace {

constexpr size_t kChunk = 512;   // words per stack buffer: vector-friendly, stays in L1
constexpr float kInv24 = 1.0f / float(1 << 24);

// body(i0, count, a, b) for consecutive chunks of [begin, end) with their sample words.
template <class F>
void for_words(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, size_t begin, size_t end, F&& body) {
    uint32_t a[kChunk], b[kChunk];
    for (size_t i0 = begin; i0 < end; i0 += kChunk) {
        const size_t m = std::min(kChunk, end - i0);
        sample_words(keys + i0, keys + n + i0, m, ka, kb, a, b);
        body(i0, m, a, b);
    }
}

}  // namespace

void uniform2_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, float* u1, float* u2) {
    parallel_for(n, [&](size_t begin, size_t end) {
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* a, const uint32_t* b) {
            for (size_t j = 0; j < m; ++j) {
                u1[i0 + j] = float(a[j] >> 8) * kInv24;
                u2[i0 + j] = float(b[j] >> 8) * kInv24;
            }
        });
    }, size_t(1) << 16);
}

void uniform_pick_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, double* pick, float* u) {
    parallel_for(n, [&](size_t begin, size_t end) {
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* a, const uint32_t* b) {
            for (size_t j = 0; j < m; ++j) {
                pick[i0 + j] = double(a[j]) * (1.0 / 4294967296.0);
                u[i0 + j] = float(b[j] >> 8) * kInv24;
            }
        });
    }, size_t(1) << 16);
}

namespace {

// sin and cos of 2 pi u for u in [0, 1): quadrant by the top bits, Taylor polynomials on
// [0, pi/2] (truncation < 6e-8). Branch-free and in plain IEEE operations, so the per-ISA clones
// below vectorise it and agree bit for bit (libm's sinf/cosf are scalar calls).
inline void sincos_turn(float u, float& s, float& c) {
    const float q4 = u * 4.0f;
    const int q = int(q4);
    const float x = (q4 - float(q)) * 1.5707963267948966f, x2 = x * x;
    const float sn = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880 +
                     x2 * (-1.0f / 39916800))))));
    const float cs = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 + x2 * (
                     -1.0f / 3628800 + x2 * (1.0f / 479001600))))));
    // rotate by q quarter turns: (s, c) = (sn, cs), (cs, -sn), (-sn, -cs), (-cs, sn)
    const bool swap = q & 1, neg_s = q & 2, neg_c = (q + 1) & 2;
    s = swap ? cs : sn;
    c = swap ? sn : cs;
    s = neg_s ? -s : s;
    c = neg_c ? -c : c;
}

// Malley's method (uniform disk point lifted to the hemisphere) around the shading normals,
// for one chunk of sample words.
__attribute__((target_clones("avx512f", "avx2", "default")))
void scatter_chunk(const uint32_t* __restrict wa, const uint32_t* __restrict wb, size_t m,
                   const float* __restrict nx_, const float* __restrict ny_, const float* __restrict nz_,
                   float* __restrict wx, float* __restrict wy, float* __restrict wz, float* __restrict pdf) {
    const float inv_pi = 0.3183098861837907f;
    for (size_t j = 0; j < m; ++j) {
        const float u1 = float(wa[j] >> 8) * kInv24, u2 = float(wb[j] >> 8) * kInv24;
        float sp, cp;
        sincos_turn(u2, sp, cp);
        const float rad = std::sqrt(u1);
        const float lx = rad * cp, ly = rad * sp;
        const float lz = std::sqrt(std::max(1.0f - u1, 0.0f));
        // branchless orthonormal basis around the shading normal (Duff et al. 2017)
        const float nx = nx_[j], ny = ny_[j], nz = nz_[j];
        const float sign = nz >= 0 ? 1.0f : -1.0f;
        const float a = -1.0f / (sign + nz);
        const float bb = nx * ny * a;
        const float t0 = 1.0f + sign * nx * a * nx, t1 = sign * bb, t2 = -sign * nx;
        const float b0 = bb, b1 = sign + ny * ny * a, b2 = -ny;
        wx[j] = t0 * lx + b0 * ly + nx * lz;
        wy[j] = t1 * lx + b1 * ly + ny * lz;
        wz[j] = t2 * lx + b2 * ly + nz * lz;
        pdf[j] = lz * inv_pi;
    }
}

}  // namespace

void cosine_scatter(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                    float* wi, float* pdf, uint8_t* ok) {
    parallel_for(n, [&](size_t begin, size_t end) {
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* wa, const uint32_t* wb) {
            scatter_chunk(wa, wb, m, ns + i0, ns + n + i0, ns + 2 * n + i0, wi + i0, wi + n + i0, wi + 2 * n + i0,
                          pdf + i0);
            for (size_t i = i0; i < i0 + m; ++i) {
                bool good = pdf[i] > 0;          // grazing: cos = 0
                if (ng) good = good && (wi[i] * ng[i] + wi[n + i] * ng[n + i] + wi[2 * n + i] * ng[2 * n + i]) > 0;
                ok[i] = good;
            }
        });
    }, size_t(1) << 15);
}

}  // namespace dacrt
