// The place in an environment map's sampled cell (environment.h's sampling, after the searches
// picked row i and column j), shared by environment_sample and the lane loop of
// environment_sample_lanes (envlanes.cpp) so that both run the same float operations.
// Plain IEEE operations and selects (-ffp-contract=off): every instruction set gives the same bits.
// Always inlined: under the module's LTO an inline function used by both files was merged into
// one out-of-line copy, called per lane (envlanes.cpp's samples 1.4x slower than one at a time).
#pragma once

#include <cmath>

#include "equirect.h"

namespace dacrt::envcell {

constexpr float INV_2PI2 = float(1.0 / (2.0 * 3.14159265358979323846 * 3.14159265358979323846));

// The bilinear blend of corners a (0, 0), b (1, 0), c (0, 1), d (1, 1) at (fx, fy).
DACRT_ENV_INLINE float bilerp(float a, float b, float c, float d, float fx, float fy) {
    return (a * (1.0f - fx) + b * fx) * (1.0f - fy) + (c * (1.0f - fx) + d * fx) * fy;
}

// x where finite, else 0 (a lookup blending in a NaN texel, environment.cpp): a select on
// x - x, which is 0 for every finite x and NaN otherwise, so it vectorises in the lane loops.
DACRT_ENV_INLINE float finite_or_0(float x) { return x - x == 0.0f ? x : 0.0f; }

// std::min(std::max(x, 0), the float below 1), spelled out: std::min<float> and std::max<float>
// are inline functions other files use too, and the module's LTO kept one out-of-line copy that
// the place lanes (envlanes.cpp) then called per lane, which left those loops scalar. The same
// selects as std::max ((x < 0) ? 0 : x) and std::min ((c < y) ? c : y), so the same bits, NaN
// included.
DACRT_ENV_INLINE float clamp_below_one(float x) {
    const float y = x < 0.0f ? 0.0f : x;
    return 0x1.fffffep-1f < y ? 0x1.fffffep-1f : y;
}

// Where a uniform falls within its picked CDF interval [lo, hi), in [0, 1): the row's (a double
// CDF) and the column's.
DACRT_ENV_INLINE float row_fraction(float u1, double lo, double hi) {
    return clamp_below_one(float((double(u1) - lo) / (hi - lo)));
}
DACRT_ENV_INLINE float column_fraction(float u2, float lo, float hi) {
    return clamp_below_one((u2 - lo) / (hi - lo));
}

// x in [0, 1) with density proportional to (1 - x) a + x b (pbrt-v4's SampleLinear).
DACRT_ENV_INLINE float sample_linear(float u, float a, float b) {
    const float x = u * (a + b) / (a + std::sqrt((1.0f - u) * a * a + u * b * b));
    return u == 0 && a == 0 ? 0.0f : clamp_below_one(x);
}

// 'Linear': (u, v) in the cell between texel centres (row fi, column fj of a fw x fh map) whose
// corners' luminances are a (i, j), b (i, j+1), c (i+1, j), d (i+1, j+1), its bilinear blend
// sampled exactly: y from its marginal, then x given y (both linear), for uniforms fu, fv.
DACRT_ENV_INLINE void linear_place(float fu, float fv, float a, float b, float c, float d, float fj, float fi,
                                   float fw, float fh, float& u, float& v) {
    const float y = sample_linear(fv, a + b, c + d);
    const float x = sample_linear(fu, a + (c - a) * y, b + (d - b) * y);
    u = (fj + 0.5f + x) / fw;
    v = (fi + 0.5f + y) / fh;
    u -= std::floor(u);  // REPEAT: the last column's and row's cells wrap
    v -= std::floor(v);
}

// 'Closest': (u, v) uniform in texel (fi, fj); the caller keeps it inside (see environment.cpp).
DACRT_ENV_INLINE void closest_place(float fu, float fv, float fj, float fi, float fw, float fh, float& u, float& v) {
    u = (fj + fu) / fw;
    v = (fi + fv) / fh;
}

}  // namespace dacrt::envcell
