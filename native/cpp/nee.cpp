// Next-event estimation on the shading side (see shading.h): MIS weights of light samples and
// the shadow rays that test them, fused so a light sample costs one pass instead of twenty.
#include <cmath>

#include "parallel.h"
#include "pathvertex.h"
#include "shading.h"

namespace dacrt {

void nee_weight(const float* ns, const float* ng, const float* wi, const float* pdf, const float* p_sel,
                const float* thr, float* value, size_t n, uint8_t* ok) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float s[3] = {ns[i], ns[n + i], ns[2 * n + i]};
            const float w[3] = {wi[i], wi[n + i], wi[2 * n + i]};
            float g[3], t[3], v[3];
            for (int a = 0; a < 3; ++a) {
                if (ng) g[a] = ng[size_t(a) * n + i];
                if (thr) t[a] = thr[size_t(a) * n + i];
                v[a] = value[size_t(a) * n + i];
            }
            ok[i] = nee_scale(s, ng ? g : nullptr, w, pdf[i], p_sel[i], thr ? t : nullptr, v);
            for (int a = 0; a < 3; ++a) value[size_t(a) * n + i] = v[a];
        }
    });
}

void shadow_rays(const float* O, const float* wi, const float* dist, const float* target, size_t n,
                 const int64_t* idx, size_t k, float shorten, Ray* out, uint8_t* valid) {
    parallel_for(k, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j) {
            const size_t i = index_at(idx, j, n);
            float o[3], w[3], t[3];
            for (int a = 0; a < 3; ++a) {
                o[a] = O[size_t(a) * n + i];
                w[a] = wi[size_t(a) * n + i];
                if (target) t[a] = target[size_t(a) * n + i];
            }
            valid[j] = shadow_record(o, w, dist[i], target ? t : nullptr, shorten, out[j]);
            out[j].id = uint32_t(j);
        }
    }, size_t(1) << 16);
}

}  // namespace dacrt
