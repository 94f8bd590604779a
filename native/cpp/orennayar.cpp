// Cycles' rough diffuse per point and per bounce (orennayar.h).
#include "orennayar.h"

#include <cstdint>

#include "parallel.h"

namespace dacrt {

void rough_rows(const float* params, size_t M, const int32_t* mat, const float* rho, const float* D, const float* ns,
                size_t n, float* out) {
    parallel_for(n, [&](size_t b0, size_t b1) {
        for (size_t i = b0; i < b1; ++i) {
            const float r[3] = {rho[i], rho[n + i], rho[2 * n + i]}, d[3] = {D[i], D[n + i], D[2 * n + i]},
                        N[3] = {ns[i], ns[n + i], ns[2 * n + i]};
            rough_row(params, M, size_t(mat[i]), r, d, N, out, n, i);
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
