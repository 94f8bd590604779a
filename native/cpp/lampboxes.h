// The padded boxes of a short lamp list (up to 64 listed lamps), tested against rays side by
// side: lamp_gather's candidates for a ray as one bit word, by a branch-free slab test of
// kRays rays at a time against each box, instead of a walk down a LampBVH. A dozen lamps make
// a BVH of a few leaves whose walk branches on each ray's direction (unpredictably: the
// gather's BVH was ~5% of a many-light render, ~2/3 of it the walk); the flat test costs a few
// vector operations per box and ray group.
//
// Each box is a LampBVH leaf's own (lamp_bounds), tested with LampBVH's padded slab and the
// same float operations per ray, so a lamp hit_lamp meets is never left out, and lamp_gather's
// sums stay bit for bit those of the linear loop.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lamps.h"

namespace dacrt {

class LampBoxes {
public:
    static constexpr size_t kMaxLamps = 64;  // a bit per listed lamp
    static constexpr size_t kRays = 8;       // rays tested side by side

    // Over the lamps rec[lamps[k]], k < nl <= kMaxLamps, that have a box (LampBVH's).
    LampBoxes(const LampRecord* rec, const int32_t* lamps, size_t nl);

    // out[q] for rays q < count (O, D: 3 rows of stride n from ray i0; tmax[i * t_step] for
    // ray i): bit k where the ray may meet listed lamp k's box at 0 < t < tmax (LampBVH::visit's test).
    void meets(const float* O, const float* D, const float* tmax, size_t t_step, size_t n, size_t i0, size_t count,
               uint64_t out[kRays]) const;
    // No listed lamp has a box (only lamps at infinity and delta lamps): no ray meets one.
    bool empty() const { return which_.empty(); }

private:
    std::vector<float> box_;      // per boxed lamp: padded lo[3], hi[3]
    std::vector<int32_t> which_;  // per boxed lamp: its list position k
};

}  // namespace dacrt
