// Diffuse (Lambertian) bounce directions and the renderer's random numbers (see shading.h).
#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.h"
#include "pathvertex.h"
#include "random.h"
#include "raylanes.h"
#include "scatterlanes.h"
#include "shading.h"

namespace dacrt {

// Split from 2^14 paths: a render's later bounces hold 10^4..10^5 paths, which from 2^16 per
// thread (as it was) ran on the calling thread alone (Cornell 256 spp: uniform_pick 0.013 s CPU,
// 80% of it on one thread).
constexpr size_t kUniformSplit = size_t(1) << 14;

void uniform2_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, float* u1, float* u2) {
    parallel_for(n, [&](size_t begin, size_t end) {
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* a, const uint32_t* b) {
            for (size_t j = 0; j < m; ++j) {
                u1[i0 + j] = unit24(a[j]);
                u2[i0 + j] = unit24(b[j]);
            }
        });
    }, kUniformSplit);
}

void uniform_pick_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, double* pick, float* u) {
    parallel_for(n, [&](size_t begin, size_t end) {
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* a, const uint32_t* b) {
            for (size_t j = 0; j < m; ++j) {
                pick[i0 + j] = double(a[j]) * (1.0 / 4294967296.0);
                u[i0 + j] = unit24(b[j]);
            }
        });
    }, kUniformSplit);
}

void scatter_range(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                   float* wi, float* pdf, uint8_t* ok, const float* O, Ray* rays, const ShadingOffset* offset,
                   size_t begin, size_t end) {
    for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* wa, const uint32_t* wb) {
        scatter_lanes(wa, wb, m, ns + i0, ns + n + i0, ns + 2 * n + i0, ng ? ng + i0 : nullptr,
                      ng ? ng + n + i0 : nullptr, ng ? ng + 2 * n + i0 : nullptr, wi + i0, wi + n + i0,
                      wi + 2 * n + i0, pdf + i0, ok + i0);
        if (offset)
            for (size_t i = i0; i < i0 + m; ++i)
                if (ok[i]) {
                    const float f = offset->freq[index_at(offset->prim, i, offset->M)];
                    const float c = ns[i] * wi[i] + ns[n + i] * wi[n + i] + ns[2 * n + i] * wi[2 * n + i];
                    if (f > 1.0f) {
                        const float s = c > 0 ? shift_cos_in(c, f) : 0.0f;
                        for (int a = 0; a < 3; ++a) offset->thr[size_t(a) * n + i] *= s;
                    }
                }
        if (rays)  // the bounce rays' records, ready for the tracer
            ray_records_lanes(O, wi, n, i0, i0 + m, nullptr, std::numeric_limits<float>::infinity(), rays);
    });
}

void cosine_scatter(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                    float* wi, float* pdf, uint8_t* ok, const float* O, Ray* rays, const ShadingOffset* offset) {
    parallel_for(n, [&](size_t begin, size_t end) {
        scatter_range(keys, n, ka, kb, ns, ng, wi, pdf, ok, O, rays, offset, begin, end);
    }, size_t(1) << 15);
}

}  // namespace dacrt
