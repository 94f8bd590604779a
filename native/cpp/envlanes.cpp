// equirect_uv_lanes, equirect_dir_lanes, env_place_lanes and env_cell_lanes (envlanes.h), compiled per
// instruction set as named copies (as noise.cpp) so that DACRT_ISA can pick a narrower one
// (dispatch.h lane_copy) and tests compare them on one machine. Compiled
// with -fno-trapping-math (CMakeLists.txt) so equirect.h's selects vectorise; -ffp-contract=off:
// every copy gives the scalar bits.
#include "envlanes.h"


#include <cmath>

#include "dispatch.h"
#include "envcell.h"
#include "equirect.h"

namespace dacrt {

namespace {

using UvFn = void (*)(const float*, const float*, const float*, const float*, size_t, float*, float*, float*);
using DirFn = void (*)(const float*, const float*, const float*, size_t, float*, float*, float*, float*);
using PlaceFn = void (*)(bool, float, float, const EnvPicks&, size_t, float*, float*);
using CellFn = void (*)(uint32_t, uint32_t, const float*, const float*, const float*, size_t, EnvCells&);

#define DACRT_EQUIRECT_ISA(NAME, TARGET)                                                                     \
    TARGET void NAME##_uv(const float* __restrict M, const float* __restrict dx, const float* __restrict dy,  \
                          const float* __restrict dz, size_t m, float* __restrict u, float* __restrict v,     \
                          float* __restrict sin_theta) {                                                      \
        for (size_t j = 0; j < m; ++j) {                                                                      \
            const float mx = M[0] * dx[j] + M[1] * dy[j] + M[2] * dz[j];                                      \
            const float my = M[3] * dx[j] + M[4] * dy[j] + M[5] * dz[j];                                      \
            const float mz = M[6] * dx[j] + M[7] * dy[j] + M[8] * dz[j];                                      \
            float s;                                                                                          \
            equirect::to_uv(mx, my, mz, u[j], v[j], s);                                                       \
            const float len2 = mx * mx + my * my + mz * mz;                                                   \
            sin_theta[j] = len2 > 0.0f ? s : -1.0f; /* (NaN: -1, no direction) */                            \
        }                                                                                                     \
    }                                                                                                         \
    TARGET void NAME##_dir(const float* __restrict M, const float* __restrict u, const float* __restrict v,    \
                           size_t m, float* __restrict wx, float* __restrict wy, float* __restrict wz,        \
                           float* __restrict sin_theta) {                                                     \
        for (size_t j = 0; j < m; ++j) {                                                                      \
            float d[3];                                                                                       \
            equirect::from_uv(u[j], v[j], d, sin_theta[j]);                                                   \
            wx[j] = M[0] * d[0] + M[3] * d[1] + M[6] * d[2]; /* orthogonal: the inverse is the transpose */    \
            wy[j] = M[1] * d[0] + M[4] * d[1] + M[7] * d[2];                                                  \
            wz[j] = M[2] * d[0] + M[5] * d[1] + M[8] * d[2];                                                  \
        }                                                                                                     \
    }                                                                                                         \
    TARGET void NAME##_place(bool closest, float fw, float fh, const EnvPicks& p, size_t m,                \
                             float* __restrict u, float* __restrict v) {                                      \
        float fu[kEnvLanes], fv[kEnvLanes];                                                                   \
        for (size_t k = 0; k < m; ++k) {                                                                      \
            fv[k] = envcell::row_fraction(p.u1[k], p.r0[k], p.r1[k]);                                         \
            fu[k] = envcell::column_fraction(p.u2[k], p.c0[k], p.c1[k]);                                      \
        }                                                                                                     \
        if (closest) {                                                                                        \
            for (size_t k = 0; k < m; ++k)                                                                    \
                envcell::closest_place(fu[k], fv[k], p.fj[k], p.fi[k], fw, fh, u[k], v[k]);                  \
        } else {                                                                                              \
            for (size_t k = 0; k < m; ++k)                                                                    \
                envcell::linear_place(fu[k], fv[k], p.a[k], p.b[k], p.c[k], p.d[k], p.fj[k], p.fi[k], fw, fh, u[k], \
                                      v[k]);                                                                  \
        }                                                                                                     \
    }                                                                                                         \
    TARGET void NAME##_cells(uint32_t w, uint32_t h, const float* __restrict u, const float* __restrict v,    \
                             const float* __restrict s, size_t m, EnvCells& c) {                              \
        const float fw = float(w), fh = float(h);                                                             \
        const int32_t iw = int32_t(w), ih = int32_t(h);                                                       \
        for (size_t k = 0; k < m; ++k) {                                                                      \
            const float x = u[k] * fw - 0.5f, y = v[k] * fh - 0.5f;                                           \
            const float x0 = std::floor(x), y0 = std::floor(y);                                               \
            c.fx[k] = x - x0, c.fy[k] = y - y0;                                                               \
            /* u, v in [0, 1]: x0 in [-1, w - 1], y0 in [-1, h - 1], one step of wrap (NaN: not ok) */         \
            const bool in = s[k] >= 0.0f && x0 >= -1.0f && x0 <= fw - 1.0f && y0 >= -1.0f && y0 <= fh - 1.0f;  \
            const int32_t j = in ? int32_t(x0) : 0, i = in ? int32_t(y0) : 0;                                 \
            c.j0[k] = uint32_t(j < 0 ? j + iw : j), c.j1[k] = uint32_t(j + 1 == iw ? 0 : j + 1);              \
            c.i0[k] = uint32_t(i < 0 ? i + ih : i), c.i1[k] = uint32_t(i + 1 == ih ? 0 : i + 1);              \
            c.ok[k] = in;                                                                                     \
        }                                                                                                     \
    }

DACRT_EQUIRECT_ISA(portable, )
DACRT_EQUIRECT_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_EQUIRECT_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

}  // namespace

void equirect_uv_lanes(const float to_map[9], const float* dx, const float* dy, const float* dz, size_t m, float* u,
                       float* v, float* sin_theta) {
    static const UvFn fn = lane_copy<UvFn>(portable_uv, avx2_uv, avx512_uv);
    fn(to_map, dx, dy, dz, m, u, v, sin_theta);
}

void equirect_dir_lanes(const float to_map[9], const float* u, const float* v, size_t m, float* wx, float* wy,
                        float* wz, float* sin_theta) {
    static const DirFn fn = lane_copy<DirFn>(portable_dir, avx2_dir, avx512_dir);
    fn(to_map, u, v, m, wx, wy, wz, sin_theta);
}

void env_place_lanes(bool closest, float fw, float fh, const EnvPicks& in, size_t m, float* u, float* v) {
    static const PlaceFn fn = lane_copy<PlaceFn>(portable_place, avx2_place, avx512_place);
    fn(closest, fw, fh, in, m, u, v);
}

void env_cell_lanes(uint32_t w, uint32_t h, const float* u, const float* v, const float* s, size_t m, EnvCells& c) {
    static const CellFn fn = lane_copy<CellFn>(portable_cells, avx2_cells, avx512_cells);
    fn(w, h, u, v, s, m, c);
}

}  // namespace dacrt
