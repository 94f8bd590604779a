// Per-point image lookups (imagepoints.h). The coordinate arithmetic (each axis' texel taps and
// weights, the Box weights) runs as lane loops over blocks of points, compiled per instruction
// set (target_clones); the texel reads after them are gathers. Compiled with -fno-trapping-math
// (CMakeLists.txt) so the selects vectorise; -ffp-contract=off and IEEE operations only, so
// every clone gives the same values, and numpy's (NaN payloads aside: built with each clone
// forced, 1.6 GB of lookups on special and random inputs compared equal but for NaN bits).
#include "imagepoints.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.h"

namespace dacrt {

namespace {

constexpr size_t kBlock = 256;
constexpr int kMaxTaps = 4;

inline int taps_of(int interp) { return interp == TEXEL_CLOSEST ? 1 : interp == TEXEL_LINEAR ? 2 : 4; }

// numpy's float -> int64 cast on x86-64 (cvttss2si): NaN and out of range give INT64_MIN, which
// the extension then wraps as any index (a NaN UV reads some texel, as numpy's lookup did)
inline int64_t to_index(float f) {
    return (f >= -0x1p63f && f < 0x1p63f) ? int64_t(f) : std::numeric_limits<int64_t>::min();
}

// np.mod of an int64 by m > 0 (the remainder takes m's sign)
inline int64_t floor_mod(int64_t i, int64_t m) {
    const int64_t r = i % m;
    return r < 0 ? r + m : r;
}

// texture._wrap: the index in [0, size) of index i, and whether that texel is inside (Clip)
inline int64_t wrap(int64_t i, int64_t size, int ext, uint8_t& inside) {
    switch (ext) {
    case TEXEL_REPEAT: return floor_mod(i, size);
    case TEXEL_MIRROR: {
        const int64_t m = floor_mod(i, 2 * size);
        return m < size ? m : 2 * size - 1 - m;
    }
    case TEXEL_CLIP: inside = uint8_t(i >= 0 && i < size); [[fallthrough]];
    default: return i < 0 ? 0 : i > size - 1 ? size - 1 : i;
    }
}

// The taps of m coordinates s along an axis of `size` texels, taps_of(interp) a point: index,
// weight, inside. As _blend_texels: x = s size (less 0.5 when blended), the texels from its
// floor on, weights 1 - f, f (Linear) or the uniform cubic B-spline's at f (Cubic,
// _bspline_weights); the first tap's index wraps around int64 as numpy's does.
__attribute__((target_clones("avx512f", "avx2", "default")))
void axis_taps(const float* __restrict s, size_t m, int64_t size, int interp, int ext, int64_t* __restrict idx,
               float* __restrict wgt, uint8_t* __restrict in) {
    const float fs = float(size);
    const int K = taps_of(interp);
    const int64_t first = interp == TEXEL_CUBIC ? -1 : 0;
    const float sixth = float(1.0 / 6.0), half = 0.5f, two_thirds = float(2.0 / 3.0);
    for (size_t j = 0; j < m; ++j) {
        float x = s[j] * fs;
        if (interp != TEXEL_CLOSEST) x = x - 0.5f;
        const float f = std::floor(x);
        const float t = x - f;
        const int64_t i0 = to_index(f);
        float w[kMaxTaps] = {1.0f, 0.0f, 0.0f, 0.0f};
        if (interp == TEXEL_LINEAR) {
            w[0] = 1.0f - t;
            w[1] = t;
        } else if (interp == TEXEL_CUBIC) {
            w[0] = ((-sixth * t + half) * t - half) * t + sixth;
            w[1] = ((half * t - 1.0f) * t) * t + two_thirds;
            w[2] = ((-half * t + half) * t + half) * t + sixth;
            w[3] = sixth * t * t * t;
        }
        const size_t o = j * size_t(K);
        for (int k = 0; k < K; ++k) wgt[o + size_t(k)] = w[k];
        if ((ext == TEXEL_REPEAT || ext == TEXEL_MIRROR) && i0 != std::numeric_limits<int64_t>::min()) {
            // one division a point: the next tap's remainder is the last one's + 1, wrapped
            // (no tap index overflows but INT64_MIN's, which takes the general path)
            const int64_t period = ext == TEXEL_REPEAT ? size : 2 * size;
            int64_t r = floor_mod(i0 + first, period);
            for (int k = 0; k < K; ++k) {
                idx[o + size_t(k)] = r < size ? r : period - 1 - r;
                in[o + size_t(k)] = 1;
                r = r + 1 == period ? 0 : r + 1;
            }
            continue;
        }
        for (int k = 0; k < K; ++k) {
            uint8_t inside = 1;
            idx[o + size_t(k)] = wrap(int64_t(uint64_t(i0) + uint64_t(first + k)), size, ext, inside);
            in[o + size_t(k)] = inside;
        }
    }
}

// One block's taps along both axes.
struct Taps {
    int64_t ix[kBlock * kMaxTaps], iy[kBlock * kMaxTaps];
    float wx[kBlock * kMaxTaps], wy[kBlock * kMaxTaps];
    uint8_t inx[kBlock * kMaxTaps], iny[kBlock * kMaxTaps];

    void find(const TexelImage& t, const float* u, const float* v, size_t m) {
        axis_taps(u, m, t.w, t.interp, t.ext, ix, wx, inx);
        axis_taps(v, m, t.h, t.interp, t.ext, iy, wy, iny);
    }
};

// The m points' blended channels into out[c * stride + j], in _blend_texels' order: rows of
// taps outer, columns inner, out += texel x (wx wy [x inside]); Closest: the texel [x inside].
template <class T>
void gather(const TexelImage& t, const Taps& a, size_t m, float* out, size_t stride) {
    const T* p = static_cast<const T*>(t.data) + t.c0 * t.sc;
    const int K = taps_of(t.interp), nc = t.c1 - t.c0;
    const bool clip = t.ext == TEXEL_CLIP;
    for (size_t j = 0; j < m; ++j) {
        float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        if (t.interp == TEXEL_CLOSEST) {
            const T* q = p + a.iy[j] * t.sy + a.ix[j] * t.sx;
            const float inside = float(a.inx[j] & a.iny[j]);
            for (int c = 0; c < nc; ++c) {
                acc[c] = float(q[c * t.sc]);
                if (clip) acc[c] = acc[c] * inside;
            }
        } else {
            const size_t o = j * size_t(K);
            for (int b = 0; b < K; ++b) {
                const T* row = p + a.iy[o + size_t(b)] * t.sy;
                for (int k = 0; k < K; ++k) {
                    float w = a.wx[o + size_t(k)] * a.wy[o + size_t(b)];
                    if (clip) w = w * float(a.inx[o + size_t(k)] & a.iny[o + size_t(b)]);
                    const T* q = row + a.ix[o + size_t(k)] * t.sx;
                    for (int c = 0; c < nc; ++c) acc[c] = acc[c] + float(q[c * t.sc]) * w;
                }
            }
        }
        for (int c = 0; c < nc; ++c) out[size_t(c) * stride + j] = acc[c];
    }
}

void blend_block(const TexelImage& t, Taps& a, const float* u, const float* v, size_t m, float* out,
                 size_t stride) {
    a.find(t, u, v, m);
    if (t.bytes)
        gather<uint8_t>(t, a, m, out, stride);
    else
        gather<float>(t, a, m, out, stride);
}

// texture.srgb_to_linear (Cycles' color_srgb_to_linear) with libm's powf: numpy's float32 power
// is SVML's on AVX-512 machines, within 1 ulp of it, so this is within an ulp of numpy there
// (and libm's own elsewhere); np.maximum's NaN is kept
inline float nan_max0(float v) { return v != v ? v : v > 0.0f ? v : 0.0f; }

inline float srgb_to_linear(float c) {
    const float hi = std::pow(nan_max0(c + 0.055f) * float(1.0 / 1.055), 2.4f);
    return c < 0.04045f ? nan_max0(c * float(1.0 / 12.92)) : hi;
}

inline float clip_unit(float v) {  // np.clip(v, 0, 1): NaN kept, -0 to +0 (max(v, 0) then min)
    const float r = v > 0.0f ? v : 0.0f;
    const float c = r < 1.0f ? r : 1.0f;
    return v != v ? v : c;
}

// _box_weights at m normals nrm (m x 3) into w (m x 3): the normal's axis shares; one axis
// alone near it, two or three blended between by Blend (0: the largest axis alone, as Cycles'
// "desperate mode" where none is), in _box_weights' order of cases and operations.
__attribute__((target_clones("avx512f", "avx2", "default")))
void box_weights(const float* __restrict nrm, size_t m, float blend, float* __restrict w) {
    const float limit = 0.5f * (1.0f + blend);
    const float lo = 0.5f * (1.0f - blend), one = 1.0f - limit, d = 2.0f * limit - 1.0f;
    const bool blended = blend > 0.0f;
    for (size_t j = 0; j < m; ++j) {
        const float ax = std::fabs(nrm[3 * j]), ay = std::fabs(nrm[3 * j + 1]), az = std::fabs(nrm[3 * j + 2]);
        const float s = ax + ay + az;
        const float x = ax / s, y = ay / s, z = az / s;
        // every case's weights computed, one chosen: selects, not branches (a normal's case
        // is a coin toss along a curved surface's points, which branches mispredicted)
        const bool on_x = (x > limit * (x + y)) & (x > limit * (x + z));
        const bool on_y = (y > limit * (x + y)) & (y > limit * (y + z));
        const bool on_z = (z > limit * (x + z)) & (z > limit * (y + z));
        const bool xy = z < one * (y + x), yz = x < one * (y + z), xz = y < one * (x + z);
        const float qxy = clip_unit((x / (x + y) - lo) / blend), qyz = clip_unit((y / (y + z) - lo) / blend);
        const float qxz = clip_unit((x / (x + z) - lo) / blend);
        const float dx = ((2.0f - limit) * x + (limit - 1.0f)) / d, dy = ((2.0f - limit) * y + (limit - 1.0f)) / d;
        const float dz = ((2.0f - limit) * z + (limit - 1.0f)) / d;
        float wx = dx, wy = dy, wz = dz;      // the cases from the last to the first
        auto take = [&](bool c, float a, float b, float e) {
            wx = c ? a : wx;
            wy = c ? b : wy;
            wz = c ? e : wz;
        };
        take(xz, qxz, 0.0f, 1.0f - qxz);
        take(yz, 0.0f, qyz, 1.0f - qyz);
        take(xy, qxy, 1.0f - qxy, 0.0f);
        take(!blended, 1.0f, 0.0f, 0.0f);
        take(on_z, 0.0f, 0.0f, 1.0f);
        take(on_y, 0.0f, 1.0f, 0.0f);
        take(on_x, 1.0f, 0.0f, 0.0f);
        w[3 * j] = wx;
        w[3 * j + 1] = wy;
        w[3 * j + 2] = wz;
    }
}

}  // namespace

void texel_blend(const TexelImage& t, const float* u, const float* v, size_t n, float* out) {
    parallel_for(n, [&](size_t b, size_t e) {
        Taps a;
        for (size_t s = b; s < e; s += kBlock)
            blend_block(t, a, u + s, v + s, std::min(kBlock, e - s), out + s, n);
    }, size_t(1) << 12);
}

void box_lookup(const TexelImage& t, const float* co, const float* normal, size_t n, float blend, float scale,
                bool srgb, bool combine, float* weights, float* out) {
    const size_t nc = size_t(t.c1 - t.c0);
    parallel_for(n, [&](size_t b, size_t e) {
        if (combine) std::fill(out + b * nc, out + e * nc, 0.0f);     // (zeroed by each thread)
        Taps a;
        float pu[kBlock], pv[kBlock], raw[4 * kBlock];
        uint32_t sel[kBlock];
        for (size_t s = b; s < e; s += kBlock) {
            const size_t m = std::min(kBlock, e - s);
            float* w = weights + 3 * s;
            box_weights(normal + 3 * s, m, blend, w);
            for (int p = 0; p < 3; ++p) {
                // the plane's points (weight > 0: Cycles skips the others), each axis flipped
                // by the normal's sign so no side reads mirrored, as _box_lookup's planes
                size_t k = 0;
                for (size_t j = 0; j < m; ++j) {
                    if (!(w[3 * j + size_t(p)] > 0.0f)) {
                        if (!combine)
                            for (size_t c = 0; c < nc; ++c) out[(size_t(p) * nc + c) * n + s + j] = 0.0f;
                        continue;
                    }
                    const float* c = co + 3 * (s + j);
                    const float* nr = normal + 3 * (s + j);
                    sel[k] = uint32_t(j);
                    if (p == 0) pu[k] = nr[0] < 0.0f ? 1.0f - c[1] : c[1], pv[k] = c[2];
                    else if (p == 1) pu[k] = nr[1] > 0.0f ? 1.0f - c[0] : c[0], pv[k] = c[2];
                    else pu[k] = nr[2] > 0.0f ? 1.0f - c[1] : c[1], pv[k] = c[0];
                    ++k;
                }
                if (!k) continue;
                blend_block(t, a, pu, pv, k, raw, kBlock);
                for (size_t q = 0; q < k; ++q) {
                    const size_t i = s + sel[q];
                    if (combine) {
                        const float wp = w[3 * size_t(sel[q]) + size_t(p)];
                        for (size_t c = 0; c < nc; ++c) {
                            float r = raw[c * kBlock + q] * scale;
                            if (srgb && t.c0 + int(c) < 3) r = srgb_to_linear(r);
                            out[i * nc + c] = out[i * nc + c] + wp * r;
                        }
                    } else {
                        for (size_t c = 0; c < nc; ++c) out[(size_t(p) * nc + c) * n + i] = raw[c * kBlock + q];
                    }
                }
            }
        }
    }, size_t(1) << 12);
}

}  // namespace dacrt
