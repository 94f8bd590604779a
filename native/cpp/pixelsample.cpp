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
    parallel_for(n, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            // blocks are pixel-major: a pixel's seed is computed once for its run of samples
            keys[i] = i > begin && pixel[i] == pixel[i - 1] ? keys[i - 1] : pixel_seed(uint64_t(pixel[i]), k0, k1);
            keys[n + i] = uint32_t(sample[i]);
        }
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* wa, const uint32_t* wb) {
            for (size_t j = 0; j < m; ++j) {
                const int64_t p = pixel[i0 + j], x = p % width, y = p / width;
                // Cycles (integrate_camera_sample): sample 0 looks up the table at 0.5, the
                // pixel centre, so the passes written from it (depth, IDs) are not jittered
                const bool centre = sample[i0 + j] == 0;
                rx[i0 + j] = filter_offset(centre ? 0.5f : unit24(wa[j]), table, table_size) + float(x);
                ry[i0 + j] = filter_offset(centre ? 0.5f : unit24(wb[j]), table, table_size) + float(y);
            }
        });
    }, size_t(1) << 16);
}

}  // namespace dacrt
