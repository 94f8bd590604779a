// The film's per-pixel sums of a block of samples (see shading.h): float32 samples summed in
// double, each row on its own, in sample order. Native because the numpy spelling that is fast
// (a float64 product with a vector of ones) goes to OpenBLAS, whose idle threads then spin in
// sched_yield on the second core for a while after every call (13% of a Cornell render's CPU
// samples), and numpy's own reductions over a short last axis are 3x slower.
#include "parallel.h"
#include "shading.h"

namespace dacrt {

void sample_sums(const float* values, size_t rows, size_t samples, const double* weights, double* out) {
    parallel_for(rows, [=](size_t b, size_t e) {
        for (size_t r = b; r < e; ++r) {
            const float* v = values + r * samples;
            double s = 0.0;
            if (weights) {
                for (size_t j = 0; j < samples; ++j) s += double(v[j]) * weights[j];
            } else {
                for (size_t j = 0; j < samples; ++j) s += double(v[j]);
            }
            out[r] = s;
        }
    }, size_t(1) << 14);
}

}  // namespace dacrt
