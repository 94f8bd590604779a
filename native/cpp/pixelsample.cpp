// Camera samples (see shading.h): path keys, filter-distributed raster positions; the native
// twin of RandomStream.path_keys + uniform2 + PixelFilter.offsets in the add-on (bit-identical,
// tested).
#include <algorithm>

#include "parallel.h"
#include "random.h"
#include "shading.h"

namespace dacrt {

namespace {

inline float filter_offset(float u, const float* table, size_t size) {
    float x = std::min(std::max(u, 0.0f), 1.0f) * float(size - 1);
    int i = int(x);
    i = std::min(i, int(size) - 2);
    x -= float(i);
    const float slope = table[i + 1] - table[i];
    return table[i] + x * slope;
}

}  // namespace

void pixel_samples(const int64_t* pixel, const int64_t* sample, size_t n, int64_t width, uint64_t k0, uint64_t k1,
                   uint32_t ka, uint32_t kb, const float* table, size_t table_size, uint32_t* keys, float* rx,
                   float* ry) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const uint32_t seed = pixel_seed(uint64_t(pixel[i]), k0, k1);
            const uint32_t s = uint32_t(sample[i]);
            keys[i] = seed;
            keys[n + i] = s;
            const Uniform2 u = uniform2(seed, s, ka, kb);
            const int64_t x = pixel[i] % width, y = pixel[i] / width;
            float fx = filter_offset(u.u1, table, table_size);
            float fy = filter_offset(u.u2, table, table_size);
            rx[i] = fx + float(x);
            ry[i] = fy + float(y);
        }
    }, size_t(1) << 16);
}

}  // namespace dacrt
