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

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "lamps.h"

namespace dacrt {

class LampBVH {
public:
    // Over the lamps rec[lamps[k]], k < nl, that have a box; candidates are reported as k.
    LampBVH(const LampRecord* rec, const int32_t* lamps, size_t nl);

    // Calls emit(k) for every lamp whose box the ray O + t D may meet at 0 < t < tmax (in no
    // particular order, each k once). The test widens each box by what hit_lamp's float32
    // rounding can move a point it computes: a relative margin of the box's coordinates (at
    // build), plus kSlack x (|O|max + t) along the ray, so a lamp hit_lamp meets is never left out.
    template <class Emit>
    void visit(const float O[3], const float D[3], float tmax, Emit&& emit) const;

    // visit's k appended to out (unsorted).
    void visit(const float O[3], const float D[3], float tmax, std::vector<int32_t>& out) const {
        visit(O, D, tmax, [&](int32_t k) { out.push_back(k); });
    }

    static constexpr float kSlack = 1.0f / 8192.0f;  // ~1000 float32 ulps of the magnitudes
    static constexpr int kLeafSize = 2;

    // Lamp L's box, padded for the rounding of its own coordinates in hit_lamp; false for lamps
    // no ray meets (delta point and spot lamps) and lamps at infinity (sun, background).
    static bool padded_box(const LampRecord& L, float lo[3], float hi[3]);

private:
    struct Node {
        float lo[3], hi[3];
        int32_t first;  // inner: index of the left child (the right one follows it); leaf: into order_
        int32_t count;  // 0 for an inner node
    };
    // A ray's slab test, its per-ray constants worked out once (see visit).
    struct Slab {
        float inv_p[3], inv_m[3], off_lo[3], off_hi[3], t_end;
        bool lower_p[3], upper_m[3];
        Slab(const float O[3], const float D[3], float tmax);
        bool meets(const Node& node) const;
    };
    // Fills nodes_[slot] for items[b, e) (box indices), reordering them leaf by leaf.
    void build(std::vector<int32_t>& items, size_t b, size_t e, const std::vector<float>& box,
               const std::vector<float>& centre, size_t slot);
    std::vector<Node> nodes_;
    std::vector<int32_t> order_;  // list positions k, leaf by leaf
};

// A point hit_lamp computes at parameter t may be off by ~ulps of |O| and of t (|D| = 1) on
// every axis: the box grows by c (M + t), M = |O|max. On axis a that is
//   (D_a + c) t >= lo_a - O_a - c M   and   (D_a - c) t <= hi_a - O_a + c M,
// a slab test whose bounds are lower or upper by the signs of D_a +- c (at |D_a| < c the
// widening outruns the ray: both are lower bounds).
inline LampBVH::Slab::Slab(const float O[3], const float D[3], float tmax) {
    const float c = kSlack;
    const float M = std::max({std::fabs(O[0]), std::fabs(O[1]), std::fabs(O[2])});
    for (int a = 0; a < 3; ++a) {
        const float ap = D[a] + c, am = D[a] - c;
        inv_p[a] = 1.0f / ap;  // a zero gives +-inf: the bound is then +-inf or (0 x inf) NaN, ignored
        inv_m[a] = 1.0f / am;
        lower_p[a] = !std::signbit(ap);
        upper_m[a] = !std::signbit(am);
        off_lo[a] = -O[a] - c * M;
        off_hi[a] = -O[a] + c * M;
    }
    t_end = tmax + c * (M + tmax);
}

inline bool LampBVH::Slab::meets(const Node& node) const {
    constexpr float inf = std::numeric_limits<float>::infinity();
    float tn = 0.0f, tf = t_end;
    for (int a = 0; a < 3; ++a) {
        const float x = (node.lo[a] + off_lo[a]) * inv_p[a], y = (node.hi[a] + off_hi[a]) * inv_m[a];
        // Each bound goes to one side, the other gets +-inf: selects, not branches on the ray's
        // signs (max/min instructions). NaN bounds compare false and are ignored: conservative.
        const float xn = lower_p[a] ? x : -inf, xf = lower_p[a] ? inf : x;
        const float yn = upper_m[a] ? -inf : y, yf = upper_m[a] ? y : inf;
        tn = xn > tn ? xn : tn;
        tf = xf < tf ? xf : tf;
        tn = yn > tn ? yn : tn;
        tf = yf < tf ? yf : tf;
    }
    return tn <= tf;
}

// Both children of an inner node are tested together, so only those met are pushed, and a
// met leaf's lamps are reported at once.
template <class Emit>
void LampBVH::visit(const float O[3], const float D[3], float tmax, Emit&& emit) const {
    if (nodes_.empty()) return;
    const Slab slab(O, D, tmax);
    const Node& root = nodes_[0];
    if (!slab.meets(root)) return;
    const int32_t* order = order_.data();
    if (root.count != 0) {
        for (int32_t i = 0; i < root.count; ++i) emit(order[root.first + i]);
        return;
    }
    const Node* nodes = nodes_.data();
    int32_t stack[64];  // inner nodes met, their children still to test; depth <= log2 of the lamps
    int top = 0;
    stack[top++] = root.first;
    while (top > 0) {
        const int32_t first = stack[--top];
        for (int32_t j = first; j < first + 2; ++j) {
            const Node& node = nodes[j];
            if (!slab.meets(node)) continue;
            if (node.count == 0) stack[top++] = node.first;
            else
                for (int32_t i = 0; i < node.count; ++i) emit(order[node.first + i]);
        }
    }
}

}  // namespace dacrt
