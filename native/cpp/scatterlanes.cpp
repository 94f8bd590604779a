// cosine_scatter's lane loop (scatterlanes.h). Compiled with -fno-trapping-math
// (CMakeLists.txt): with traps kept as side effects GCC leaves malley()'s selects (its quadrant
// rotation, the basis sign) as branches and only the AVX-512 clone vectorised; the AVX2 and
// portable clones ran one path at a time. The values are IEEE's either way (and
// -ffp-contract=off: no clone fuses a multiply-add), so every clone gives the same bits.
#include "scatterlanes.h"

#include "pathvertex.h"
#include "random.h"

namespace dacrt {

__attribute__((target_clones("avx512f", "avx2", "default")))
void scatter_lanes(const uint32_t* __restrict wa, const uint32_t* __restrict wb, size_t m,
                   const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
                   const float* __restrict gx, const float* __restrict gy, const float* __restrict gz,
                   float* __restrict wx, float* __restrict wy, float* __restrict wz, float* __restrict pdf,
                   uint8_t* __restrict ok) {
    for (size_t j = 0; j < m; ++j) {
        const float n[3] = {nx[j], ny[j], nz[j]};
        float w[3];
        pdf[j] = malley(unit24(wa[j]), unit24(wb[j]), n, w);
        wx[j] = w[0];
        wy[j] = w[1];
        wz[j] = w[2];
    }
    if (gx) {  // and above the geometric surface
        for (size_t j = 0; j < m; ++j) {
            const float c = wx[j] * gx[j] + wy[j] * gy[j] + wz[j] * gz[j];
            ok[j] = uint8_t(int(pdf[j] > 0.0f) & int(c > 0.0f));
        }
    } else {
        for (size_t j = 0; j < m; ++j) ok[j] = uint8_t(pdf[j] > 0.0f);  // grazing: cos = 0
    }
}

}  // namespace dacrt
