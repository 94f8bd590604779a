// Light samples on emissive triangles (see shading.h): the same arithmetic, in the same order,
// as the numpy code it replaces (addon/lights/triangles.py), without gathering 15 rows per ray.
#include <algorithm>
#include <atomic>
#include <cmath>

#include "parallel.h"
#include "shading.h"

namespace dacrt {

size_t sample_triangles(const float* geo, const float* area, size_t M, const int64_t* which, const float* P,
                        const float* u1, const float* u2, size_t n, float* wi, float* dist, float* pdf,
                        float* target) {
    std::atomic<size_t> bad{0};
    parallel_for(n, [&](size_t b, size_t e) {
        size_t local_bad = 0;
        for (size_t i = b; i < e; ++i) {
            const int64_t w = which[i];
            if (w < 0 || size_t(w) >= M) {
                ++local_bad;
                continue;
            }
            auto g = [&](int row) { return geo[size_t(row) * M + size_t(w)]; };
            // uniform point by area: barycentrics (u2 sqrt(u1), 1 - sqrt(u1)) of vertices 1, 2
            const float su = std::sqrt(u1[i]);
            const float b1 = u2[i] * su, b2 = 1.0f - su;
            float q[3], d[3];
            for (int a = 0; a < 3; ++a) {
                float x = g(3 + a) * b1;
                x += g(6 + a) * b2;
                x += g(a);
                q[a] = x;
                d[a] = x - P[size_t(a) * n + i];
            }
            const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const float inv = len > 0 ? 1.0f / len : 0.0f;
            for (int a = 0; a < 3; ++a) d[a] *= inv;
            float cos_l = g(9) * d[0] + g(10) * d[1] + g(11) * d[2];
            const float side = cos_l <= 0 ? 1.0f : -1.0f;  // the emitter face that sees P
            cos_l = std::fabs(cos_l);
            const bool ok = cos_l > 0 && len > 0;
            const float p = ok ? len * len / (area[w] * cos_l) : 0.0f;
            // The shadow ray must end in front of the emitter by more than where its end can
            // drift: a few ULPs of its origin's coordinates and of its length, which can exceed
            // the emitter's own step (a small emitter seen from afar). 8 ULPs of the larger.
            float big = len;
            for (int a = 0; a < 3; ++a) big = std::max(big, std::fabs(P[size_t(a) * n + i]));
            const float own = std::sqrt(g(12) * g(12) + g(13) * g(13) + g(14) * g(14));
            const float reach = 8.0f * ulp_of(std::max(big, 0x1p-100f));
            const float scale = own >= reach || !(own > 0) ? side : side * (reach / own);
            for (int a = 0; a < 3; ++a) {
                wi[size_t(a) * n + i] = d[a];
                target[size_t(a) * n + i] = q[a] + g(12 + a) * scale;
            }
            dist[i] = len;
            pdf[i] = std::isfinite(p) ? p : 0.0f;
        }
        if (local_bad) bad += local_bad;
    });
    return bad.load();
}

size_t gather_emission(const Hit* hits, const uint8_t* hit, size_t n, const float* emission, const uint8_t* emissive,
                       const float* tri_prob, const float* area, const float* geo, size_t M, const float* D,
                       const float* thr, const float* pdf, const int64_t* pid, float* L, size_t N) {
    std::atomic<size_t> count{0};
    parallel_for(n, [&](size_t b, size_t e) {
        size_t local = 0;
        for (size_t i = b; i < e; ++i) {
            const int32_t p = hits[i].prim;
            if (!hit[i] || p < 0 || size_t(p) >= M || !emissive[p]) continue;
            const size_t q = size_t(p);
            float w = 1.0f;
            if (tri_prob && tri_prob[q] > 0) {  // a BSDF ray: power heuristic against light sampling
                const float cos_l = std::fabs(geo[9 * M + q] * D[i] + geo[10 * M + q] * D[n + i] +
                                              geo[11 * M + q] * D[2 * n + i]);
                const float t = hits[i].t;
                float r = tri_prob[q] * t * t / (area[q] * cos_l);
                r /= pdf[i];
                r *= r;
                r += 1.0f;
                w = 1.0f / r;
            }
            const size_t j = size_t(pid[i]);
            for (int a = 0; a < 3; ++a) {
                float v = emission[size_t(a) * M + q];
                if (thr) v *= thr[size_t(a) * n + i];
                L[size_t(a) * N + j] += v * w;
            }
            ++local;
        }
        count += local;
    });
    return count.load();
}

}  // namespace dacrt
