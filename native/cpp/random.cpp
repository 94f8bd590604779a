// Batched sample words (random.h mix_words) for the shading kernels. The hash chain is ~150
// integer operations per pair and vectorises well, so it is compiled once per instruction set
// (GCC target_clones; the dynamic loader picks the widest the CPU has: 4x over scalar code on
// AVX2/AVX-512). Integer arithmetic only: every ISA gives the same bits.
#include "random.h"

namespace dacrt {

__attribute__((target_clones("avx512f", "avx2", "default")))
void sample_words(const uint32_t* pixel, const uint32_t* sample, size_t n, uint32_t ka, uint32_t kb, uint32_t* a,
                  uint32_t* b) {
    for (size_t i = 0; i < n; ++i) {
        const Words w = mix_words(pixel[i], sample[i], ka, kb);
        a[i] = w.a;
        b[i] = w.b;
    }
}

}  // namespace dacrt
