// Bob Jenkins' lookup3 hash as Cycles' util/hash.h computes it: the mix and final mix of three
// words and a float's bits as a word. Shared by the noise and Voronoi kernels, whose cells Cycles hashes
// with it (the texture's values depend on it bit for bit).
#pragma once

#include <cstdint>
#include <cstring>

namespace dacrt {
namespace lookup3 {

inline uint32_t rot(uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }

// The mix between blocks of three words (Cycles' hash_uint4 mixes its first three).
inline void mix(uint32_t& a, uint32_t& b, uint32_t& c) {
    a -= c; a ^= rot(c, 4);  c += b;
    b -= a; b ^= rot(a, 6);  a += c;
    c -= b; c ^= rot(b, 8);  b += a;
    a -= c; a ^= rot(c, 16); c += b;
    b -= a; b ^= rot(a, 19); a += c;
    c -= b; c ^= rot(b, 4);  b += a;
}

inline uint32_t final_mix(uint32_t a, uint32_t b, uint32_t c) {
    c ^= b; c -= rot(b, 14);
    a ^= c; a -= rot(c, 11);
    b ^= a; b -= rot(a, 25);
    c ^= b; c -= rot(b, 16);
    a ^= c; a -= rot(c, 4);
    b ^= a; b -= rot(a, 14);
    c ^= b; c -= rot(b, 24);
    return c;
}

inline uint32_t float_bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

}  // namespace lookup3
}  // namespace dacrt
