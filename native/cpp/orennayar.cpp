// Cycles' rough diffuse per point and per bounce (orennayar.h).
#include "orennayar.h"

#include <cstdint>

#include "parallel.h"

namespace dacrt {

void rough_rows(const float* params, size_t M, const int32_t* mat, const float* rho, const float* D, const float* ns,
                size_t n, float* out) {
    parallel_for(n, [&](size_t b0, size_t b1) {
        for (size_t i = b0; i < b1; ++i) {
            const size_t m = size_t(mat[i]);
            const float a = params[m], b = params[M + m], ebar = params[2 * M + m], eavg = params[3 * M + m];
            float nv = 0.0f;
            for (int c = 0; c < 3; ++c) {
                out[size_t(c) * n + i] = -D[size_t(c) * n + i];
                nv -= ns[size_t(c) * n + i] * D[size_t(c) * n + i];
            }
            out[3 * n + i] = a;
            out[4 * n + i] = b;
            const float ev = a * 3.14159265358979f + b * oren_nayar_G(std::fmax(nv, 0.0f));
            for (int c = 0; c < 3; ++c) {
                float k = 0.0f, inv_d = 0.0f;
                if (b > 0.0f) {
                    // pi Ems of Cycles' multiple scattering for the saturated colour
                    const float r = std::fmin(std::fmax(rho[size_t(c) * n + i], 0.0f), 1.0f);
                    const float ms = r * r * eavg / (1.0f - eavg) / (1.0f - r * (1.0f - eavg));
                    k = ms * (1.0f - ev);
                    inv_d = 1.0f / (ebar + ms * (1.0f - ebar) * (1.0f - ebar));
                }
                out[size_t(5 + c) * n + i] = k;
                out[size_t(8 + c) * n + i] = inv_d;
            }
        }
    }, 4096);
}

void rough_scale(const float* rows, const float* wi, const float* ns, size_t n, float* thr) {
    parallel_for(n, [&](size_t b0, size_t b1) {
        for (size_t i = b0; i < b1; ++i) {
            const float w[3] = {wi[i], wi[n + i], wi[2 * n + i]}, N[3] = {ns[i], ns[n + i], ns[2 * n + i]};
            float v[3] = {thr[i], thr[n + i], thr[2 * n + i]};
            rough_diffuse_scale(rows, n, i, N, w, v);
            for (int c = 0; c < 3; ++c) thr[size_t(c) * n + i] = v[c];
        }
    }, 4096);
}

}  // namespace dacrt
