// Diffuse (Lambertian) bounce directions and the renderer's random numbers (see shading.h).
#include <cmath>

#include "parallel.h"
#include "random.h"
#include "shading.h"

namespace dacrt {

void uniform2_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, float* u1, float* u2) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            Uniform2 r = uniform2(keys[i], keys[n + i], ka, kb);
            u1[i] = r.u1;
            u2[i] = r.u2;
        }
    }, size_t(1) << 16);
}

void uniform_pick_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, double* pick, float* u) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const Words w = mix_words(keys[i], keys[n + i], ka, kb);
            pick[i] = double(w.a) * (1.0 / 4294967296.0);
            u[i] = float(w.b >> 8) * (1.0f / float(1 << 24));
        }
    }, size_t(1) << 16);
}

void cosine_scatter(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                    float* wi, float* pdf, uint8_t* ok) {
    const float two_pi = 6.283185307179586f, inv_pi = 0.3183098861837907f;
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            Uniform2 r = uniform2(keys[i], keys[n + i], ka, kb);
            // Malley: uniform disk point lifted to the hemisphere (polar map)
            const float rad = std::sqrt(r.u1), phi = two_pi * r.u2;
            const float lx = rad * std::cos(phi), ly = rad * std::sin(phi);
            const float lz = std::sqrt(std::max(1.0f - r.u1, 0.0f));
            // branchless orthonormal basis around the shading normal (Duff et al. 2017)
            const float nx = ns[i], ny = ns[n + i], nz = ns[2 * n + i];
            const float sign = nz >= 0 ? 1.0f : -1.0f;
            const float a = -1.0f / (sign + nz);
            const float bb = nx * ny * a;
            const float t0 = 1.0f + sign * nx * a * nx, t1 = sign * bb, t2 = -sign * nx;
            const float b0 = bb, b1 = sign + ny * ny * a, b2 = -ny;
            const float w0 = t0 * lx + b0 * ly + nx * lz;
            const float w1 = t1 * lx + b1 * ly + ny * lz;
            const float w2 = t2 * lx + b2 * ly + nz * lz;
            wi[i] = w0;
            wi[n + i] = w1;
            wi[2 * n + i] = w2;
            pdf[i] = lz * inv_pi;
            bool good = lz > 0;
            if (ng) good = good && (w0 * ng[i] + w1 * ng[n + i] + w2 * ng[2 * n + i]) > 0;
            ok[i] = good;
        }
    }, size_t(1) << 15);
}

}  // namespace dacrt
