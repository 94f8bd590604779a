// Next-event estimation on the shading side (see shading.h): MIS weights of light samples and
// the shadow rays that test them, fused so a light sample costs one pass instead of twenty.
#include <cmath>

#include "parallel.h"
#include "shading.h"

namespace dacrt {

void nee_weight(const float* ns, const float* ng, const float* wi, const float* pdf, const float* p_sel,
                const float* thr, float* value, size_t n, uint8_t* ok) {
    const float inv_pi = 0.3183098861837907f;
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float w0 = wi[i], w1 = wi[n + i], w2 = wi[2 * n + i];
            const float cos_s = ns[i] * w0 + ns[n + i] * w1 + ns[2 * n + i] * w2;
            // power heuristic w = 1 / (1 + (pdf_bsdf / (p_sel pdf_light))^2); delta lights: 1
            float r = cos_s * inv_pi;
            r /= p_sel[i] * pdf[i];
            r *= r;
            r += 1.0f;
            float scale = cos_s * inv_pi;
            scale /= r * p_sel[i];
            float m = -1.0f;
            for (int a = 0; a < 3; ++a) {
                float v = value[size_t(a) * n + i];
                if (thr) v *= thr[size_t(a) * n + i];
                v *= scale;
                value[size_t(a) * n + i] = v;
                m = std::fmax(m, v);  // fmax ignores NaN: a NaN channel alone never counts
            }
            bool good = cos_s > 0 && m > 0;
            if (ng) good = good && (ng[i] * w0 + ng[n + i] * w1 + ng[2 * n + i] * w2) > 0;
            ok[i] = good;
        }
    });
}

void shadow_rays(const float* O, const float* wi, const float* dist, const float* target, size_t n,
                 const int64_t* idx, size_t k, float shorten, Ray* out, uint8_t* valid) {
    parallel_for(k, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j) {
            const size_t i = size_t(idx[j]);
            Ray& r = out[j];
            float d[3], len;
            for (int a = 0; a < 3; ++a) r.org[a] = O[size_t(a) * n + i];
            if (target && !std::isnan(target[i])) {
                for (int a = 0; a < 3; ++a) d[a] = target[size_t(a) * n + i] - r.org[a];
                len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                const float inv = len > 0 ? 1.0f / len : 0.0f;
                for (int a = 0; a < 3; ++a) d[a] *= inv;
                len *= shorten;
            } else {
                for (int a = 0; a < 3; ++a) d[a] = wi[size_t(a) * n + i];
                len = dist[i];
            }
            const bool good = len > 0;
            for (int a = 0; a < 3; ++a) r.dir[a] = good ? d[a] : (a == 2 ? 1.0f : 0.0f);
            r.tfar = good ? len : 0.0f;
            r.id = uint32_t(j);
            valid[j] = good;
        }
    }, size_t(1) << 16);
}

void accumulate(float* L, size_t N, const int64_t* idx, const float* values, size_t k) {
    parallel_for(k, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j) {
            const size_t i = size_t(idx[j]);
            for (int a = 0; a < 3; ++a) L[size_t(a) * N + i] += values[size_t(a) * k + j];
        }
    }, size_t(1) << 17);
}

}  // namespace dacrt
