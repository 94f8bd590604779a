// 8-bit image texels back to bytes and to scene-linear floats (see texels.h).
#include "texels.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "parallel.h"

namespace dacrt {

namespace {

inline uint8_t to_byte(float v) {
    // as numpy's rint(v * 255).astype(uint8) for v in [0, 1] (float32 product, ties to even);
    // NaN and out-of-range values clamp (a byte image has none). Rounded by adding and
    // subtracting 2^23 (exact ties-to-even for 0 <= x < 2^23 in the default rounding mode):
    // std::nearbyint is a libm call on the baseline x86-64 build (no SSE4.1 round), which
    // had made this pass slower than numpy's (a 1K image: 27 ms per megatexel).
    const float x = v * 255.0f;
    if (!(x >= 0.0f)) return 0;
    if (x >= 255.0f) return 255;
    return uint8_t((x + 0x1p23f) - 0x1p23f);
}

inline uint8_t associated(uint8_t c, uint8_t a) {
    const uint32_t p = uint32_t(c) * a;          // c a / 255 rounded down, without a division
    return uint8_t((p + 1 + (p >> 8)) >> 8);
}

// One texel's channels as RGBA: grey and alpha expanded (one: grey; two: grey, alpha; three:
// alpha `one`).
template <class T>
inline void expand(const T* s, int ch, T one, T v[4]) {
    if (ch >= 3) {
        v[0] = s[0], v[1] = s[1], v[2] = s[2];
        v[3] = ch == 4 ? s[3] : one;
    } else {
        v[0] = v[1] = v[2] = s[0];
        v[3] = ch == 2 ? s[1] : one;
    }
}

inline void store_bytes(const uint8_t k[4], size_t i, uint8_t* k8, uint8_t* k8_assoc) {
    for (int c = 0; c < 4; ++c) k8[4 * i + size_t(c)] = k[c];
    if (k8_assoc) {
        for (int c = 0; c < 3; ++c) k8_assoc[4 * i + size_t(c)] = associated(k[c], k[3]);
        k8_assoc[4 * i + 3] = k[3];
    }
}

}  // namespace

bool byte_texels(const float* buf, size_t n, int ch, const float* byte_floats, float* rgba, uint8_t* k8,
                 uint8_t* k8_assoc) {
    std::atomic<bool> exact{true};
    parallel_for(n, [&](size_t b, size_t e) {
        bool same = true;
        for (size_t i = b; i < e; ++i) {
            float v[4];
            expand(buf + i * size_t(ch), ch, 1.0f, v);
            uint8_t k[4];
            for (int c = 0; c < 4; ++c) {
                if (rgba) rgba[4 * i + size_t(c)] = v[c];
                k[c] = to_byte(v[c]);
            }
            for (int c = 0; c < 3; ++c) same &= v[c] == byte_floats[k[c]];
            store_bytes(k, i, k8, k8_assoc);
        }
        if (!same) exact.store(false, std::memory_order_relaxed);
    }, size_t(1) << 16);
    return exact.load();
}

void byte_texels(const uint8_t* buf, size_t n, int ch, const float* byte_floats, float* rgba, uint8_t* k8,
                 uint8_t* k8_assoc) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            uint8_t k[4];
            expand(buf + i * size_t(ch), ch, uint8_t(255), k);
            if (rgba)
                for (int c = 0; c < 4; ++c) rgba[4 * i + size_t(c)] = byte_floats[k[c]];
            store_bytes(k, i, k8, k8_assoc);
        }
    }, size_t(1) << 16);
}

void byte_lookup(const uint8_t* k8, size_t n, const float* table, float* rgba) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i)
            for (int c = 0; c < 3; ++c) rgba[4 * i + size_t(c)] = table[k8[4 * i + size_t(c)]];
    }, size_t(1) << 16);
}

}  // namespace dacrt
