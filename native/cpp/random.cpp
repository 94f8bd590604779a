// Batched sample words (random.h mix_words) for the shading kernels. The hash chain is ~150
// integer operations per pair and vectorises well, so it is compiled once per instruction set
// (GCC target_clones; the dynamic loader picks the widest the CPU has: 4x over scalar code on
// AVX2/AVX-512). Where the CPU has GFNI with AVX-512, a hand-written 16-lane version reverses
// bits with one byte shuffle and one affine transform instead of ~14 shifts and masks: a third
// of the chain was its four bit reversals. Integer arithmetic only: every path gives the same
// bits (tests/integrator compare them with addon/sampling.py).
#include "random.h"

#include <immintrin.h>

#include <strings.h>

#include <cstdlib>

namespace dacrt {

namespace {

__attribute__((target_clones("avx512f", "avx2", "default")))
void sample_words_generic(const uint32_t* pixel, const uint32_t* sample, size_t n, uint32_t ka, uint32_t kb,
                          uint32_t* a, uint32_t* b) {
    for (size_t i = 0; i < n; ++i) {
        const Words w = mix_words(pixel[i], sample[i], ka, kb);
        a[i] = w.a;
        b[i] = w.b;
    }
}

#define DACRT_GFNI __attribute__((target("avx512f,avx512bw,gfni"), always_inline)) inline

DACRT_GFNI __m512i mul(__m512i x, uint32_t c) { return _mm512_mullo_epi32(x, _mm512_set1_epi32(int(c))); }

DACRT_GFNI __m512i fmix32_v(__m512i x) {
    x = _mm512_xor_si512(x, _mm512_srli_epi32(x, 16));
    x = mul(x, 0x85EBCA6Bu);
    x = _mm512_xor_si512(x, _mm512_srli_epi32(x, 13));
    x = mul(x, 0xC2B2AE35u);
    return _mm512_xor_si512(x, _mm512_srli_epi32(x, 16));
}

DACRT_GFNI __m512i reverse_bits_v(__m512i x) {
    const __m512i bswap = _mm512_set4_epi32(0x0C0D0E0F, 0x08090A0B, 0x04050607, 0x00010203);
    x = _mm512_shuffle_epi8(x, bswap);
    return _mm512_gf2p8affine_epi64_epi8(x, _mm512_set1_epi64(0x8040201008040201ll), 0);
}

DACRT_GFNI __m512i laine_karras_v(__m512i x, __m512i seed) {
    x = _mm512_add_epi32(x, seed);
    x = _mm512_xor_si512(x, mul(x, 0x6C50B47Cu));
    x = _mm512_xor_si512(x, mul(x, 0xB82F1E52u));
    x = _mm512_xor_si512(x, mul(x, 0xC7AFE638u));
    return _mm512_xor_si512(x, mul(x, 0x8D22F6E6u));
}

DACRT_GFNI __m512i sobol1_reversed_v(__m512i x) {
    x = _mm512_xor_si512(x, _mm512_and_si512(_mm512_srli_epi32(x, 1), _mm512_set1_epi32(0x55555555)));
    x = _mm512_xor_si512(x, _mm512_and_si512(_mm512_srli_epi32(x, 2), _mm512_set1_epi32(0x33333333)));
    x = _mm512_xor_si512(x, _mm512_and_si512(_mm512_srli_epi32(x, 4), _mm512_set1_epi32(0x0F0F0F0F)));
    x = _mm512_xor_si512(x, _mm512_and_si512(_mm512_srli_epi32(x, 8), _mm512_set1_epi32(0x00FF00FF)));
    return _mm512_xor_si512(x, _mm512_and_si512(_mm512_srli_epi32(x, 16), _mm512_set1_epi32(0x0000FFFF)));
}

// mix_words, 16 paths at a time, step for step.
__attribute__((target("avx512f,avx512bw,gfni")))
void sample_words_gfni(const uint32_t* pixel, const uint32_t* sample, size_t n, uint32_t ka, uint32_t kb, uint32_t* a,
                       uint32_t* b) {
    const __m512i vka = _mm512_set1_epi32(int(ka)), vkb = _mm512_set1_epi32(int(kb));
    const __m512i ca = _mm512_set1_epi32(int(0x9E3779B9u)), cb = _mm512_set1_epi32(int(0x7F4A7C15u));
    size_t i = 0;
    for (; i + 16 <= n; i += 16) {
        const __m512i p = _mm512_loadu_si512(pixel + i), s = _mm512_loadu_si512(sample + i);
        const __m512i seed = fmix32_v(_mm512_xor_si512(fmix32_v(_mm512_xor_si512(p, vka)), vkb));
        const __m512i j = reverse_bits_v(laine_karras_v(reverse_bits_v(s), seed));
        const __m512i wa = reverse_bits_v(laine_karras_v(j, fmix32_v(_mm512_xor_si512(seed, ca))));
        const __m512i wb = reverse_bits_v(laine_karras_v(sobol1_reversed_v(j), fmix32_v(_mm512_xor_si512(seed, cb))));
        _mm512_storeu_si512(a + i, wa);
        _mm512_storeu_si512(b + i, wb);
    }
    for (; i < n; ++i) {
        const Words w = mix_words(pixel[i], sample[i], ka, kb);
        a[i] = w.a;
        b[i] = w.b;
    }
}

using WordsFn = void (*)(const uint32_t*, const uint32_t*, size_t, uint32_t, uint32_t, uint32_t*, uint32_t*);

// GFNI where the CPU has it, unless DACRT_ISA asks for a narrower instruction set (as it does
// for the tracer), which also lets the tests compare both versions on one machine.
WordsFn pick_words() {
    __builtin_cpu_init();
    const char* isa = std::getenv("DACRT_ISA");
    const bool narrower = isa && *isa && strcasecmp(isa, "avx512") != 0;
    const bool gfni = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                      __builtin_cpu_supports("gfni");
    return gfni && !narrower ? sample_words_gfni : sample_words_generic;
}

}  // namespace

void sample_words(const uint32_t* pixel, const uint32_t* sample, size_t n, uint32_t ka, uint32_t kb, uint32_t* a,
                  uint32_t* b) {
    static const WordsFn fn = pick_words();
    fn(pixel, sample, n, ka, kb, a, b);
}

}  // namespace dacrt
