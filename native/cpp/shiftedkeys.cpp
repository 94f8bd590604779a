// The overlap check's second plane-key grid (coplanar.h): coplanar_key's float32 expressions,
// in the same order, on the grid shifted by half a bin in every component, for the candidates
// only. Twins whose plane offsets float32 rounding puts on either side of a bin's edge share
// a key here; the add-on had written this as a numpy twin of the expressions (~4 ms a dragon
// frame in temporaries, against a fraction of a millisecond in one threaded pass).
#include <cstdint>

#include "coplanar.h"
#include "parallel.h"

namespace dacrt {

void shifted_plane_keys(const float* geo, size_t M, const uint8_t* candidates, float inv_step, uint64_t* out) {
    parallel_for(M, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            if (!candidates[i]) {
                out[i] = 0;
                continue;
            }
            const float x = geo[9 * M + i], y = geo[10 * M + i], z = geo[11 * M + i];
            const float s = kCoplanarSign[0] * x + kCoplanarSign[1] * y + kCoplanarSign[2] * z;
            const float sign = s < 0.0f ? -1.0f : 1.0f;
            const float n[3] = {x * sign, y * sign, z * sign};
            const float d = geo[i] * n[0] + geo[M + i] * n[1] + geo[2 * M + i] * n[2];
            const float half = kCoplanarBins + 1.0f;  // (4096.5 + 0.5: the shifted grid)
            const float v[4] = {n[0] * kCoplanarBins + half, n[1] * kCoplanarBins + half,
                                n[2] * kCoplanarBins + half, d * inv_step + 2097153.0f};
            const float top[4] = {16384.0f, 16384.0f, 16384.0f, 4194304.0f};
            const int width[4] = {14, 14, 14, 22};
            // (one component out of range, or a NaN, leaves the whole key 0: keyless, so such a
            // triangle joins no group of this grid)
            uint64_t key = 0;
            bool ok = true;
            for (int c = 0; c < 4; ++c) {
                ok &= v[c] >= 0.0f && v[c] < top[c];
                key = key << width[c] | (ok ? uint64_t(uint32_t(int32_t(v[c]))) : 0);
            }
            out[i] = ok ? key : 0;
        }
    });
}

}  // namespace dacrt
