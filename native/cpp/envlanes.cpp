// equirect_uv_lanes (envlanes.h), compiled per instruction set as named copies (as noise.cpp)
// so that DACRT_ISA can pick a narrower one and tests compare them on one machine. Compiled
// with -fno-trapping-math (CMakeLists.txt) so equirect.h's selects vectorise; -ffp-contract=off:
// every copy gives the scalar bits.
#include "envlanes.h"

#include <strings.h>

#include <cstdlib>

#include "dispatch.h"
#include "equirect.h"

namespace dacrt {

namespace {

using UvFn = void (*)(const float*, const float*, const float*, const float*, size_t, float*, float*, float*);

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
    }

DACRT_EQUIRECT_ISA(portable, )
DACRT_EQUIRECT_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_EQUIRECT_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

// The widest the CPU runs, or a narrower one DACRT_ISA names (a wider one it lacks: the widest).
UvFn pick_uv() {
    const Isa best = resolve_isa("");
    const char* env = std::getenv("DACRT_ISA");
    Isa isa = best;
    if (env && strcasecmp(env, "portable") == 0) isa = Isa::Portable;
    if (env && strcasecmp(env, "avx2") == 0 && best != Isa::Portable) isa = Isa::Avx2;
    return isa == Isa::Avx512 ? avx512_uv : (isa == Isa::Avx2 ? avx2_uv : portable_uv);
}

}  // namespace

void equirect_uv_lanes(const float to_map[9], const float* dx, const float* dy, const float* dz, size_t m, float* u,
                       float* v, float* sin_theta) {
    static const UvFn fn = pick_uv();
    fn(to_map, dx, dy, dz, m, u, v, sin_theta);
}

}  // namespace dacrt
