// The lamp BVH of lampbvh.h: boxes per lamp kind, a median-split build, and a padded slab test.
#include "lampbvh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dacrt {

namespace {

// The box around everything of lamp L that hit_lamp can report as met, unpadded; false for
// lamps no ray meets (delta point and spot lamps) and lamps at infinity (sun, background).
bool lamp_box(const LampRecord& L, float lo[3], float hi[3]) {
    const int kind = int(L.kind), shape = int(L.shape);
    float ext[3];
    if ((kind == LAMP_POINT || kind == LAMP_SPOT) && shape != POINT_DELTA) {
        // a sphere, or a disk through the centre: within radius of the centre either way
        for (int a = 0; a < 3; ++a) ext[a] = L.radius;
    } else if (kind == LAMP_AREA) {
        // rectangle or ellipse spanned by half the axes around the centre
        for (int a = 0; a < 3; ++a) ext[a] = 0.5f * (std::fabs(L.axis_x[a]) + std::fabs(L.axis_y[a]));
    } else {
        return false;
    }
    for (int a = 0; a < 3; ++a) {
        lo[a] = L.pos[a] - ext[a];
        hi[a] = L.pos[a] + ext[a];
    }
    return true;
}

// The rounding of the lamp's own coordinates in hit_lamp (|pos| and its extent).
float box_pad(const float lo[3], const float hi[3]) {
    float mag = 0.0f;
    for (int a = 0; a < 3; ++a) mag = std::max({mag, std::fabs(lo[a]), std::fabs(hi[a]), hi[a] - lo[a]});
    return LampBVH::kSlack * mag;
}

}  // namespace

bool LampBVH::padded_box(const LampRecord& L, float lo[3], float hi[3]) {
    if (!lamp_box(L, lo, hi)) return false;
    const float pad = box_pad(lo, hi);
    for (int a = 0; a < 3; ++a) lo[a] -= pad, hi[a] += pad;
    return true;
}

LampBVH::LampBVH(const LampRecord* rec, const int32_t* lamps, size_t nl) {
    std::vector<float> box, centre;
    std::vector<int32_t> items, position;
    for (size_t k = 0; k < nl; ++k) {
        float lo[3], hi[3];
        if (!lamp_box(rec[lamps[k]], lo, hi)) continue;
        const float pad = box_pad(lo, hi);
        for (int a = 0; a < 3; ++a) box.push_back(lo[a] - pad);
        for (int a = 0; a < 3; ++a) box.push_back(hi[a] + pad);
        for (int a = 0; a < 3; ++a) centre.push_back(0.5f * (lo[a] + hi[a]));
        items.push_back(int32_t(items.size()));
        position.push_back(int32_t(k));
    }
    if (items.empty()) return;
    nodes_.reserve(2 * items.size());  // a binary tree over m >= 1 leaves' items: < 2m nodes
    nodes_.emplace_back();
    build(items, 0, items.size(), box, centre, 0);
    order_.reserve(items.size());
    for (int32_t j : items) order_.push_back(position[size_t(j)]);  // leaf by leaf
}

void LampBVH::build(std::vector<int32_t>& items, size_t b, size_t e, const std::vector<float>& box,
                    const std::vector<float>& centre, size_t slot) {
    Node node;
    float clo[3], chi[3];
    for (int a = 0; a < 3; ++a) {
        node.lo[a] = clo[a] = std::numeric_limits<float>::infinity();
        node.hi[a] = chi[a] = -std::numeric_limits<float>::infinity();
    }
    for (size_t i = b; i < e; ++i) {
        const size_t j = size_t(items[i]);
        for (int a = 0; a < 3; ++a) {
            node.lo[a] = std::min(node.lo[a], box[6 * j + a]);
            node.hi[a] = std::max(node.hi[a], box[6 * j + 3 + a]);
            clo[a] = std::min(clo[a], centre[3 * j + a]);
            chi[a] = std::max(chi[a], centre[3 * j + a]);
        }
    }
    if (e - b <= size_t(kLeafSize)) {
        node.first = int32_t(b);
        node.count = int32_t(e - b);
        nodes_[slot] = node;
        return;
    }
    // median of the centroids along their widest axis: lamps are small and similar in size
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
    const size_t mid = b + (e - b) / 2;
    std::nth_element(items.begin() + long(b), items.begin() + long(mid), items.begin() + long(e),
                     [&](int32_t x, int32_t y) { return centre[3 * size_t(x) + axis] < centre[3 * size_t(y) + axis]; });
    node.first = int32_t(nodes_.size());
    node.count = 0;
    nodes_[slot] = node;
    nodes_.emplace_back();
    nodes_.emplace_back();
    build(items, b, mid, box, centre, size_t(node.first));
    build(items, mid, e, box, centre, size_t(node.first) + 1);
}

}  // namespace dacrt
