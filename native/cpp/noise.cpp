// Cycles' Noise Texture (see noise.h): every operation in Cycles' order, in float32.
#include "noise.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lookup3.h"
#include "parallel.h"
#include "svmmath.h"

namespace dacrt {

namespace {

using lookup3::final_mix;

inline uint32_t hash_uint2(uint32_t kx, uint32_t ky) {
    uint32_t a = 0xdeadbeefu + (2u << 2) + 13u, b = a, c = a;
    b += ky;
    a += kx;
    return final_mix(a, b, c);
}

inline uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz) {
    uint32_t a = 0xdeadbeefu + (3u << 2) + 13u, b = a, c = a;
    c += kz;
    b += ky;
    a += kx;
    return final_mix(a, b, c);
}


// Cycles' random_float3_offset / random_float2_offset component k of a seed.
inline float random_offset(float seed, int k) {
    const uint32_t h32 = hash_uint2(lookup3::float_bits(seed), lookup3::float_bits(float(k)));
    const float h = float(h32) / float(0xFFFFFFFFu);
    return 100.0f + h * 100.0f;
}

inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

inline float negate_if(float v, uint32_t flag) { return flag ? -v : v; }

inline float grad3(uint32_t h, float x, float y, float z) {
    h &= 15u;
    const float u = h < 8 ? x : y;
    const float vt = (h == 12 || h == 14) ? x : z;
    const float v = h < 4 ? y : vt;
    return negate_if(u, h & 1u) + negate_if(v, h & 2u);
}

inline float grad2(uint32_t h, float x, float y) {
    h &= 7u;
    const float u = h < 4 ? x : y;
    const float v = 2.0f * (h < 4 ? y : x);
    return negate_if(u, h & 1u) + negate_if(v, h & 2u);
}

// x - floor(x) and floor(x) as an integer (0 where x is not finite; wraps as Cycles' int).
inline float floorfrac(float x, uint32_t& i) {
    const float f = std::floor(x);
    // (beyond int64's range numpy's conversion, which the reference uses, gives 0 bits too)
    i = std::fabs(f) < 9.2e18f ? uint32_t(uint64_t(int64_t(f))) : 0u;
    return x - f;
}

float perlin_3d(const float* p) {
    uint32_t X, Y, Z;
    const float fx = floorfrac(p[0], X), fy = floorfrac(p[1], Y), fz = floorfrac(p[2], Z);
    const float u = fade(fx), v = fade(fy), w = fade(fz);
    float g[8];
    for (uint32_t k = 0; k < 2; ++k)
        for (uint32_t j = 0; j < 2; ++j)
            for (uint32_t i = 0; i < 2; ++i)
                g[4 * k + 2 * j + i] = grad3(hash_uint3(X + i, Y + j, Z + k), fx - float(i), fy - float(j), fz - float(k));
    const float x1 = 1.0f - u, y1 = 1.0f - v, z1 = 1.0f - w;
    return z1 * (y1 * (g[0] * x1 + g[1] * u) + v * (g[2] * x1 + g[3] * u)) +
           w * (y1 * (g[4] * x1 + g[5] * u) + v * (g[6] * x1 + g[7] * u));
}

float perlin_2d(const float* p) {
    uint32_t X, Y;
    const float fx = floorfrac(p[0], X), fy = floorfrac(p[1], Y);
    const float u = fade(fx), v = fade(fy);
    float g[4];
    for (uint32_t j = 0; j < 2; ++j)
        for (uint32_t i = 0; i < 2; ++i) g[2 * j + i] = grad2(hash_uint2(X + i, Y + j), fx - float(i), fy - float(j));
    const float x1 = 1.0f - u;
    return (1.0f - v) * (g[0] * x1 + g[1] * u) + v * (g[2] * x1 + g[3] * u);
}

// Cycles' snoise_2d / snoise_3d: the noise repeats every 100000 on each axis (fmod, against
// float32's spacing far out; past 1e6 the point also moves half a cell), scaled, 0 where not
// finite.
inline float snoise(const float* p, int dims) {
    float q[3];
    for (int a = 0; a < dims; ++a)
        q[a] = std::fmod(p[a], 100000.0f) + 0.5f * float(std::fabs(p[a]) >= 1000000.0f);
    float r = dims == 3 ? perlin_3d(q) : perlin_2d(q);
    if (!std::isfinite(r)) r = 0.0f;
    return (dims == 3 ? 0.9820f : 0.6616f) * r;
}

// Cycles' noise_fbm of point q (dims).
float fbm(const float* q, int dims, float detail, float roughness, float lacunarity, bool normalize) {
    float s[3];
    float fscale = 1.0f, amp = 1.0f, maxamp = 0.0f, sum = 0.0f;
    const int octaves = int(std::floor(detail));
    for (int i = 0; i <= octaves; ++i) {
        for (int a = 0; a < dims; ++a) s[a] = fscale * q[a];
        const float t = snoise(s, dims);
        sum = sum + t * amp;
        maxamp = maxamp + amp;
        amp = amp * roughness;
        fscale = fscale * lacunarity;
    }
    const float rmd = detail - std::floor(detail);
    const float whole = normalize ? 0.5f * sum / maxamp + 0.5f : sum;
    if (rmd == 0.0f) return whole;
    for (int a = 0; a < dims; ++a) s[a] = fscale * q[a];
    const float t = snoise(s, dims);
    const float sum2 = sum + t * amp;
    if (normalize) {
        const float part = 0.5f * sum2 / (maxamp + amp) + 0.5f;
        return (1.0f - rmd) * whole + rmd * part;
    }
    return (1.0f - rmd) * sum + rmd * sum2;
}

// The multifractals of fractal_noise.h: the point itself scaled by the lacunarity each octave
// (p *= lacunarity, not fBM's running fscale x p: other roundings, as in Cycles).
inline void scale_point(float* p, int dims, float lacunarity) {
    for (int a = 0; a < dims; ++a) p[a] = p[a] * lacunarity;
}

float multi_fractal(float* p, int dims, float detail, float roughness, float lacunarity) {
    float value = 1.0f, pwr = 1.0f;
    const int octaves = int(std::floor(detail));
    for (int i = 0; i <= octaves; ++i) {
        value = value * (pwr * snoise(p, dims) + 1.0f);
        pwr = pwr * roughness;
        scale_point(p, dims, lacunarity);
    }
    const float rmd = detail - std::floor(detail);
    if (rmd != 0.0f) value = value * (rmd * pwr * snoise(p, dims) + 1.0f);
    return value;
}

float hetero_terrain(float* p, int dims, float detail, float roughness, float lacunarity, float offset) {
    float pwr = roughness;
    float value = offset + snoise(p, dims);
    scale_point(p, dims, lacunarity);
    const int octaves = int(std::floor(detail));
    for (int i = 1; i <= octaves; ++i) {
        const float increment = (snoise(p, dims) + offset) * pwr * value;
        value = value + increment;
        pwr = pwr * roughness;
        scale_point(p, dims, lacunarity);
    }
    const float rmd = detail - std::floor(detail);
    if (rmd != 0.0f) {
        const float increment = (snoise(p, dims) + offset) * pwr * value;
        value = value + rmd * increment;
    }
    return value;
}

float hybrid_multi_fractal(float* p, int dims, float detail, float roughness, float lacunarity, float offset,
                           float gain) {
    float pwr = 1.0f, value = 0.0f, weight = 1.0f;
    const int octaves = int(std::floor(detail));
    for (int i = 0; (weight > 0.001f) && (i <= octaves); ++i) {
        weight = std::fmin(weight, 1.0f);
        const float signal = (snoise(p, dims) + offset) * pwr;
        pwr = pwr * roughness;
        value = value + weight * signal;
        weight = weight * (gain * signal);
        scale_point(p, dims, lacunarity);
    }
    const float rmd = detail - std::floor(detail);
    if ((rmd != 0.0f) && (weight > 0.001f)) {
        weight = std::fmin(weight, 1.0f);
        const float signal = (snoise(p, dims) + offset) * pwr;
        value = value + rmd * weight * signal;
    }
    return value;
}

float ridged_multi_fractal(float* p, int dims, float detail, float roughness, float lacunarity, float offset,
                           float gain) {
    float pwr = roughness;
    float signal = offset - std::fabs(snoise(p, dims));
    signal = signal * signal;
    float value = signal, weight = 1.0f;
    const int octaves = int(std::floor(detail));
    for (int i = 1; i <= octaves; ++i) {
        scale_point(p, dims, lacunarity);
        weight = svm::clamp(signal * gain, 0.0f, 1.0f);
        signal = offset - std::fabs(snoise(p, dims));
        signal = signal * signal;
        signal = signal * weight;
        value = value + signal * pwr;
        pwr = pwr * roughness;
    }
    return value;
}

// Cycles' noise_select: the texture's type at point p (dims), offset by off (dims) first.
float noise_select(const float* p, const float* off, int dims, int type, float detail, float roughness,
                   float lacunarity, float offset, float gain, bool normalize) {
    float q[3];
    for (int a = 0; a < dims; ++a) q[a] = off ? p[a] + off[a] : p[a];
    switch (type) {
        case NOISE_FBM: return fbm(q, dims, detail, roughness, lacunarity, normalize);
        case NOISE_MULTIFRACTAL: return multi_fractal(q, dims, detail, roughness, lacunarity);
        case NOISE_HYBRID_MULTIFRACTAL: return hybrid_multi_fractal(q, dims, detail, roughness, lacunarity, offset, gain);
        case NOISE_RIDGED_MULTIFRACTAL: return ridged_multi_fractal(q, dims, detail, roughness, lacunarity, offset, gain);
        default: return hetero_terrain(q, dims, detail, roughness, lacunarity, offset);
    }
}

inline float at(const float* a, size_t count, size_t i) { return a[count == 1 ? 0 : i]; }

}  // namespace

void noise_texture(const float* p, size_t n, int dims, const NoiseParams& k, float* fac, float* color) {
    float offsets[5][3];    // seeds 0..dims-1: distortion; dims, dims + 1: the colour's channels
    for (int seed = 0; seed < 5; ++seed)
        for (int a = 0; a < 3; ++a) offsets[seed][a] = random_offset(float(seed), a);
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float scale = at(k.scale, k.scale_n, i);
            const float detail = svm::clamp(at(k.detail, k.detail_n, i), 0.0f, 15.0f);   // NaN: one octave
            const float rough = svm::max(at(k.roughness, k.roughness_n, i), 0.0f);
            const float lac = at(k.lacunarity, k.lacunarity_n, i);
            const float dist = at(k.distortion, k.distortion_n, i);
            float q[3];
            for (int a = 0; a < dims; ++a) q[a] = p[i * size_t(dims) + a] * scale;
            if (dist != 0.0f) {
                float shift[3], s[3];
                for (int c = 0; c < dims; ++c) {
                    for (int a = 0; a < dims; ++a) s[a] = q[a] + offsets[c][a];
                    shift[c] = snoise(s, dims);
                }
                for (int a = 0; a < dims; ++a) q[a] = q[a] + shift[a] * dist;
            }
            const float offset = at(k.offset, k.offset_n, i), gain = at(k.gain, k.gain_n, i);
            const float value = noise_select(q, nullptr, dims, k.type, detail, rough, lac, offset, gain, k.normalize);
            fac[i] = value;
            if (color) {
                color[3 * i] = value;
                for (int c = 1; c < 3; ++c)
                    color[3 * i + c] = noise_select(q, offsets[dims + c - 1], dims, k.type, detail, rough, lac, offset,
                                                    gain, k.normalize);
            }
        }
    }, size_t(1) << 12);
}

}  // namespace dacrt
