// A bounding volume hierarchy over the finite lamps a ray can meet (spheres, disks, area
// lights), so that lamp_gather tests each ray against the lamps near its path instead of every
// lamp: with thousands of lamps the lamp-by-lamp loop was most of a render (1000 point lights:
// 93%, ~8 ns per ray and lamp). Built per lamp_gather call, from the records alone: nothing
// outlives the call, and a few thousand boxes build in well under a millisecond.
//
// It only narrows the candidates: lamp_gather still evaluates each candidate with hit_lamp and
// adds the lamps a ray meets in list order, so its sums are bit for bit those of the linear
// loop. For that the boxes must never miss a meeting hit_lamp's float32 arithmetic reports, so
// they are padded for its rounding (see visit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lamps.h"

namespace dacrt {

class LampBVH {
public:
    // Over the lamps rec[lamps[k]], k < nl, that have a box; candidates are reported as k.
    LampBVH(const LampRecord* rec, const int32_t* lamps, size_t nl);

    // Appends to out the k of every lamp whose box the ray O + t D may meet at 0 < t < tmax
    // (unsorted). The test widens each box by what hit_lamp's float32 rounding can move a
    // point it computes: a relative margin of the box's coordinates (at build), plus
    // kSlack x (|O|max + t) along the ray, so a lamp hit_lamp meets is never left out.
    void visit(const float O[3], const float D[3], float tmax, std::vector<int32_t>& out) const;

    static constexpr float kSlack = 1.0f / 8192.0f;  // ~1000 float32 ulps of the magnitudes
    static constexpr int kLeafSize = 2;

private:
    struct Node {
        float lo[3], hi[3];
        int32_t first;  // inner: index of the left child (the right one follows it); leaf: into order_
        int32_t count;  // 0 for an inner node
    };
    // Fills nodes_[slot] for items[b, e) (box indices), reordering them leaf by leaf.
    void build(std::vector<int32_t>& items, size_t b, size_t e, const std::vector<float>& box,
               const std::vector<float>& centre, size_t slot);
    std::vector<Node> nodes_;
    std::vector<int32_t> order_;  // list positions k, leaf by leaf
};

}  // namespace dacrt
