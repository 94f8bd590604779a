// The equirectangular map's direction <-> (u, v) in float arithmetic that vectorises: libm's
// atan2f / acosf / sinf / cosf are calls a lane loop cannot inline (8% of an environment
// render's samples, besides environment_sample's own 15%). Plain IEEE operations and selects
// only (no FMA: -ffp-contract=off), so a scalar call and every target_clones lane give the same
// bits. Within ~2 float ulps of the exact functions (tests/native/test_environment_lanes.py),
// as close to Cycles' formulas as their float rounding:
//   u = 0.5 - atan2(m.y, m.x) / 2pi,  v = 1 - theta / pi,  theta = atan2(|m.xy|, m.z) (= acos of
//   the normalised m.z, without its loss of precision near the poles);
//   theta = pi (1 - v), phi = pi (1 - 2u): sin(theta) = sinpi(v), cos(theta) = -cospi(v),
//   sin(phi) = sinpi(2u), cos(phi) = -cospi(2u) (exact argument reduction, no rounding of pi x).
#pragma once

#include <cmath>

// For the functions both a lane loop (envlanes.cpp) and scalar code use: the module's LTO
// otherwise merges them into one out-of-line copy that the lane loop calls per lane.
#define DACRT_ENV_INLINE __attribute__((always_inline)) inline

namespace dacrt::equirect {

// atan(t) on [-tan(pi/8), tan(pi/8)] (Cephes atanf's minimax polynomial, ~1 ulp).
inline float atan_small(float t) {
    const float z = t * t;
    return (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t;
}

// atan2(y, x) with libm's quadrants and signs for finite inputs (atan2(+-0, -x) = +-pi,
// atan2(+-0, +0) = +-0; +-pi/2 on the y axis).
inline float atan2f_poly(float y, float x) {
    const float ax = std::fabs(x), ay = std::fabs(y);
    const float hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    const float a = hi > 0.0f ? lo / hi : 0.0f;  // in [0, 1]
    const bool big = a > 0.414213562373f;          // tan(pi/8): reduce by pi/4
    const float t = big ? (a - 1.0f) / (a + 1.0f) : a;
    float r = atan_small(t) + (big ? 0.785398163397f : 0.0f);
    r = ay > ax ? 1.57079632679f - r : r;
    r = x < 0.0f || (x == 0.0f && std::signbit(x)) ? 3.14159265359f - r : r;
    return std::signbit(y) ? -r : r;
}

// sin(pi r), cos(pi r) for r in [-1/4, 1/4]: Taylor in r to degree 9 / 10 (truncation below
// 2e-9 relative there).
DACRT_ENV_INLINE float sinpi_small(float r) {
    const float z = r * r;
    return ((((8.21458866e-2f * z - 5.99264529e-1f) * z + 2.55016404f) * z - 5.16771278f) * z + 3.14159274f) * r;
}
DACRT_ENV_INLINE float cospi_small(float r) {
    const float z = r * r;
    return ((((-2.58068914e-2f * z + 2.35330630e-1f) * z - 1.33526277f) * z + 4.05871213f) * z - 4.93480220f) * z + 1.0f;
}

// sin(pi t) and cos(pi t) for t in [0, 2]: t = k / 2 + r exactly (|r| <= 1/4), then the quadrant.
DACRT_ENV_INLINE void sincospi(float t, float& s, float& c) {
    const int ki = int(2.0f * t + 0.5f);  // (t >= 0: a truncation, which every ISA vectorises)
    const float k = float(ki);
    const float r = t - 0.5f * k;
    const float sr = sinpi_small(r), cr = cospi_small(r);
    const int q = ki & 3;
    const float s0 = (q & 1) ? cr : sr, c0 = (q & 1) ? sr : cr;
    s = (q & 2) ? -s0 : s0;
    c = ((q + 1) & 2) ? -c0 : c0;
}

constexpr float INV_2PI = float(1.0 / (2.0 * 3.14159265358979323846));
constexpr float INV_PI = float(1.0 / 3.14159265358979323846);

// (u, v) of a map-frame direction m (any length > 0) and sin(theta) = |m.xy| / |m|.
inline void to_uv(float mx, float my, float mz, float& u, float& v, float& sin_theta) {
    const float rho = std::sqrt(mx * mx + my * my);
    const float len = std::sqrt(mx * mx + my * my + mz * mz);
    // At the pole (m.x, m.y both zero) atan2 reads only their signs: Cycles' directions there
    // have +0 (its camera sums products, one of them +0), ours can carry -0 (an orthographic
    // camera's -forward, to_map's products), which read the u = 0 seam column instead of
    // u = 0.5. Adding +0 turns -0 into +0 and leaves every other value as it is.
    u = 0.5f - atan2f_poly(my + 0.0f, mx + 0.0f) * INV_2PI;
    v = 1.0f - atan2f_poly(rho, mz) * INV_PI;
    sin_theta = len > 0.0f ? rho / len : 0.0f;
}

// The unit map-frame direction of (u, v) in [0, 1) and its sin(theta).
DACRT_ENV_INLINE void from_uv(float u, float v, float m[3], float& sin_theta) {
    float st, ct, sp, cp;
    sincospi(v, st, ct);
    sincospi(2.0f * u, sp, cp);
    m[0] = st * -cp;
    m[1] = st * sp;
    m[2] = -ct;
    sin_theta = st;
}

}  // namespace dacrt::equirect
