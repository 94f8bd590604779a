// Ray records from structure-of-arrays columns, 8 at a time (see raylanes.h). One record at a
// time the compiler loads the 8 fields from 7 columns and stores them as 8 scalar stores (the
// bounce rays' records of a Cornell render: 7% of shade_bounce's perf samples, bound by those
// stores to lines not yet in cache); here each field's 8 floats are one load and each record
// one 32-byte store after an 8x8 transpose (unpacks and shuffles within 128-bit halves, then
// one cross-half permute per pair of records). Named copies per instruction set (as
// survivorlanes.cpp) so that DACRT_ISA picks the portable one and tests compare the copies;
// every copy moves the same floats, so every one gives the same bits.
#include "raylanes.h"

#include <immintrin.h>

#include "dispatch.h"
#include "pathvertex.h"

namespace dacrt {

namespace {

using LanesFn = void (*)(const float*, const float*, size_t, size_t, size_t, const float*, float, Ray*);

void portable_lanes(const float* O, const float* D, size_t n, size_t b, size_t e, const float* tfar, float tfar_all,
                    Ray* rays) {
    for (size_t i = b; i < e; ++i) {
        Ray r;
        ray_record(O, D, n, i, tfar ? tfar[i] : tfar_all, r);
        rays[i] = r;
    }
}

// Records i..i+7 from the field rows f[0..7] (org x y z, dir x y z, tfar, id as bits).
#define DACRT_RAY_STORE8(NAME, TARGET)                                                                               \
    TARGET inline void NAME##_store8(const __m256 f[8], Ray* out) {                                                  \
        __m256 s[8];                                                                                                 \
        for (int h = 0; h < 2; ++h) { /* fields 0-3, then 4-7: records j (low half) and j + 4 (high) */              \
            const __m256 t0 = _mm256_unpacklo_ps(f[4 * h], f[4 * h + 1]);                                            \
            const __m256 t1 = _mm256_unpackhi_ps(f[4 * h], f[4 * h + 1]);                                            \
            const __m256 t2 = _mm256_unpacklo_ps(f[4 * h + 2], f[4 * h + 3]);                                        \
            const __m256 t3 = _mm256_unpackhi_ps(f[4 * h + 2], f[4 * h + 3]);                                        \
            s[4 * h + 0] = _mm256_shuffle_ps(t0, t2, 0x44);                                                          \
            s[4 * h + 1] = _mm256_shuffle_ps(t0, t2, 0xEE);                                                          \
            s[4 * h + 2] = _mm256_shuffle_ps(t1, t3, 0x44);                                                          \
            s[4 * h + 3] = _mm256_shuffle_ps(t1, t3, 0xEE);                                                          \
        }                                                                                                            \
        float* o = reinterpret_cast<float*>(out);                                                                    \
        for (int j = 0; j < 4; ++j) {                                                                                \
            _mm256_storeu_ps(o + 8 * j, _mm256_permute2f128_ps(s[j], s[4 + j], 0x20));                               \
            _mm256_storeu_ps(o + 8 * (j + 4), _mm256_permute2f128_ps(s[j], s[4 + j], 0x31));                         \
        }                                                                                                            \
    }

#define DACRT_RAY_LANES(NAME, TARGET)                                                                                \
    DACRT_RAY_STORE8(NAME, TARGET)                                                                                   \
    TARGET void NAME##_lanes(const float* O, const float* D, size_t n, size_t b, size_t e, const float* tfar,        \
                             float tfar_all, Ray* rays) {                                                            \
        const __m256i step = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);                                              \
        const __m256 all = _mm256_set1_ps(tfar_all);                                                                 \
        size_t i = b;                                                                                                \
        for (; i + 8 <= e; i += 8) {                                                                                 \
            __m256 f[8];                                                                                             \
            for (size_t a = 0; a < 3; ++a) {                                                                         \
                f[a] = _mm256_loadu_ps(O + a * n + i);                                                               \
                f[3 + a] = _mm256_loadu_ps(D + a * n + i);                                                           \
            }                                                                                                        \
            f[6] = tfar ? _mm256_loadu_ps(tfar + i) : all;                                                           \
            f[7] = _mm256_castsi256_ps(_mm256_add_epi32(_mm256_set1_epi32(int32_t(uint32_t(i))), step));             \
            NAME##_store8(f, rays + i);                                                                              \
        }                                                                                                            \
        portable_lanes(O, D, n, i, e, tfar, tfar_all, rays);                                                         \
    }

DACRT_RAY_LANES(avx2, __attribute__((target("avx2"))))
DACRT_RAY_LANES(avx512, __attribute__((target("avx2,avx512f,avx512vl"))))

}  // namespace

void ray_records_lanes(const float* O, const float* D, size_t n, size_t b, size_t e, const float* tfar,
                       float tfar_all, Ray* rays) {
    static const LanesFn fn = lane_copy<LanesFn>(portable_lanes, avx2_lanes, avx512_lanes);
    fn(O, D, n, b, e, tfar, tfar_all, rays);
}

}  // namespace dacrt
