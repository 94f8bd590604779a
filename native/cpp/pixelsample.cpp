// Camera samples (see shading.h): path keys, filter-distributed raster positions; the native
// twin of RandomStream.path_keys + uniform2 + PixelFilter.offsets in the add-on (bit-identical,
// tested).
#include <algorithm>
#include <cstdint>

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

// The keys and positions of paths [begin, end); at(i, p, s) sets path i's pixel p and sample s.
// The seed is computed once per run of a pixel's samples (blocks are pixel-major).
template <class At>
void samples_range(At&& at, size_t n, int64_t width, uint64_t k0, uint64_t k1, uint32_t ka, uint32_t kb,
                   const float* table, size_t table_size, uint32_t* keys, float* rx, float* ry, size_t begin,
                   size_t end) {
    int64_t last = -1;
    uint32_t seed = 0;
    for (size_t i = begin; i < end; ++i) {
        int64_t p, s;
        at(i, p, s);
        if (p != last) seed = pixel_seed(uint64_t(p), k0, k1);
        last = p;
        keys[i] = seed;
        keys[n + i] = uint32_t(s);
    }
    for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* wa, const uint32_t* wb) {
        for (size_t j = 0; j < m; ++j) {
            int64_t p, s;
            at(i0 + j, p, s);
            const int64_t x = p % width, y = p / width;
            // Cycles (integrate_camera_sample): sample 0 looks up the table at 0.5, the
            // pixel centre, so the passes written from it (depth, IDs) are not jittered
            const bool centre = s == 0;
            rx[i0 + j] = filter_offset(centre ? 0.5f : unit24(wa[j]), table, table_size) + float(x);
            ry[i0 + j] = filter_offset(centre ? 0.5f : unit24(wb[j]), table, table_size) + float(y);
        }
    });
}

}  // namespace

void pixel_samples(const int64_t* pixel, const int64_t* sample, size_t n, int64_t width, uint64_t k0, uint64_t k1,
                   uint32_t ka, uint32_t kb, const float* table, size_t table_size, uint32_t* keys, float* rx,
                   float* ry) {
    parallel_for(n, [&](size_t begin, size_t end) {
        samples_range([&](size_t i, int64_t& p, int64_t& s) { p = pixel[i], s = sample[i]; }, n, width, k0, k1, ka,
                      kb, table, table_size, keys, rx, ry, begin, end);
    }, size_t(1) << 16);
}

void block_samples(const int64_t* pixels, size_t npix, int64_t s0, size_t ns, int64_t width, uint64_t k0,
                   uint64_t k1, uint32_t ka, uint32_t kb, const float* table, size_t table_size, uint32_t* keys,
                   float* rx, float* ry) {
    const size_t n = npix * ns;
    // path i is pixel i / ns's sample s0 + i % ns: both loops go by runs of one pixel's samples
    // (one division per range or chunk), the pixel's seed, column and row once per run. Through
    // a per-path callback (samples_range's, as pixel_samples has it) the positions' loop had
    // cost ~3x the sample words it reads (a Cornell 256 spp render's 4.9M camera samples: ~20
    // ns a path against uniform2's ~5)
    parallel_for(n, [&](size_t begin, size_t end) {
        for (size_t i = begin, q = begin / ns, r = begin % ns; i < end; r = 0, ++q) {
            const size_t run = std::min(end - i, ns - r);
            const uint32_t seed = pixel_seed(uint64_t(pixels[q]), k0, k1);
            for (size_t t = 0; t < run; ++t) {
                keys[i + t] = seed;
                keys[n + i + t] = uint32_t(s0 + int64_t(r + t));
            }
            i += run;
        }
        for_words(keys, n, ka, kb, begin, end, [&](size_t i0, size_t m, const uint32_t* wa, const uint32_t* wb) {
            const float* const tab = table;  // (locals: the float stores below may alias none of them)
            const size_t size = table_size;
            float* const X = rx + i0;
            float* const Y = ry + i0;
            for (size_t j = 0, q = i0 / ns, r = i0 % ns; j < m; r = 0, ++q) {
                const size_t run = std::min(m - j, ns - r);
                const int64_t p = pixels[q];
                const float x = float(p % width), y = float(p / width);
                for (size_t t = j; t < j + run; ++t) {
                    X[t] = filter_offset(unit24(wa[t]), tab, size) + x;
                    Y[t] = filter_offset(unit24(wb[t]), tab, size) + y;
                }
                // Cycles (integrate_camera_sample): sample 0 looks up the table at 0.5, the
                // pixel centre, so the passes written from it (depth, IDs) are not jittered
                if (r == 0 && s0 == 0) {
                    X[j] = filter_offset(0.5f, tab, size) + x;
                    Y[j] = filter_offset(0.5f, tab, size) + y;
                }
                j += run;
            }
        });
    }, size_t(1) << 16);
}

}  // namespace dacrt
