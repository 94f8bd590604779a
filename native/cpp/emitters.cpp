// Emissive triangles as lights (see shading.h): light samples from shading points, and the
// emission BSDF rays meet, weighted by MIS with the pdf the light sample would have had
// (trianglelight.h holds both).
#include <algorithm>
#include <atomic>
#include <cmath>

#include "parallel.h"
#include "shading.h"
#include "trianglelight.h"

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
            const float p[3] = {P[i], P[n + i], P[2 * n + i]};
            float d[3], q[3];
            triangle_light(geo, area, M, size_t(w), p, u1[i], u2[i], d, dist[i], pdf[i], q);
            for (int a = 0; a < 3; ++a) {
                wi[size_t(a) * n + i] = d[a];
                target[size_t(a) * n + i] = q[a];
            }
        }
        if (local_bad) bad += local_bad;
    });
    return bad.load();
}

size_t gather_emission(const Hit* hits, const uint8_t* hit, size_t n, const float* emission, const uint8_t* emissive,
                       const float* tri_prob, const float* area, const float* geo, size_t M, const float* O,
                       const float* D, const float* thr, const float* pdf, const int64_t* pid, float* L, size_t N, float clamp,
                       const LightTree* tree, const int32_t* tri_key, const float* normal,
                       const uint64_t* receivers) {
    std::atomic<size_t> count{0};
    parallel_for(n, [&](size_t b, size_t e) {
        size_t local = 0;
        for (size_t i = b; i < e; ++i) {
            const int32_t p = __atomic_load_n(&hits[i].prim, __ATOMIC_RELAXED);
            // (hit null: every ray, a missed one, prim < 0, left out as by the flags)
            if ((hit && !hit[i]) || p < 0 || size_t(p) >= M || !emissive[p]) continue;
            const size_t q = size_t(p);
            float w = 1.0f;
            if (tri_prob && tri_prob[q] > 0) {  // a BSDF ray: power heuristic against light sampling
                const float o[3] = {O[i], O[n + i], O[2 * n + i]}, d[3] = {D[i], D[n + i], D[2 * n + i]};
                float p_sel = tri_prob[q];
                if (tree && tri_key && tri_key[q] >= 0)  // as picked from o with the vertex's normal
                    p_sel = float(double(p_sel) * tree->pdf(o, normal, n, i, tri_key[q],
                                                            receivers ? receivers[i] : LightTree::kAllSets));
                float r = p_sel * triangle_light_pdf(geo, area, M, q, o, d, hits[i].t);
                r /= pdf[i];
                r *= r;
                r += 1.0f;
                w = 1.0f / r;
            }
            const size_t j = index_at(pid, i, N);
            float v[3];
            for (int a = 0; a < 3; ++a) {
                v[a] = emission[size_t(a) * M + q];
                if (thr) v[a] *= thr[size_t(a) * n + i];
                v[a] *= w;
            }
            clamp_light(v, clamp);
            for (int a = 0; a < 3; ++a) L[size_t(a) * N + j] += v[a];
            ++local;
        }
        count += local;
    });
    return count.load();
}

}  // namespace dacrt
