// Chunks of nearby origins (see chunkorder.h).
//
// Chunks cut from the batch by index each met nearly every leaf of the scene with a fraction of
// the rays: on San Francisco's 1M diffuse rays two chunks visited 53K leaves against one
// chunk's 31K, and 2 threads spent 8% more CPU time than 1. Cut at the median origin instead,
// each chunk meets mostly the leaves near its own origins. Hits do not change: they are a
// function of each ray and the triangles, and the tracer permutes the records anyway.
#include "chunkorder.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace dacrt {

namespace {

constexpr size_t kSamples = 1024;  // origins sampled for a cut's axis and plane

#include "runpartition.h"

// Bit k set: rays[k] (k < m <= kRunRays) lies below the plane.
uint64_t below_mask(const Ray* rays, size_t m, int axis, float plane) {
    uint64_t bits = 0;
    for (size_t k = 0; k < m; ++k) bits |= uint64_t(rays[k].org[axis] < plane) << k;
    return bits;
}

// Moves the rays below the plane to the front; returns their count. One way, forward, a run's
// mask at a time (the filter's filter_small, filter.h): a cut sweeps a whole batch (San
// Francisco's 1M rays: 32 MB of records, serial), and a two-ended sweep reads records out of
// cache at up to twice the cost of one forward read (filter.h, kForwardSweepRays). The next
// run's mask is taken before this run's swaps, which move records within [w, i + kRunRays)
// only. Branch-free classification: a record-at-a-time std::partition spent a mispredicted
// branch on about every other ray.
size_t split_rays(Ray* rays, size_t n, int axis, float plane) {
    auto mask = [&](size_t i) { return below_mask(rays + i, std::min(kRunRays, n - i), axis, plane); };
    size_t w = 0;
    uint64_t next = n ? mask(0) : 0;
    for (size_t i = 0; i < n; i += kRunRays) {
        uint64_t m = next;
        if (i + kRunRays < n) next = mask(i + kRunRays);
        while (m) {
            swap_records(rays + i + size_t(__builtin_ctzll(m)), rays + w);
            m &= m - 1;
            ++w;
        }
    }
    return w;
}

bool order(Ray* rays, size_t n, size_t parts) {
    if (parts < 2 || n < 2 * kSamples) return false;
    const size_t s = std::min(n, kSamples);
    std::vector<float> v[3];
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        v[a].resize(s);
        for (size_t k = 0; k < s; ++k) v[a][k] = rays[k * n / s].org[a];
        const auto mm = std::minmax_element(v[a].begin(), v[a].end());
        lo[a] = *mm.first;
        hi[a] = *mm.second;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    if (!(hi[axis] > lo[axis])) return false;  // one origin (camera rays): nothing to gain
    const size_t left_parts = parts / 2;
    const size_t q = s * left_parts / parts;
    std::nth_element(v[axis].begin(), v[axis].begin() + q, v[axis].end());
    const float plane = v[axis][q];
    const size_t k = split_rays(rays, n, axis, plane);
    if (k == 0 || k == n) return false;
    order(rays, k, left_parts);
    order(rays + k, n - k, parts - left_parts);
    return true;
}

}  // namespace

bool order_by_origin(Ray* rays, size_t n, size_t parts) { return order(rays, n, parts); }

}  // namespace dacrt
