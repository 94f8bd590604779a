// Random numbers of the path tracer, the native twin of addon/sampling.py's RandomStream
// (bit-identical: tests compare them). Randomised quasi-Monte Carlo as Cycles' default sampler:
// each dimension pair of a pixel is a 2D Sobol (0,2)-sequence, Owen-scrambled and shuffled by
// hash (Burley 2020, "Practical Hash-based Owen Scrambling"), so a pixel's first N samples of
// every pair are stratified in both dimensions at once, independently of the other pairs.
// A path's key is (pixel seed, sample index); a pair is named by two dimension words (ka, kb).
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

inline uint32_t fmix32(uint32_t x) {  // murmur3 finaliser: a bijection of 32-bit words
    x ^= x >> 16;
    x *= 0x85EBCA6Bu;
    x ^= x >> 13;
    x *= 0xC2B2AE35u;
    x ^= x >> 16;
    return x;
}

inline uint32_t reverse_bits(uint32_t x) {
    x = __builtin_bswap32(x);  // bytes, then the bits inside each byte
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
}

// Laine-Karras permutation as improved by Burley: each bit is flipped by a hash of the bits
// below it (in bit-reversed order: above it), an Owen scramble of the reversed word.
inline uint32_t laine_karras(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6C50B47Cu;
    x ^= x * 0xB82F1E52u;
    x ^= x * 0xC7AFE638u;
    x ^= x * 0x8D22F6E6u;
    return x;
}

inline uint32_t owen_scramble(uint32_t x, uint32_t seed) {
    return reverse_bits(laine_karras(reverse_bits(x), seed));
}

// Second Sobol dimension (primitive polynomial x + 1), bit-reversed. Its generator matrix is
// Pascal's triangle mod 2: by Lucas' theorem output bit i (from the top) is the XOR of the index
// bits j with i a subset of j, a superset-XOR transform in five branch-free steps (the textbook
// loop over set bits mispredicts on shuffled indices and cannot be vectorised).
inline uint32_t sobol1_reversed(uint32_t index) {
    index ^= (index >> 1) & 0x55555555u;
    index ^= (index >> 2) & 0x33333333u;
    index ^= (index >> 4) & 0x0F0F0F0Fu;
    index ^= (index >> 8) & 0x00FF00FFu;
    index ^= (index >> 16) & 0x0000FFFFu;
    return index;
}

inline uint32_t sobol1(uint32_t index) { return reverse_bits(sobol1_reversed(index)); }

struct Words {
    uint32_t a, b;
};

// The two 32-bit sample words of dimension pair (ka, kb) for sample `sample` of the pixel with
// seed `pixel`: j = owen(sample), a = owen(reverse(j)), b = owen(sobol1(j)), with the reversals
// that cancel (owen(x) = reverse(laine_karras(reverse(x)))) left out.
inline Words mix_words(uint32_t pixel, uint32_t sample, uint32_t ka, uint32_t kb) {
    const uint32_t seed = fmix32(fmix32(pixel ^ ka) ^ kb);        // per pixel and pair
    const uint32_t j = owen_scramble(sample, seed);               // shuffled sample order
    return {reverse_bits(laine_karras(j, fmix32(seed ^ 0x9E3779B9u))),
            reverse_bits(laine_karras(sobol1_reversed(j), fmix32(seed ^ 0x7F4A7C15u)))};
}

// A sample word as a uniform in [0, 1) with 24-bit resolution (exact in float32).
inline float unit24(uint32_t word) { return float(word >> 8) * (1.0f / float(1 << 24)); }

// The two sample words of dimension pair (ka, kb) for paths (pixel[i], sample[i]) (mix_words),
// compiled per instruction set (random.cpp).
void sample_words(const uint32_t* pixel, const uint32_t* sample, size_t n, uint32_t ka, uint32_t kb, uint32_t* a,
                  uint32_t* b);

// body(i0, count, a, b) for consecutive chunks of paths [begin, end) with their sample words;
// keys: rows pixel seed, sample index (stride n). Chunks of 512 words stay in L1 and vectorise.
constexpr size_t kWordChunk = 512;
template <class F>
void for_words(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, size_t begin, size_t end, F&& body) {
    constexpr size_t kChunk = kWordChunk;
    uint32_t a[kChunk], b[kChunk];
    for (size_t i0 = begin; i0 < end; i0 += kChunk) {
        const size_t m = kChunk < end - i0 ? kChunk : end - i0;
        sample_words(keys + i0, keys + n + i0, m, ka, kb, a, b);
        body(i0, m, a, b);
    }
}

// The 32-bit pixel seed of `pixel` for the 64-bit seed words k0, k1 (splitmix64, folded).
inline uint32_t pixel_seed(uint64_t pixel, uint64_t k0, uint64_t k1) {
    auto mix64 = [](uint64_t x) {
        x ^= x >> 30;
        x *= 0xBF58476D1CE4E5B9ull;
        x ^= x >> 27;
        x *= 0x94D049BB133111EBull;
        x ^= x >> 31;
        return x;
    };
    const uint64_t key = mix64(mix64(pixel ^ k0) + k1);
    return uint32_t(key ^ (key >> 32));
}

}  // namespace dacrt
