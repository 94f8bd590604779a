// Cycles' Noise Texture (see noise.h): every operation in Cycles' order, in float32, kLanes
// points at a time. One point at a time (8 lookup3 hashes, a branchy gradient and 3 std::fmod
// calls per Perlin evaluation; 16 evaluations per point at Detail 15, 48 for Color) the kernel
// was 78-86% of a render at Detail 15. Here each step is a loop over lanes without branches
// (gradients and floors as bit selects, fmod in double below 1e14), compiled once per
// instruction set like target_clones, but as named copies (portable, avx2, avx512) so that
// DACRT_ISA can pick a narrower one (dispatch.h lane_copy), as for the tracer, and the tests
// compare them on one machine. Per lane the operations and their order are the one-point
// kernel's, so every instruction set gives its bits (-ffp-contract=off: no fused multiply-add;
// tests/native/test_noise_lanes.py, tests/integrator/test_noise.py).
#include "noise.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "dispatch.h"
#include "lookup3.h"
#include "parallel.h"
#include "svmmath.h"

namespace dacrt {

namespace {

using lookup3::final_mix;

#define DACRT_LANES __attribute__((always_inline)) inline

// 16: one AVX-512 vector, two AVX2 ones, four SSE2 ones per step.
constexpr int kLanes = 16;
using Lanes = float[kLanes];
using Points = float[4][kLanes];   // a coordinate's lanes per axis (1D to 3D: the first ones)

DACRT_LANES uint32_t hash_uint(uint32_t kx) {
    uint32_t a = 0xdeadbeefu + (1u << 2) + 13u, b = a, c = a;
    a += kx;
    return final_mix(a, b, c);
}

DACRT_LANES uint32_t hash_uint2(uint32_t kx, uint32_t ky) {
    uint32_t a = 0xdeadbeefu + (2u << 2) + 13u, b = a, c = a;
    b += ky;
    a += kx;
    return final_mix(a, b, c);
}

DACRT_LANES uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz) {
    uint32_t a = 0xdeadbeefu + (3u << 2) + 13u, b = a, c = a;
    c += kz;
    b += ky;
    a += kx;
    return final_mix(a, b, c);
}

// Cycles' hash_uint4: three words mixed, the fourth added to a, the final mix.
DACRT_LANES uint32_t hash_uint4(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw) {
    uint32_t a = 0xdeadbeefu + (4u << 2) + 13u, b = a, c = a;
    a += kx;
    b += ky;
    c += kz;
    lookup3::mix(a, b, c);
    a += kw;
    return final_mix(a, b, c);
}

// Cycles' random_float{2,3,4}_offset component k of a seed (hash of the seed and k); in 1D
// random_float_offset, the hash of the seed alone.
inline float random_offset(float seed, int k, int dims) {
    const uint32_t h32 = dims == 1 ? hash_uint(lookup3::float_bits(seed))
                                   : hash_uint2(lookup3::float_bits(seed), lookup3::float_bits(float(k)));
    const float h = float(h32) / float(0xFFFFFFFFu);
    return 100.0f + h * 100.0f;
}

DACRT_LANES float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

DACRT_LANES float from_bits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

// -v where the bit is set: negation's sign flip (NaN's too) as an xor, no branch.
DACRT_LANES float negate_if(float v, uint32_t bit, int shift) {
    return from_bits(lookup3::float_bits(v) ^ (bit << shift));
}

// c ? a : b as bit masks: plain ?: selects here let GCC thread constant paths (NaN's zero
// cell) into branches that stopped the wide versions from vectorising.
DACRT_LANES uint32_t mask(bool c) { return 0u - uint32_t(c); }
DACRT_LANES float select(uint32_t m, float a, float b) {
    return from_bits((lookup3::float_bits(a) & m) | (lookup3::float_bits(b) & ~m));
}

DACRT_LANES float grad3(uint32_t h, float x, float y, float z) {
    h &= 15u;
    const float u = select(mask(h < 8), x, y);
    const float vt = select(mask(h == 12) | mask(h == 14), x, z);
    const float v = select(mask(h < 4), y, vt);
    return negate_if(u, h & 1u, 31) + negate_if(v, h & 2u, 30);
}

// Cycles' grad4: three of the four offsets, each negated by its bit of the hash.
DACRT_LANES float grad4(uint32_t h, float x, float y, float z, float w) {
    h &= 31u;
    const float u = select(mask(h < 24), x, y);
    const float v = select(mask(h < 16), y, z);
    const float s = select(mask(h < 8), z, w);
    return negate_if(u, h & 1u, 31) + negate_if(v, h & 2u, 30) + negate_if(s, h & 4u, 29);
}

// Cycles' grad1: a slope 1..8 from the hash's low bits, negated by its bit 3.
DACRT_LANES float grad1(uint32_t h, float x) {
    h &= 15u;
    const float g = float(int32_t(1u + (h & 7u)));
    return negate_if(g, h & 8u, 28) * x;
}

DACRT_LANES float grad2(uint32_t h, float x, float y) {
    h &= 7u;
    const uint32_t lo = mask(h < 4);
    const float u = select(lo, x, y);
    const float v = 2.0f * select(lo, y, x);
    return negate_if(u, h & 1u, 31) + negate_if(v, h & 2u, 30);
}

// x - floor(x) and floor(x) as an integer (wrapping as Cycles' int; 0 where x is NaN), for
// snoise's coordinates (|x| <= 100000.5 or NaN). The floor comes from the truncated integer,
// which every x86-64 vectorises (std::floor needs SSE4.1); copysign keeps std::floor(-0) = -0,
// so x - floor(x) has its bits. (The one-point kernel's int64 conversion gives the same words
// for |x| < 2^31.)
DACRT_LANES float floorfrac(float x, uint32_t& i) {
    const float xs = select(mask(std::fabs(x) < 2147483648.0f), x, 0.0f);
    const int32_t t = int32_t(xs);
    const float tf = float(t);
    const uint32_t below = mask(tf > xs);
    i = uint32_t(t) + below;
    return x - std::copysign(tf - select(below, 1.0f, 0.0f), xs);  // (tf - 0 is tf)
}

DACRT_LANES float perlin_3d(float x, float y, float z) {
    uint32_t X, Y, Z;
    const float fx = floorfrac(x, X), fy = floorfrac(y, Y), fz = floorfrac(z, Z);
    const float u = fade(fx), v = fade(fy), w = fade(fz);
    const float gx = fx - 1.0f, gy = fy - 1.0f, gz = fz - 1.0f;
    const float g0 = grad3(hash_uint3(X, Y, Z), fx, fy, fz);
    const float g1 = grad3(hash_uint3(X + 1, Y, Z), gx, fy, fz);
    const float g2 = grad3(hash_uint3(X, Y + 1, Z), fx, gy, fz);
    const float g3 = grad3(hash_uint3(X + 1, Y + 1, Z), gx, gy, fz);
    const float g4 = grad3(hash_uint3(X, Y, Z + 1), fx, fy, gz);
    const float g5 = grad3(hash_uint3(X + 1, Y, Z + 1), gx, fy, gz);
    const float g6 = grad3(hash_uint3(X, Y + 1, Z + 1), fx, gy, gz);
    const float g7 = grad3(hash_uint3(X + 1, Y + 1, Z + 1), gx, gy, gz);
    const float x1 = 1.0f - u, y1 = 1.0f - v, z1 = 1.0f - w;
    return z1 * (y1 * (g0 * x1 + g1 * u) + v * (g2 * x1 + g3 * u)) +
           w * (y1 * (g4 * x1 + g5 * u) + v * (g6 * x1 + g7 * u));
}

// Cycles' mix (a + t (b - a)): quad_mix's last step and perlin_1d's.
DACRT_LANES float mix(float a, float b, float t) { return a + t * (b - a); }

DACRT_LANES float perlin_1d(float x) {
    uint32_t X;
    const float fx = floorfrac(x, X);
    const float u = fade(fx);
    return mix(grad1(hash_uint(X), fx), grad1(hash_uint(X + 1), fx - 1.0f), u);
}

// Cycles' tri_mix of perlin_4d's 8 gradients at one w lattice step (Wk, offset wk).
DACRT_LANES float perlin_4d_cube(uint32_t X, uint32_t Y, uint32_t Z, uint32_t Wk, float fx, float fy, float fz,
                                 float wk, float u, float v, float t) {
    const float gx = fx - 1.0f, gy = fy - 1.0f, gz = fz - 1.0f;
    const float g0 = grad4(hash_uint4(X, Y, Z, Wk), fx, fy, fz, wk);
    const float g1 = grad4(hash_uint4(X + 1, Y, Z, Wk), gx, fy, fz, wk);
    const float g2 = grad4(hash_uint4(X, Y + 1, Z, Wk), fx, gy, fz, wk);
    const float g3 = grad4(hash_uint4(X + 1, Y + 1, Z, Wk), gx, gy, fz, wk);
    const float g4 = grad4(hash_uint4(X, Y, Z + 1, Wk), fx, fy, gz, wk);
    const float g5 = grad4(hash_uint4(X + 1, Y, Z + 1, Wk), gx, fy, gz, wk);
    const float g6 = grad4(hash_uint4(X, Y + 1, Z + 1, Wk), fx, gy, gz, wk);
    const float g7 = grad4(hash_uint4(X + 1, Y + 1, Z + 1, Wk), gx, gy, gz, wk);
    const float x1 = 1.0f - u, y1 = 1.0f - v, z1 = 1.0f - t;
    return z1 * (y1 * (g0 * x1 + g1 * u) + v * (g2 * x1 + g3 * u)) +
           t * (y1 * (g4 * x1 + g5 * u) + v * (g6 * x1 + g7 * u));
}

// Cycles' scalar perlin_4d: quad_mix, the cubes at w and w + 1 mixed along w.
DACRT_LANES float perlin_4d(float x, float y, float z, float w) {
    uint32_t X, Y, Z, W;
    const float fx = floorfrac(x, X), fy = floorfrac(y, Y), fz = floorfrac(z, Z), fw = floorfrac(w, W);
    const float u = fade(fx), v = fade(fy), t = fade(fz), s = fade(fw);
    return mix(perlin_4d_cube(X, Y, Z, W, fx, fy, fz, fw, u, v, t),
               perlin_4d_cube(X, Y, Z, W + 1, fx, fy, fz, fw - 1.0f, u, v, t), s);
}

DACRT_LANES float perlin_2d(float x, float y) {
    uint32_t X, Y;
    const float fx = floorfrac(x, X), fy = floorfrac(y, Y);
    const float u = fade(fx), v = fade(fy);
    const float gx = fx - 1.0f, gy = fy - 1.0f;
    const float g0 = grad2(hash_uint2(X, Y), fx, fy);
    const float g1 = grad2(hash_uint2(X + 1, Y), gx, fy);
    const float g2 = grad2(hash_uint2(X, Y + 1), fx, gy);
    const float g3 = grad2(hash_uint2(X + 1, Y + 1), gx, gy);
    const float x1 = 1.0f - u;
    return (1.0f - v) * (g0 * x1 + g1 * u) + v * (g2 * x1 + g3 * u);
}

// fmod(x, 100000) with std::fmod's bits for |x| < 1e14 (x itself below 100000) in vector code:
// the quotient from a double product is off by at most one, which the remainder's range test
// corrects; every step is exact in double (the remainder is a float, as fmod's always is).
DACRT_LANES float wrap(float x) {
    const double a = double(select(mask(std::fabs(x) < 1e14f), std::fabs(x), 0.0f));
    const double q = double(int32_t(a * 1e-5));
    double r = a - q * 100000.0;
    r = r < 0.0 ? r + 100000.0 : r;
    r = r >= 100000.0 ? r - 100000.0 : r;
    return std::copysign(float(r), x);
}

// Cycles' snoise_1d to snoise_4d of every lane: the noise repeats every 100000 on each axis
// (fmod, against float32's spacing far out; past 1e6 the point also moves half a cell), scaled,
// NaN where a coordinate is not finite (as Cycles 5.0). Only lanes beyond wrap's range (1e14, inf, NaN) call std::fmod, after the
// vector pass: at Detail 15 the last octaves' coordinates are past 100000 in every lane.
template <int D>
DACRT_LANES void snoise_lanes(const Points& p, Lanes& out) {
    Points q;
    int far = 0;
    for (int a = 0; a < D; ++a)
        for (int k = 0; k < kLanes; ++k) {
            const float x = p[a][k];
            q[a][k] = wrap(x) + 0.5f * float(std::fabs(x) >= 1000000.0f);
            far |= int(!(std::fabs(x) < 1e14f));
        }
    if (far)
        for (int a = 0; a < D; ++a)
            for (int k = 0; k < kLanes; ++k) {
                const float x = p[a][k];
                if (!(std::fabs(x) < 1e14f))
                    q[a][k] = std::fmod(x, 100000.0f) + 0.5f * float(std::fabs(x) >= 1000000.0f);
            }
    constexpr float kScale = D == 1 ? 0.2500f : D == 2 ? 0.6616f : D == 3 ? 0.9820f : 0.8344f;
    for (int k = 0; k < kLanes; ++k) {
        float r;
        if constexpr (D == 1)
            r = perlin_1d(q[0][k]);
        else if constexpr (D == 2)
            r = perlin_2d(q[0][k], q[1][k]);
        else if constexpr (D == 3)
            r = perlin_3d(q[0][k], q[1][k], q[2][k]);
        else
            r = perlin_4d(q[0][k], q[1][k], q[2][k], q[3][k]);
        // a NaN (from a coordinate that overflowed to inf: a Scale or Lacunarity typed 'inf',
        // Blender's 3.4e38) is passed on, as Cycles 5.0's snoise does (no ensure_finite): it
        // renders black there; zeroed, it had rendered grey (0.5 + the other octaves)
        out[k] = kScale * r;
    }
}

// A NaN result as one NaN: an octave's NaN (passed on, as Cycles') reaches the sums through
// operands whose order each ISA's code picks, and x86 keeps the first NaN operand's sign.
inline float one_nan(float v) { return v == v ? v : std::numeric_limits<float>::quiet_NaN(); }

// The per-point parameters of a block's lanes.
struct Params {
    Lanes detail, rough, lac, offset, gain;
    int octaves[kLanes];  // int(floor(detail))
    int most;             // the lanes' largest octave count
    bool rmd_any;         // some lane has a fractional Detail
};

// s = scale * p per lane (fBM's fscale x q).
template <int D>
DACRT_LANES void scaled(const Points& p, const Lanes& scale, Points& s) {
    for (int a = 0; a < D; ++a)
        for (int k = 0; k < kLanes; ++k) s[a][k] = scale[k] * p[a][k];
}

// The multifractals' p *= lacunarity, in the lanes still in their octave loop.
template <int D>
DACRT_LANES void scale_point(Points& p, const Lanes& lac, const bool* on) {
    for (int a = 0; a < D; ++a)
        for (int k = 0; k < kLanes; ++k) p[a][k] = on[k] ? p[a][k] * lac[k] : p[a][k];
}

// Cycles' noise_fbm of points q, lanes past their octave count (Detail per point) unchanged.
template <int D, class S>
DACRT_LANES void fbm(const Points& q, const Params& w, bool normalize, Lanes& out, S snoise) {
    Lanes fscale, amp, maxamp, sum, t;
    Points s;
    for (int k = 0; k < kLanes; ++k) fscale[k] = 1.0f, amp[k] = 1.0f, maxamp[k] = 0.0f, sum[k] = 0.0f;
    for (int i = 0; i <= w.most; ++i) {
        scaled<D>(q, fscale, s);
        snoise(s, t);
        for (int k = 0; k < kLanes; ++k) {
            const bool on = i <= w.octaves[k];
            sum[k] = on ? sum[k] + t[k] * amp[k] : sum[k];
            maxamp[k] = on ? maxamp[k] + amp[k] : maxamp[k];
            amp[k] = on ? amp[k] * w.rough[k] : amp[k];
            fscale[k] = on ? fscale[k] * w.lac[k] : fscale[k];
        }
    }
    for (int k = 0; k < kLanes; ++k) out[k] = normalize ? 0.5f * sum[k] / maxamp[k] + 0.5f : sum[k];
    if (!w.rmd_any) return;
    scaled<D>(q, fscale, s);
    snoise(s, t);
    for (int k = 0; k < kLanes; ++k) {
        const float rmd = w.detail[k] - std::floor(w.detail[k]);
        const float sum2 = sum[k] + t[k] * amp[k];
        float v;
        if (normalize) {
            const float part = 0.5f * sum2 / (maxamp[k] + amp[k]) + 0.5f;
            v = (1.0f - rmd) * out[k] + rmd * part;
        } else {
            v = (1.0f - rmd) * sum[k] + rmd * sum2;
        }
        out[k] = rmd == 0.0f ? out[k] : v;
    }
}

// The multifractals of fractal_noise.h: the point itself scaled by the lacunarity each octave
// (p *= lacunarity, not fBM's running fscale x p: other roundings, as in Cycles).
template <int D, class S>
DACRT_LANES void multi_fractal(Points& p, const Params& w, Lanes& out, S snoise) {
    Lanes pwr, t;
    bool on[kLanes];
    for (int k = 0; k < kLanes; ++k) out[k] = 1.0f, pwr[k] = 1.0f;
    for (int i = 0; i <= w.most; ++i) {
        snoise(p, t);
        for (int k = 0; k < kLanes; ++k) {
            on[k] = i <= w.octaves[k];
            out[k] = on[k] ? out[k] * (pwr[k] * t[k] + 1.0f) : out[k];
            pwr[k] = on[k] ? pwr[k] * w.rough[k] : pwr[k];
        }
        scale_point<D>(p, w.lac, on);
    }
    if (!w.rmd_any) return;
    snoise(p, t);
    for (int k = 0; k < kLanes; ++k) {
        const float rmd = w.detail[k] - std::floor(w.detail[k]);
        out[k] = rmd != 0.0f ? out[k] * (rmd * pwr[k] * t[k] + 1.0f) : out[k];
    }
}

template <int D, class S>
DACRT_LANES void hetero_terrain(Points& p, const Params& w, Lanes& out, S snoise) {
    Lanes pwr, t;
    bool on[kLanes];
    snoise(p, t);
    for (int k = 0; k < kLanes; ++k) pwr[k] = w.rough[k], out[k] = w.offset[k] + t[k], on[k] = true;
    scale_point<D>(p, w.lac, on);
    for (int i = 1; i <= w.most; ++i) {
        snoise(p, t);
        for (int k = 0; k < kLanes; ++k) {
            on[k] = i <= w.octaves[k];
            const float increment = (t[k] + w.offset[k]) * pwr[k] * out[k];
            out[k] = on[k] ? out[k] + increment : out[k];
            pwr[k] = on[k] ? pwr[k] * w.rough[k] : pwr[k];
        }
        scale_point<D>(p, w.lac, on);
    }
    if (!w.rmd_any) return;
    snoise(p, t);
    for (int k = 0; k < kLanes; ++k) {
        const float rmd = w.detail[k] - std::floor(w.detail[k]);
        const float increment = (t[k] + w.offset[k]) * pwr[k] * out[k];
        out[k] = rmd != 0.0f ? out[k] + rmd * increment : out[k];
    }
}

// A lane leaves the octave loop for good once its weight is <= 0.001 (or NaN), as Cycles'
// loop does; fmin(weight, 1) of a weight above 0.001 is the select.
template <int D, class S>
DACRT_LANES void hybrid_multi_fractal(Points& p, const Params& w, Lanes& out, S snoise) {
    Lanes pwr, weight, t;
    bool on[kLanes];
    for (int k = 0; k < kLanes; ++k) pwr[k] = 1.0f, out[k] = 0.0f, weight[k] = 1.0f;
    for (int i = 0;; ++i) {
        int any = 0;
        for (int k = 0; k < kLanes; ++k) {
            on[k] = (weight[k] > 0.001f) & (i <= w.octaves[k]);
            any |= int(on[k]);
        }
        if (!any) break;
        snoise(p, t);
        for (int k = 0; k < kLanes; ++k) {
            const float wt = weight[k] < 1.0f ? weight[k] : 1.0f;
            const float signal = (t[k] + w.offset[k]) * pwr[k];
            pwr[k] = on[k] ? pwr[k] * w.rough[k] : pwr[k];
            out[k] = on[k] ? out[k] + wt * signal : out[k];
            weight[k] = on[k] ? wt * (w.gain[k] * signal) : weight[k];
        }
        scale_point<D>(p, w.lac, on);
    }
    if (!w.rmd_any) return;
    snoise(p, t);
    for (int k = 0; k < kLanes; ++k) {
        const float rmd = w.detail[k] - std::floor(w.detail[k]);
        const float wt = weight[k] < 1.0f ? weight[k] : 1.0f;
        const float signal = (t[k] + w.offset[k]) * pwr[k];
        out[k] = (rmd != 0.0f) & (weight[k] > 0.001f) ? out[k] + rmd * wt * signal : out[k];
    }
}

template <int D, class S>
DACRT_LANES void ridged_multi_fractal(Points& p, const Params& w, Lanes& out, S snoise) {
    Lanes pwr, signal, t;
    bool on[kLanes];
    snoise(p, t);
    for (int k = 0; k < kLanes; ++k) {
        pwr[k] = w.rough[k];
        const float s = w.offset[k] - std::fabs(t[k]);
        signal[k] = s * s;
        out[k] = signal[k];
    }
    for (int i = 1; i <= w.most; ++i) {
        for (int k = 0; k < kLanes; ++k) on[k] = i <= w.octaves[k];
        scale_point<D>(p, w.lac, on);
        snoise(p, t);
        for (int k = 0; k < kLanes; ++k) {
            const float weight = svm::clamp(signal[k] * w.gain[k], 0.0f, 1.0f);
            float s = w.offset[k] - std::fabs(t[k]);
            s = s * s;
            s = s * weight;
            out[k] = on[k] ? out[k] + s * pwr[k] : out[k];
            signal[k] = on[k] ? s : signal[k];
            pwr[k] = on[k] ? pwr[k] * w.rough[k] : pwr[k];
        }
    }
}

// Cycles' noise_select: the texture's type at points p, offset by off (D) first.
template <int D, class S>
DACRT_LANES void noise_select(const Points& p, const float* off, int type, bool normalize, const Params& w,
                              Lanes& out, S snoise) {
    Points q;
    for (int a = 0; a < D; ++a)
        for (int k = 0; k < kLanes; ++k) q[a][k] = off ? p[a][k] + off[a] : p[a][k];
    switch (type) {
        case NOISE_FBM: return fbm<D>(q, w, normalize, out, snoise);
        case NOISE_MULTIFRACTAL: return multi_fractal<D>(q, w, out, snoise);
        case NOISE_HYBRID_MULTIFRACTAL: return hybrid_multi_fractal<D>(q, w, out, snoise);
        case NOISE_RIDGED_MULTIFRACTAL: return ridged_multi_fractal<D>(q, w, out, snoise);
        default: return hetero_terrain<D>(q, w, out, snoise);
    }
}

inline float at(const float* a, size_t count, size_t i) { return a[count == 1 ? 0 : i]; }

using Offsets = float[6][4];  // seeds 0..dims-1: distortion; dims, dims + 1: the colour's channels

// Points [b, e) of noise_texture, kLanes at a time (a short last block repeats its last point).
template <int D, class S>
DACRT_LANES void noise_range(const float* p, size_t b, size_t e, const NoiseParams& k, const Offsets& offsets,
                             float* fac, float* color, S snoise) {
    for (size_t i0 = b; i0 < e; i0 += kLanes) {
        Params w;
        Points q;
        Lanes dist;
        int distort = 0;
        w.most = 0;
        w.rmd_any = false;
        for (int j = 0; j < kLanes; ++j) {
            const size_t i = std::min(i0 + size_t(j), e - 1);
            const float scale = at(k.scale, k.scale_n, i);
            w.detail[j] = svm::clamp(at(k.detail, k.detail_n, i), 0.0f, 15.0f);   // NaN: one octave
            w.rough[j] = svm::max(at(k.roughness, k.roughness_n, i), 0.0f);
            w.lac[j] = at(k.lacunarity, k.lacunarity_n, i);
            w.offset[j] = at(k.offset, k.offset_n, i);
            w.gain[j] = at(k.gain, k.gain_n, i);
            w.octaves[j] = int(std::floor(w.detail[j]));
            w.most = std::max(w.most, w.octaves[j]);
            w.rmd_any |= w.detail[j] - std::floor(w.detail[j]) != 0.0f;
            dist[j] = at(k.distortion, k.distortion_n, i);
            distort |= int(dist[j] != 0.0f);
            for (int a = 0; a < D; ++a) q[a][j] = p[i * size_t(D) + a] * scale;
        }
        if (distort) {
            Points shift, s;
            for (int c = 0; c < D; ++c) {
                for (int a = 0; a < D; ++a)
                    for (int j = 0; j < kLanes; ++j) s[a][j] = q[a][j] + offsets[c][a];
                snoise(s, shift[c]);
            }
            for (int a = 0; a < D; ++a)
                for (int j = 0; j < kLanes; ++j) q[a][j] = dist[j] != 0.0f ? q[a][j] + shift[a][j] * dist[j] : q[a][j];
        }
        const size_t m = std::min(size_t(kLanes), e - i0);
        Lanes value;
        noise_select<D>(q, nullptr, k.type, k.normalize, w, value, snoise);
        for (size_t j = 0; j < m; ++j) fac[i0 + j] = one_nan(value[j]);
        if (color) {
            for (size_t j = 0; j < m; ++j) color[3 * (i0 + j)] = one_nan(value[j]);
            for (int c = 1; c < 3; ++c) {
                noise_select<D>(q, offsets[D + c - 1], k.type, k.normalize, w, value, snoise);
                for (size_t j = 0; j < m; ++j) color[3 * (i0 + j) + c] = one_nan(value[j]);
            }
        }
    }
}

using RangeFn = void (*)(const float*, size_t, size_t, int, const NoiseParams&, const Offsets&, float*, float*);

// One copy of the kernel per instruction set: snoise (the hot loop) its own function, called
// from the fractal loops of the same instruction set.
#define DACRT_NOISE_ISA(NAME, TARGET)                                                                      \
    TARGET __attribute__((noinline)) void NAME##_snoise1(const Points& p, Lanes& out) {                  \
        snoise_lanes<1>(p, out);                                                                         \
    }                                                                                                    \
    TARGET __attribute__((noinline)) void NAME##_snoise2(const Points& p, Lanes& out) {                  \
        snoise_lanes<2>(p, out);                                                                         \
    }                                                                                                    \
    TARGET __attribute__((noinline)) void NAME##_snoise3(const Points& p, Lanes& out) {                  \
        snoise_lanes<3>(p, out);                                                                         \
    }                                                                                                    \
    TARGET __attribute__((noinline)) void NAME##_snoise4(const Points& p, Lanes& out) {                  \
        snoise_lanes<4>(p, out);                                                                         \
    }                                                                                                    \
    TARGET void NAME##_range(const float* p, size_t b, size_t e, int dims, const NoiseParams& k,         \
                             const Offsets& offsets, float* fac, float* color) {                         \
        if (dims == 1)                                                                                   \
            noise_range<1>(p, b, e, k, offsets, fac, color, NAME##_snoise1);                             \
        else if (dims == 2)                                                                              \
            noise_range<2>(p, b, e, k, offsets, fac, color, NAME##_snoise2);                             \
        else if (dims == 3)                                                                              \
            noise_range<3>(p, b, e, k, offsets, fac, color, NAME##_snoise3);                             \
        else                                                                                             \
            noise_range<4>(p, b, e, k, offsets, fac, color, NAME##_snoise4);                             \
    }

DACRT_NOISE_ISA(portable, )
DACRT_NOISE_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_NOISE_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

}  // namespace

void noise_texture(const float* p, size_t n, int dims, const NoiseParams& k, float* fac, float* color) {
    static const RangeFn range = lane_copy<RangeFn>(portable_range, avx2_range, avx512_range);
    Offsets offsets;
    for (int seed = 0; seed < 6; ++seed)
        for (int a = 0; a < 4; ++a) offsets[seed][a] = random_offset(float(seed), a, dims);
    parallel_for(n, [&](size_t b, size_t e) { range(p, b, e, dims, k, offsets, fac, color); }, size_t(1) << 12);
}

}  // namespace dacrt
