// survivor_range (survival.cpp) on kSurvivorLanes survivors at a time, from the hit-point
// records: each step of surface_point_of (pathvertex.h) and of the throughput runs as a loop
// over lanes with its branches as selects, so the compiler keeps the lanes in vector registers
// (one survivor at a time the record arithmetic is a chain of dependent scalar operations with
// branches on the step's cut and the flip between them). Only inside_edges' rare move toward
// the triangle's middle (move_inside) runs per lane, for the lanes that need it. Per lane the
// operations and their order are the scalar code's (-ffp-contract=off), so every instruction
// set gives its bits; compiled per instruction set as named copies (as noise.cpp) so that
// DACRT_ISA can pick a narrower one and tests compare them on one machine, and with
// -fno-trapping-math (CMakeLists.txt) so the selects after a division vectorise.
#include "survivorlanes.h"

#include <cmath>
#include <cstring>

#include "dispatch.h"
#include "hitrecords.h"
#include "pathvertex.h"
#include "shading.h"

namespace dacrt {

namespace {

constexpr size_t K = kSurvivorLanes;

inline float vmax(float a, float b) { return a < b ? b : a; }  // std::max(a, b), NaN included
inline float vmin(float a, float b) { return b < a ? b : a; }  // std::min(a, b)

using LanesFn = size_t (*)(const Hit*, size_t, const float*, size_t, const float*, bool, const int64_t*, size_t,
                           float*, const float*, bool, const float*, float*, int32_t*, size_t, size_t);

// One group of K survivors from j0 (survivor_range's loop body, lane by lane).
[[gnu::always_inline]] inline void group(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr,
                                         bool roulette, const int64_t* idx, size_t k, float* thr_out,
                                         const float* records, bool smooth, const float* D, float* surf_out,
                                         int32_t* prim_out, size_t j0) {
    size_t ii[K];
    uint32_t p[K];  // (32-bit: the records' gathers below take 32-bit indices)
    float u[K], v[K], t[K];
    for (size_t l = 0; l < K; ++l) {
        const size_t i = size_t(idx[j0 + l]);
        const Hit& h = hits[i];
        ii[l] = i;
        p[l] = uint32_t(prim_at(h, M));  // survivors have 0 <= prim < M (survivors' pass), the clamp as the scalar code
        u[l] = h.u;
        v[l] = h.v;
        t[l] = h.t;
    }
    // throughput: albedo x thr / q (survival(): q = min(sqrt(largest channel), 1))
    float inv_q[K];
    for (size_t l = 0; l < K; ++l) {
        const size_t i = ii[l];
        float q = 1.0f;
        if (roulette) {
            const float m = thr ? vmax(vmax(thr[i], thr[n + i]), thr[2 * n + i]) : 1.0f;
            q = vmin(__builtin_sqrtf(m), 1.0f);   // (not std::sqrt: LTO kept it out of line, one lane at a time)
        }
        inv_q[l] = q > 0 ? 1.0f / q : 1.0f;
    }
    for (size_t a = 0; a < 3; ++a)
        for (size_t l = 0; l < K; ++l) {
            float tt = thr ? thr[a * n + ii[l]] : 1.0f;
            if (roulette) tt = tt * inv_q[l];
            thr_out[a * k + j0 + l] = albedo[a * M + p[l]] * tt;
        }
    // the records' rows 0-21 (table and shape), a row of all lanes at a time (a gather)
    float R[kRecordNormals][K], d[3][K];
    for (size_t row = 0; row < kRecordNormals; ++row)
        for (size_t l = 0; l < K; ++l) R[row][l] = records[kHitRecord * p[l] + row];
    for (size_t a = 0; a < 3; ++a)
        for (size_t l = 0; l < K; ++l) d[a][l] = D[a * n + ii[l]];
    // inside_edges: the common test in lanes, the rare move per lane
    const float* margin = R[kRecordShape];
    const float* area2 = R[kRecordShape + 1];
    int32_t move[K];  // (int lanes, no early exit: the test vectorises)
    for (size_t l = 0; l < K; ++l) {
        const bool ok = (area2[l] > 0) & (margin[l] > 0) & (area2[l] < kFloatMax);
        const float w[3] = {1.0f - u[l] - v[l], u[l], v[l]};
        bool inside = true;
        for (size_t c = 0; c < 3; ++c) {
            const float wa = w[c] * area2[l];
            inside = inside & (wa >= 0) & (wa * wa >= margin[l] * margin[l] * R[kRecordShape + 2 + c][l]);
        }
        move[l] = ok & !inside;
    }
    int32_t any = 0;
    for (size_t l = 0; l < K; ++l) any |= move[l];
    if (any)
        for (size_t l = 0; l < K; ++l)
            if (move[l]) {
                TriangleShape sh;
                std::memcpy(&sh, records + kHitRecord * p[l] + kRecordShape, sizeof sh);
                float w[3] = {1.0f - u[l] - v[l], u[l], v[l]};
                move_inside(sh, w, u[l], v[l]);
            }
    // P, the normal facing d, the step off the surface (cut to half the way back to the origin)
    float P[3][K], flip[K], step[K];
    for (size_t a = 0; a < 3; ++a)
        for (size_t l = 0; l < K; ++l) {
            float x = R[3 + a][l] * u[l];
            x += R[6 + a][l] * v[l];
            x += R[a][l];
            P[a][l] = x;
        }
    for (size_t l = 0; l < K; ++l) {
        const float dn = R[9][l] * d[0][l] + R[10][l] * d[1][l] + R[11][l] * d[2][l];
        flip[l] = dn > 0 ? -1.0f : 1.0f;
        const float half_back = 0.5f * t[l] * std::fabs(dn);
        const float step2 = R[kRecordShape + 5][l], step_len = R[kRecordShape + 6][l];
        const float cut = flip[l] * (half_back / step_len);
        step[l] = half_back * half_back < step2 ? cut : flip[l];  // (t NaN: the full step)
    }
    for (size_t a = 0; a < 3; ++a)
        for (size_t l = 0; l < K; ++l) {
            const size_t j = j0 + l;
            surf_out[a * k + j] = P[a][l];
            surf_out[(3 + a) * k + j] = R[9 + a][l] * flip[l];
            surf_out[(6 + a) * k + j] = P[a][l] + R[12 + a][l] * step[l];
        }
    if (smooth) {
        float N[9][K];
        for (size_t row = 0; row < 9; ++row)
            for (size_t l = 0; l < K; ++l) N[row][l] = records[kHitRecord * p[l] + kRecordNormals + row];
        float nv[3][K];
        for (size_t a = 0; a < 3; ++a)
            for (size_t l = 0; l < K; ++l) {
                float x = N[3 + a][l] * u[l];
                x += N[6 + a][l] * v[l];
                x += N[a][l];
                nv[a][l] = x;
            }
        for (size_t l = 0; l < K; ++l) {
            const float len = __builtin_sqrtf(nv[0][l] * nv[0][l] + nv[1][l] * nv[1][l] + nv[2][l] * nv[2][l]);
            // a zero interpolated normal (opposite corner normals) falls back to ng; len > 0 and
            // len <= kFloatMax is len > 0 && isfinite(len)
            const bool good = (len > 0) & (len <= kFloatMax);
            const float inv = flip[l] / len;
            for (size_t a = 0; a < 3; ++a)
                surf_out[(9 + a) * k + j0 + l] = good ? nv[a][l] * inv : R[9 + a][l] * flip[l];
        }
    }
    for (size_t l = 0; l < K; ++l) prim_out[j0 + l] = int32_t(p[l]);
}

#define DACRT_SURVIVOR_ISA(NAME, TARGET)                                                                        \
    TARGET size_t NAME##_lanes(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr,       \
                               bool roulette, const int64_t* idx, size_t k, float* thr_out, const float* records, \
                               bool smooth, const float* D, float* surf_out, int32_t* prim_out, size_t b,        \
                               size_t e) {                                                                       \
        size_t j0 = b;                                                                                          \
        for (; j0 + K <= e; j0 += K)                                                                            \
            group(hits, n, albedo, M, thr, roulette, idx, k, thr_out, records, smooth, D, surf_out, prim_out, j0); \
        return j0;                                                                                              \
    }

DACRT_SURVIVOR_ISA(portable, )
DACRT_SURVIVOR_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_SURVIVOR_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

}  // namespace

size_t survivor_lanes(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                      const int64_t* idx, size_t k, float* thr_out, const float* records, bool smooth,
                      const float* D, float* surf_out, int32_t* prim_out, size_t b, size_t e) {
    static const LanesFn fn = lane_copy<LanesFn>(portable_lanes, avx2_lanes, avx512_lanes);   // (dispatch.h)
    return fn(hits, n, albedo, M, thr, roulette, idx, k, thr_out, records, smooth, D, surf_out, prim_out, b, e);
}

}  // namespace dacrt
