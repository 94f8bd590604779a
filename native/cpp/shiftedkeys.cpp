// The overlap check's second plane-key grid (coplanar.h): coplanar_key's float32 expressions,
// in the same order, on the grid shifted by half a bin in every component, for the candidates
// only. Twins whose plane offsets float32 rounding puts on either side of a bin's edge share
// a key here; the add-on had written this as a numpy twin of the expressions, a dozen passes
// over temporaries.
#include <cstdint>

#include "coplanar.h"
#include "parallel.h"

namespace dacrt {

void shifted_plane_keys(const float* geo, size_t M, const uint8_t* candidates, float inv_step, uint64_t* out) {
    // (one pass over the v0 and normal rows: ~5 ns a key in cache, bound by memory beyond, ~14 ns
    // a key for 100K triangles on the loaded machine against ~27 for the numpy expressions)
    parallel_for(M, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float x = geo[9 * M + i], y = geo[10 * M + i], z = geo[11 * M + i];
            const float s = kCoplanarSign[0] * x + kCoplanarSign[1] * y + kCoplanarSign[2] * z;
            const float sign = s < 0.0f ? -1.0f : 1.0f;
            const float n0 = x * sign, n1 = y * sign, n2 = z * sign;
            const float d = geo[i] * n0 + geo[M + i] * n1 + geo[2 * M + i] * n2;
            const float half = kCoplanarBins + 1.0f;  // (4096.5 + 0.5: the shifted grid)
            const float a0 = n0 * kCoplanarBins + half, a1 = n1 * kCoplanarBins + half, a2 = n2 * kCoplanarBins + half;
            const float a3 = d * inv_step + 2097153.0f;
            // (a component out of range, or a NaN, leaves the whole key 0: keyless, so such a
            // triangle joins no group of this grid; so does a triangle that is no candidate)
            const bool ok = (candidates[i] != 0) & (a0 >= 0.0f) & (a0 < 16384.0f) & (a1 >= 0.0f) & (a1 < 16384.0f) &
                            (a2 >= 0.0f) & (a2 < 16384.0f) & (a3 >= 0.0f) & (a3 < 4194304.0f);
            auto bin = [ok](float v) { return uint64_t(uint32_t(int32_t(ok ? v : 0.0f))); };
            out[i] = bin(a0) << 50 | bin(a1) << 36 | bin(a2) << 22 | bin(a3);
        }
    });
}

}  // namespace dacrt
