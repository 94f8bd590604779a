// A light tree: many-light sampling that picks, per shading point, a light with probability
// following its estimated contribution there (Cycles' kernel/light/tree.h, after Conty and
// Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018). Built per
// frame over the local lights (lamps with a position, emissive triangles); distant lights stay
// in the global choice. A leaf is one light or one group of them (the triangles of one emissive
// object), within which a point picks by energy alone.
//
// Each node bounds its lights by a sphere, the directions they emit in by a cone (axis, spread
// theta_o, falloff theta_e beyond it) and carries their summed energy (on-axis intensity: an
// irradiance of energy / d^2 at distance d). A point P goes down two levels at a time, from a
// node to one of its (up to) four grandchildren, by their importance, each the sum of its own
// children's (a look one level further down, whose tighter bounds tell more); a node's own
// importance is energy x the cosine of the smallest emission angle any of the node's lights can
// have toward P / the squared distance to the centre (0 where no light of the node can face P;
// inside the sphere no cone culling, and the distance at least half the radius, as in Cycles;
// but where the node's lights emit within a hemisphere, theta_o + theta_e <= pi/2, a point
// behind the box's extent along the axis is 0 inside the sphere too: a one-sided area light
// gives nothing behind its plane, as Cycles' area_light_tree_parameters culls it), times the
// cosine of the smallest angle of incidence at the receiving point's normal N (0 for a node
// wholly below its horizon, by its box, even where its sphere holds the point: a diffuse
// surface gets nothing from there). A BSDF ray's MIS
// weight evaluates the same pdf at its origin with that vertex's normal.
//
// Delta lights (points, spots) are given a cone of every direction, so they are never culled:
// their only estimator is light sampling, and every node on their way keeps a probability > 0
// (targets whose importances are all 0 or overflow split by energy).
//
// Two levels per step and eight weighs side by side in float (falling back to float64 where
// distances leave float's range) made picking a light about twice as fast as one level per
// step in float64, the same look-ahead; the eight are one AVX vector where the CPU has it
// (treelanes.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dacrt {

struct TreePoint;  // treelanes.h

struct LightTreeNode {
    float center[3], radius;  // bounding sphere of the lights' bounds
    float half[3];            // the bounds' half extents about center (rounded up)
    float axis[3], cos_o;     // emission cone: within theta_o of axis (cos_o = -1: every direction)
    float sin_o, cos_e;       // sin theta_o; cos of the falloff angle theta_e beyond theta_o
    float slab;               // where theta_o + theta_e <= pi/2 (every light emits only to the
                              // front of planes normal to axis through it): the bounds' half
                              // extent along axis, so that a point with axis . (P - center) +
                              // slab <= 0 is behind every light (-1: no such half-space)
    float cos_b, cos_s, sin_s;  // the smallest importance's cone: every light of the node emits
                                // toward every direction within theta_b - theta_s of axis, its
                                // own axis within theta_s of it (cos_b 2: no such direction, a
                                // light may give nothing anywhere; -2: all emit every way alike)
    double energy;            // summed energy of the lights below (> 0; double: sums of float
                              // energies overflow float, and importances divide it by d^2)
    int32_t child;            // inner node: left child (right = child + 1); leaf: -1 - member
};

// The lights of a tree, m members, each with an axis-aligned box (lo, hi: 3 rows of m), an
// emission cone (axis: 3 rows of m, unit or anything for cos_o = -1; cos_o, cos_e: m), an
// energy (m, a normal double at most 1e200: importances and probabilities stay finite) and the key it answers to (m distinct values >= 0, e.g. the light
// choice's entry index).
struct LightTreeInput {
    const float* lo;
    const float* hi;
    const float* axis;
    const float* cos_o;
    const float* cos_e;  // (with cos_o = -1: -1 the same intensity every way, e.g. a point lamp)
    const double* energy;
    const int32_t* key;
    size_t m;
    // (null: each member its own) members with the same group value (>= 0) form one leaf, in
    // which a point picks by energy alone: e.g. the triangles of one emissive object, whose
    // per-point split would cost a tree level per halving for little gain
    const int32_t* group = nullptr;
    // (null: all 0) light linking: each member's light set (0..63; the members of one group
    // share theirs). A point whose receiver mask (bit s: it is lit by set s) holds none of a
    // node's sets never goes there, so light samples are not spent on lights it is not lit by.
    const uint8_t* set = nullptr;
    // (null: the box's) each member's own bounding sphere about its box's centre, radius (m,
    // >= 0; inf: the box's): a leaf of one member takes it where it is tighter than the box's (a tilted
    // area light's box holds a sphere up to sqrt(3)x its own, which had kept it from being
    // culled where it cannot reach; a member of a group keeps the box's)
    const float* radius = nullptr;
};

class LightTree {
public:
    // Throws std::invalid_argument naming the first bad member (see light_tree_error).
    explicit LightTree(const LightTreeInput& in);

    size_t members() const { return member_key_.size(); }
    size_t nodes() const { return nodes_.size(); }
    // One more than the largest key.
    size_t key_bound() const { return leaf_of_key_.size(); }
    // Whether key is one of the tree's lights.
    bool member(int64_t key) const {
        return key >= 0 && uint64_t(key) < leaf_of_key_.size() && leaf_of_key_[size_t(key)] >= 0;
    }
    // Every light set (receiver mask) a point can hold: no light is excluded.
    static constexpr uint64_t kAllSets = ~uint64_t(0);
    // The key of the light picked at P (receiving normal N, unit; null: none) with the uniform
    // u in [0, 1), and its probability, among the lights of the sets in `receivers` (when the
    // point is lit by none of the tree's, a light of any set, which lights it nothing).
    int32_t sample(const float P[3], const float* N, double u, double& prob, uint64_t receivers = kAllSets) const;
    // sample() at count points i (P[a * stride + i], N likewise or null: none, u[i], receivers[i]
    // or null: every set; into key[i], prob[i]), the same bits, walked stop by stop: each stop
    // weighs the points that reach it side by side (treelanes.h LaneRowsFn), one of its lanes at
    // a time and only the lanes that hold a node, rather than each point's eight lanes at once.
    void sample_rows(size_t count, const float* P, const float* N, size_t stride, const double u[],
                     const uint64_t* receivers, int32_t key[], double prob[]) const;
    struct Rows;  // (lighttree.cpp) sample_rows' points and scratch
    // The probability that sample() at P, N (and receivers) picks key (0 when key is not a member).
    double pdf(const float P[3], const float* N, int64_t key, uint64_t receivers = kAllSets) const;
    // For tests: every stop's eight lanes (stops() x 8, stop by stop) weighed at P (and N) as a
    // walk weighs them (the float lanes, float64 where they leave float's range) into lanes,
    // and by the float64 weigh() into exact (0 for an empty lane); their smallest importances
    // likewise into lanes_min and exact_min (null: not wanted).
    size_t stops() const { return stops_.size(); }
    void stop_weighs(const float P[3], const float* N, double* lanes, double* exact, double* lanes_min = nullptr,
                     double* exact_min = nullptr) const;
    // The same with N column i of normals (3 rows, stride n; null: none).
    double pdf(const float P[3], const float* normals, size_t n, size_t i, int64_t key,
               uint64_t receivers = kAllSets) const;

    // A node a walk down the tree stops at (sample()), two levels apart: from it the walk goes
    // on to one of its four targets, its children's children (a leaf child stands for itself:
    // targets 1 and 3 then -1), by their importance at the point, each the sum of its two lanes'
    // weighs (lookahead: its children, or itself when a leaf). The lanes' bounds side by side in
    // float, so that all eight are weighed at once (treelanes.cpp); an empty lane has energy 0.
    struct Stop {
        float center[3][8], half[3][8], radius[8];
        float axis[3][8], cos_o[8], sin_o[8], cos_e[8], slab[8];
        float cos_b[8], cos_s[8], sin_s[8];
        double energy[8];
        int32_t node[8];    // the node each lane is (-1: empty), for the float64 path
        int32_t target[4];  // target j weighs as lanes 2j, 2j + 1
    };

private:
    void build_stops();
    void walk_rows(Rows& r, size_t depth, size_t at, size_t b, size_t e, int32_t key[], double prob[]) const;
    void walk_each(const Rows& r, size_t depth, size_t at, size_t b, size_t e, int32_t key[], double prob[]) const;
    void probs_at(size_t at, const TreePoint& point, uint64_t receivers, double p[4]) const;
    size_t step(size_t at, const double p[4], double u, double& lo, double& w) const;
    static int pick_of(const double p[4], double u, double& lo, double& w);  // step's target index
    int32_t leaf_pick(size_t at, double u, double lo, double w, double& prob) const;

    std::vector<LightTreeNode> nodes_;
    std::vector<Stop> stops_;
    std::vector<int32_t> stop_of_;      // node -> its stop (-1: no walk stops there, or a leaf)
    std::vector<uint64_t> stop_sets_;   // light linking: per stop its 8 lanes' sets, its 4 targets' (empty: unlinked)
    std::vector<int32_t> hop_from_;     // node -> the stop it is a target of (-1: the root, or none)
    std::vector<uint8_t> hop_lane_;     // node -> its target index there
    std::vector<int32_t> item_start_;   // group g's members: slots item_start_[g] .. [g + 1] - 1
    std::vector<int32_t> member_key_;   // slot -> key
    std::vector<double> member_cdf_;    // slot -> cumulative energy share within its group
    std::vector<double> member_share_;  // slot -> its energy share within its group
    std::vector<int32_t> leaf_of_key_;  // key -> its leaf node, -1: not a member
    std::vector<int32_t> slot_of_key_;  // key -> its slot
    std::vector<uint64_t> sets_;        // node -> the light sets below it (bit s); empty: unlinked
};

// Empty when the input can build a tree, else what is wrong with which member.
std::string light_tree_error(const LightTreeInput& in);

}  // namespace dacrt
