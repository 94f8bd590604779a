// Counter-based random numbers of the path tracer, the native twin of addon/sampling.py's
// RandomStream (bit-identical: tests compare them). A path's key is two 32-bit words; a
// dimension pair mixes them with two per-dimension words (ka, kb) by murmur3 finalisers.
#pragma once

#include <cstdint>

namespace dacrt {

inline uint32_t fmix32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x85EBCA6Bu;
    x ^= x >> 13;
    x *= 0xC2B2AE35u;
    x ^= x >> 16;
    return x;
}

struct Words {
    uint32_t a, b;
};

inline Words mix_words(uint32_t k0, uint32_t k1, uint32_t ka, uint32_t kb) {
    uint32_t a = fmix32(k1 ^ ka);
    a = fmix32(a ^ k0);
    return {a, fmix32(a ^ kb)};
}

struct Uniform2 {
    float u1, u2;
};

// Two uniforms in [0, 1) (24-bit resolution) for key words (k0, k1) and dimension words (ka, kb).
inline Uniform2 uniform2(uint32_t k0, uint32_t k1, uint32_t ka, uint32_t kb) {
    const Words w = mix_words(k0, k1, ka, kb);
    const float inv24 = 1.0f / float(1 << 24);
    return {float(w.a >> 8) * inv24, float(w.b >> 8) * inv24};
}

}  // namespace dacrt
