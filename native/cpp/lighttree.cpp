// The light tree (see lighttree.h): a build by the surface area orientation heuristic, cones
// merged as Cycles' light tree does, and the importance that splits a point's choice between
// two children.
#include "lighttree.h"
#include "treelanes.h"
#include "dispatch.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <stdexcept>

#pragma GCC diagnostic ignored "-Wpsabi"  // 32-byte vectors only ever inlined (pick_rows)

namespace dacrt {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Squared distances below this count as this: energy (< 1e210) / d2 stays finite.
constexpr double kMinDist2 = 1e-60;
// A point counts as behind a node's lights (LightTreeNode::slab) only beyond this share of
// 2 (d + max |P_k|) + slab, d its distance to the centre: ~100 float ULPs of the lengths and
// coordinates the lights' own float arithmetic rounds (their sample at a point on the plane,
// or a hair behind it, may still find a cosine > 0), so that no node is culled that could
// give the point light.
constexpr float kBackMargin = 1e-5f;

double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

struct Cone {
    double axis[3];
    double theta_o, theta_e;  // theta_o >= pi: every direction
};

// The smallest cone holding a's and b's directions (Cycles' merge_cones), with a small margin
// so that float rounding of the stored cone never excludes a direction of its lights.
Cone merge(const Cone& a, const Cone& b) {
    Cone c{};
    c.theta_e = std::max(a.theta_e, b.theta_e);
    c.axis[0] = c.axis[1] = 0.0;
    c.axis[2] = 1.0;
    c.theta_o = kPi;
    if (a.theta_o >= kPi || b.theta_o >= kPi) return c;
    const double theta_d = std::acos(std::clamp(dot3(a.axis, b.axis), -1.0, 1.0));
    if (std::min(theta_d + b.theta_o, kPi) <= a.theta_o) {
        std::copy(a.axis, a.axis + 3, c.axis);
        c.theta_o = a.theta_o;
        return c;
    }
    if (std::min(theta_d + a.theta_o, kPi) <= b.theta_o) {
        std::copy(b.axis, b.axis + 3, c.axis);
        c.theta_o = b.theta_o;
        return c;
    }
    const double theta_o = 0.5 * (a.theta_o + theta_d + b.theta_o) + 1e-6;
    if (theta_o >= kPi) return c;
    // a's axis turned toward b's by theta_o - theta_a, in the plane of the two
    double w[3];
    const double ab = dot3(a.axis, b.axis);
    for (int k = 0; k < 3; ++k) w[k] = b.axis[k] - a.axis[k] * ab;
    const double len = std::sqrt(dot3(w, w));
    if (!(len > 1e-12)) return c;  // (anti)parallel axes not caught above: every direction
    const double r = theta_o - a.theta_o, cr = std::cos(r), sr = std::sin(r);
    for (int k = 0; k < 3; ++k) c.axis[k] = a.axis[k] * cr + w[k] / len * sr;
    c.theta_o = theta_o;
    return c;
}

// The importance of node nd's own bounds at P (see lighttree.h): energy x f / d2, f the
// incidence and emission cosines. N (null: none) is the receiving point's unit normal: lights
// wholly below its horizon count 0. wmin: the smallest importance (Cycles' min_importance), the
// cosines at their worst over the node's sphere and cone (cos(theta_i + theta_u), and
// cos(theta + theta_u + theta_s) where that stays within theta_b, LightTreeNode::cos_b; a node of
// lights that emit every way alike: cos_u, as Cycles orients a point light toward P), 0 inside
// the sphere and wherever the largest is 0.
double weigh(const LightTreeNode& nd, const float P[3], const float* N, double& wmin) {
    wmin = 0.0;
    const double v[3] = {double(nd.center[0]) - P[0], double(nd.center[1]) - P[1], double(nd.center[2]) - P[2]};
    const double dd = dot3(v, v), r = nd.radius, r2 = r * r;
    if (N) {  // the box wholly below the tangent plane at P (its highest corner on or under it)
        const double reach = double(N[0]) * v[0] + double(N[1]) * v[1] + double(N[2]) * v[2] +
                             std::fabs(N[0]) * nd.half[0] + std::fabs(N[1]) * nd.half[1] + std::fabs(N[2]) * nd.half[2];
        if (!(reach > 0.0)) return 0.0;
    }
    if (nd.slab >= 0.0f) {  // every light emits within a hemisphere: P behind all of them gets 0
        const double back = -(double(nd.axis[0]) * v[0] + double(nd.axis[1]) * v[1] + double(nd.axis[2]) * v[2]) +
                            nd.slab;
        const double pm = std::max({std::fabs(double(P[0])), std::fabs(double(P[1])), std::fabs(double(P[2]))});
        if (back <= -double(kBackMargin) * (2.0 * (std::sqrt(dd) + pm) + nd.slab)) return 0.0;
    }
    // within the bounds (or NaN): no cone culling, and the distance to the centre at least half
    // the radius (Cycles)
    if (!(dd > r2)) return nd.energy / std::max(std::max(dd, 0.25 * r2), kMinDist2);
    double f = 1.0, fmin = 1.0;
    const double d = std::sqrt(dd);
    const double sin_u = r / d, cos_u = std::sqrt(std::max(0.0, 1.0 - sin_u * sin_u));
    if (N) {  // the smallest angle of incidence any light of the node can have: theta_i - theta_u
        const double n[3] = {N[0], N[1], N[2]};
        const double cos_i = std::clamp(dot3(n, v) / d, -1.0, 1.0);
        const double sin_i = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i));
        if (cos_i < cos_u) {
            const double c = cos_i * cos_u + sin_i * sin_u;  // cos(theta_i - theta_u)
            if (!(c > 0.0)) return 0.0;
            f = c;
        }
        fmin = std::max(cos_i * cos_u - sin_i * sin_u, 0.0);  // cos(theta_i + theta_u)
    }
    const double ax[3] = {nd.axis[0], nd.axis[1], nd.axis[2]};
    const double cos_t = std::clamp(-dot3(ax, v) / d, -1.0, 1.0);  // axis vs. node -> P
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
    if (nd.cos_o > -1.0f) {
        // phi = theta_o + theta_u: the widest angle from the axis at which a light of the node
        // can be seen from P's direction
        const double cos_p = nd.cos_o * cos_u - nd.sin_o * sin_u, sin_p = nd.sin_o * cos_u + nd.cos_o * sin_u;
        if (sin_p >= 0.0 && cos_t < cos_p) {                           // phi <= pi and theta > phi
            const double cos_r = cos_t * cos_p + sin_t * sin_p;        // cos(theta - phi)
            if (cos_r <= nd.cos_e) return 0.0;
            f *= cos_r;
        }
    }
    const double inv = 1.0 / std::max(dd, kMinDist2);
    if (nd.cos_b < -1.0f) {
        fmin *= cos_u;
    } else {  // cos(theta + theta_u + theta_s), within theta_b
        const double c1 = cos_t * cos_u - sin_t * sin_u, s1 = sin_t * cos_u + cos_t * sin_u;
        const double cw = c1 * nd.cos_s - s1 * nd.sin_s;
        fmin *= cos_t >= 0.0 && cw >= nd.cos_b ? cw : 0.0;
    }
    wmin = nd.energy * fmin * inv;
    return nd.energy * f * inv;
}

// The halves of stop q's lanes that bad names (bit 0: lanes 0-3, bit 1: lanes 4-7: a distance
// out of float's range) weighed in float64 into imp.
void exact_halves(const LightTreeNode* nodes, const LightTree::Stop& q, int bad, const float P[3], const float* N,
                  double imp[8], double imin[8]) {
    for (int o = 0; o < 8; o += 4)
        if (bad & (1 << (o / 4)))
            for (int k = o; k < o + 4; ++k) {
                imin[k] = 0.0;
                imp[k] = q.node[k] < 0 ? 0.0 : weigh(nodes[q.node[k]], P, N, imin[k]);
            }
}

// The eight lanes of stop q weighed at the point: side by side in float (treelanes.h), the four
// of them a distance out of float's range takes in float64.
void lane_weighs(const LightTreeNode* nodes, const LightTree::Stop& q, const TreePoint& at, double imp[8],
                 double imin[8]) {
    static const StopWeighFn weigh_lanes = stop_weigh_fn();
    exact_halves(nodes, q, weigh_lanes(q, at, imp, imin), at.P, at.N, imp, imin);
}

// The targets' shares where their largest importances t sum to s > 0 (finite, inv = 1 / s), as
// Cycles' get_left_probability splits a node: the mean of the shares by the largest and by the
// smallest importances tm (inv_m = 1 / their sum), so that a light that surely reaches the point
// keeps about half the samples beside a brighter one that may give nothing there (fuzz seed 10,
// README). Where the smallest sum to 0 (or overflow), the share by the largest alone, as before:
// Cycles then takes an even share among the targets that can give anything, which made a street
// of 16 point lamps 23x noisier (its inner nodes' smallest are all 0: the walk's first stop sent
// 3/8 of the samples to the far quarters; README). The same operations, in order, as pick_rows'
// lanes.
inline __attribute__((always_inline)) double share(double t, double tm, double inv, double inv_m, bool ok_m) {
    return ok_m ? 0.5 * (t * inv + tm * inv_m) : t * inv;
}

// The probabilities at P of a walk at stop q going on to each of its targets (see
// LightTree::Stop), from its eight lanes' importances imp: by importance, a leaf target's own
// weigh() or an inner one's children's summed (whose tighter bounds see more than their
// parent's: a group of spots all aimed away from P, or lights all behind its surface, is 0 even
// where their merged cone and sphere are not); by energy where all importances are 0 (or their
// sum is not finite). With light linking (lane_sets: the stop's lanes' light sets then its
// targets', null: none) what holds none of the point's sets counts nothing, and such a target is
// never taken (unless no target holds them: then the point is lit by no light below, and any way
// gives it nothing). Each probability is its own quotient, not 1 - the others: a faint light's
// 1e-19 would round to 0 that way, and a delta light must never become impossible. At least one
// target gets > 0.
inline __attribute__((always_inline)) void probs_of(const LightTreeNode* nodes, const LightTree::Stop& q, const uint64_t* lane_sets, uint64_t receivers,
              double imp[8], double imin[8], double p[4]) {
    if (lane_sets)
        for (int k = 0; k < 8; ++k) {
            imp[k] = (lane_sets[k] & receivers) ? imp[k] : 0.0;
            imin[k] = (lane_sets[k] & receivers) ? imin[k] : 0.0;
        }
    bool eligible[4], any = false;
    for (int j = 0; j < 4; ++j) {
        eligible[j] = q.target[j] >= 0 && (!lane_sets || (lane_sets[8 + j] & receivers));
        any |= eligible[j];
    }
    if (!any)
        for (int j = 0; j < 4; ++j) eligible[j] = q.target[j] >= 0;
    double t[4], tm[4], s = 0.0, sm = 0.0;
    for (int j = 0; j < 4; ++j) {
        t[j] = eligible[j] ? imp[2 * j] + imp[2 * j + 1] : 0.0;
        tm[j] = eligible[j] ? imin[2 * j] + imin[2 * j + 1] : 0.0;
        s += t[j];
        sm += tm[j];
    }
    if (s > 0.0 && std::isfinite(s) && std::isfinite(1.0 / s)) {  // (a subnormal sum's inverse overflows)
        const double inv = 1.0 / s, inv_m = 1.0 / sm;
        const bool ok_m = sm > 0.0 && std::isfinite(sm) && std::isfinite(inv_m);
        for (int j = 0; j < 4; ++j) p[j] = share(t[j], tm[j], inv, inv_m, ok_m);
        return;
    }
    double e = 0.0;
    for (int j = 0; j < 4; ++j) e += eligible[j] ? nodes[q.target[j]].energy : 0.0;
    const double inv = 1.0 / e;
    for (int j = 0; j < 4; ++j) p[j] = eligible[j] ? nodes[q.target[j]].energy * inv : 0.0;
}

// probs_of at P, its lanes weighed there.
void target_probs(const LightTreeNode* nodes, const LightTree::Stop& q, const uint64_t* lane_sets, const TreePoint& at,
                  uint64_t receivers, double p[4]) {
    double imp[8], imin[8];
    lane_weighs(nodes, q, at, imp, imin);
    probs_of(nodes, q, lane_sets, receivers, imp, imin, p);
}

// Conty and Kulla's orientation measure of a cone: the solid angle of its axis spread plus the
// falloff beyond it, weighted by cosine (Cycles' OrientationBounds::calculate_measure).
double measure(const Cone& c) {
    const double theta_o = std::min(c.theta_o, kPi), theta_w = std::min(kPi, theta_o + c.theta_e);
    const double co = std::cos(theta_o), so = std::sin(theta_o);
    return 2.0 * kPi * (1.0 - co) +
           0.5 * kPi * (2.0 * theta_w * so - std::cos(theta_o - 2.0 * theta_w) - 2.0 * theta_o * so + co);
}

// A leaf's lights: a group of members (LightTreeInput::group), their box, cone and energy.
struct Item {
    double lo[3], hi[3];
    Cone cone;
    double energy;
    uint64_t sets;  // light linking: its members' light sets (bit s)
    double radius;  // one member's own bounding sphere about the box centre (LightTreeInput::radius;
                    // infinite: the box's)
    int reach;      // what its smallest importance may count on (Reach::kind)
};

// Where every light of a node surely emits, for its smallest importance (LightTreeNode::cos_b):
// kind 0 nowhere (a light may give nothing anywhere: two-sided emitters, IES profiles, cones
// of every direction; inner nodes of kind-1 lights), 1 every way alike (a point lamp), 2 within theta_b - theta_s of the
// node's axis (each light within theta_b of its own axis, those within theta_s of the node's).
struct Reach {
    int kind;
    double s, b;
};

// A member's Reach kind: a cone of every direction with cos_e -1 is a light of the same
// intensity every way (LightTreeInput::cos_e); a narrower cone reaches within theta_o + theta_e.
int member_reach(const LightTreeInput& in, size_t i) {
    if (in.cos_o[i] <= -1.0f) return in.cos_e[i] <= -1.0f ? 1 : 0;
    return 2;
}

Cone member_cone(const LightTreeInput& in, size_t i) {
    Cone cone{};
    const double co = in.cos_o[i];
    cone.theta_o = co <= -1.0 ? kPi : std::acos(std::min(co, 1.0));
    cone.theta_e = std::acos(std::clamp(double(in.cos_e[i]), -1.0, 1.0));
    const double ax[3] = {in.axis[i], in.axis[in.m + i], in.axis[2 * in.m + i]};
    const double len = std::sqrt(dot3(ax, ax));
    for (int k = 0; k < 3; ++k) cone.axis[k] = len > 0 ? ax[k] / len : double(k == 2);
    if (!(len > 0)) cone.theta_o = kPi;
    return cone;
}

struct Builder {
    const std::vector<Item>& items;
    std::vector<LightTreeNode>& nodes;
    std::vector<int32_t>& leaf_of_item;
    std::vector<int32_t> order;

    double centroid(int32_t i, int k) const { return 0.5 * (items[size_t(i)].lo[k] + items[size_t(i)].hi[k]); }

    // Splits order[b, e) by Conty and Kulla's surface area orientation heuristic, as Cycles'
    // light tree builds: over 12 bins of the centres per axis, the split of least
    // sum over the halves of energy x box area x orientation measure, times the longest
    // extent over the axis' (favouring cuts across long axes). A bright light that emits one
    // way is so kept apart from lights that emit every way: grouped, the group would look
    // bright from everywhere its cone then covers. Returns the first item of the right half
    // (b or e: no split found).
    size_t saoh_split(size_t b, size_t e, const double clo[3], const double chi[3]) {
        constexpr int kBins = 12;
        struct Bin {
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            double energy = 0.0;
            Cone cone{};
            size_t count = 0;
            void add(const double l[3], const double h[3], double en, const Cone& c) {
                for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], l[k]), hi[k] = std::max(hi[k], h[k]);
                cone = count ? merge(cone, c) : c;
                energy += en;
                ++count;
            }
            void add(const Bin& o) {
                if (o.count) add(o.lo, o.hi, o.energy, o.cone), count += o.count - 1;
            }
            double cost(double pad) const {  // energy x area x orientation measure
                double d[3];
                for (int k = 0; k < 3; ++k) d[k] = hi[k] - lo[k] + pad;
                return energy * 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]) * measure(cone);
            }
        };
        double longest = 0.0;
        for (int k = 0; k < 3; ++k) longest = std::max(longest, chi[k] - clo[k]);
        if (!(longest > 0.0)) return b;
        const double pad = 1e-3 * longest;  // lights without extent still cost their energy
        double best = INFINITY;
        int best_axis = -1, best_cut = 0;
        for (int k = 0; k < 3; ++k) {
            const double extent = chi[k] - clo[k];
            if (!(extent > 1e-9 * longest)) continue;
            Bin bins[kBins];
            for (size_t j = b; j < e; ++j) {
                const Item& it = items[size_t(order[j])];
                bins[bin_of(order[j], k, clo[k], extent, kBins)].add(it.lo, it.hi, it.energy, it.cone);
            }
            Bin right[kBins];  // right[c]: bins c..kBins-1
            right[kBins - 1] = bins[kBins - 1];
            for (int c = kBins - 2; c >= 0; --c) {
                right[c] = right[c + 1];
                right[c].add(bins[c]);
            }
            Bin left;
            for (int cut = 1; cut < kBins; ++cut) {
                left.add(bins[cut - 1]);
                if (!left.count || !right[cut].count) continue;
                const double cost = (longest / extent) * (left.cost(pad) + right[cut].cost(pad));
                if (cost < best) best = cost, best_axis = k, best_cut = cut;
            }
        }
        if (best_axis < 0) return b;
        const double extent = chi[best_axis] - clo[best_axis];
        const auto first_right = std::stable_partition(order.begin() + long(b), order.begin() + long(e), [&](int32_t x) {
            return bin_of(x, best_axis, clo[best_axis], extent, kBins) < best_cut;
        });
        return size_t(first_right - order.begin());
    }

    // A node's reach from its children's (cones lc, rc and their reaches) about its cone's axis:
    // each child's axis spread widened by the angle between its axis and the node's (a bound),
    // the narrowest theta_b; lights alike every way add no condition.
    static Reach merge_reach(const Cone& cone, const Cone& lc, const Reach& lr, const Cone& rc, const Reach& rr) {
        if (lr.kind == 0 || rr.kind == 0) return {0, 0.0, 0.0};
        // (lights alike every way count at leaves only: an inner node of them, whose sphere holds
        // the points near it, would count 0 there and more than 0 far away, and so send the
        // near points' samples away; Cycles' inner node of point lights counts 0 everywhere)
        if (lr.kind == 1 && rr.kind == 1) return {0, 0.0, 0.0};
        Reach r{2, 0.0, kPi};
        const Cone* cs[2] = {&lc, &rc};
        const Reach* rs[2] = {&lr, &rr};
        for (int c = 0; c < 2; ++c) {
            if (rs[c]->kind != 2) continue;
            const double off = std::acos(std::clamp(dot3(cone.axis, cs[c]->axis), -1.0, 1.0)) + 1e-6;
            r.s = std::max(r.s, rs[c]->s + off);
            r.b = std::min(r.b, rs[c]->b);
        }
        if (!(r.s < r.b)) r.kind = 0;
        return r;
    }

    int bin_of(int32_t i, int k, double lo, double extent, int bins) const {
        const int c = int((centroid(i, k) - lo) / extent * bins);
        return std::clamp(c, 0, bins - 1);
    }

    // Fills node `at` over items order[b, e); returns its box (lo, hi), cone and reach.
    void build(size_t at, size_t b, size_t e, double lo[3], double hi[3], Cone& cone, Reach& reach) {
        double own_radius = INFINITY;
        if (e - b == 1) {
            const int32_t i = order[b];
            const Item& it = items[size_t(i)];
            for (int k = 0; k < 3; ++k) lo[k] = it.lo[k], hi[k] = it.hi[k];
            cone = it.cone;
            reach = {it.cone.theta_o >= kPi && it.reach == 2 ? 0 : it.reach, 0.0, it.cone.theta_o + it.cone.theta_e};
            own_radius = it.radius;
            nodes[at].energy = it.energy;
            nodes[at].child = -1 - i;
            leaf_of_item[size_t(i)] = int32_t(at);
        } else {
            double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (size_t j = b; j < e; ++j)
                for (int k = 0; k < 3; ++k) {
                    const double c = centroid(order[j], k);
                    clo[k] = std::min(clo[k], c);
                    chi[k] = std::max(chi[k], c);
                }
            size_t mid = saoh_split(b, e, clo, chi);
            if (mid == b || mid == e) {  // no split: all centres in one place (or bins)
                int axis = 0;
                for (int k = 1; k < 3; ++k)
                    if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
                mid = b + (e - b) / 2;
                // ties broken by item index: the halves (and so the tree) do not depend on
                // the standard library's partitioning
                std::nth_element(order.begin() + long(b), order.begin() + long(mid), order.begin() + long(e),
                                 [&](int32_t x, int32_t y) {
                                     const double cx = centroid(x, axis), cy = centroid(y, axis);
                                     return cx < cy || (cx == cy && x < y);
                                 });
            }
            const size_t child = nodes.size();
            nodes.resize(child + 2);
            double llo[3], lhi[3], rlo[3], rhi[3];
            Cone lc, rc;
            Reach lr, rr;
            build(child, b, mid, llo, lhi, lc, lr);
            build(child + 1, mid, e, rlo, rhi, rc, rr);
            for (int k = 0; k < 3; ++k) lo[k] = std::min(llo[k], rlo[k]), hi[k] = std::max(lhi[k], rhi[k]);
            cone = merge(lc, rc);
            reach = merge_reach(cone, lc, lr, rc, rr);
            nodes[at].energy = nodes[child].energy + nodes[child + 1].energy;
            nodes[at].child = int32_t(child);
        }
        LightTreeNode& nd = nodes[at];
        double r2 = 0.0, off2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double c = 0.5 * (lo[k] + hi[k]), h = 0.5 * (hi[k] - lo[k]);
            nd.center[k] = float(c);
            // the float centre is off the box's by up to half an ULP: the radius covers that
            const double off = std::fabs(double(nd.center[k]) - c);
            r2 += (h + off) * (h + off);
            off2 += off * off;
            nd.half[k] = float((h + off) * (1.0 + 1e-6));
        }
        // a lone light's own sphere where it is the tighter (moved by the centre's rounding)
        const double own = own_radius + std::sqrt(off2);
        nd.radius = float(std::min(std::sqrt(r2), own) * (1.0 + 1e-6));
        const bool all = cone.theta_o >= kPi;
        for (int k = 0; k < 3; ++k) nd.axis[k] = float(cone.axis[k]);
        nd.cos_o = all ? -1.0f : float(std::cos(cone.theta_o));
        nd.sin_o = all ? 0.0f : float(std::sin(cone.theta_o));
        nd.cos_e = float(std::cos(std::min(cone.theta_e, kPi / 2)));
        // (theta_b at most pi/2: the worst emission cosine counted is never below 0)
        nd.cos_b = reach.kind == 0 ? 2.0f : reach.kind == 1 ? -2.0f : float(std::cos(std::min(reach.b, kPi / 2)));
        nd.cos_s = reach.kind == 2 ? float(std::cos(reach.s)) : 1.0f;
        nd.sin_s = reach.kind == 2 ? float(std::sin(reach.s)) : 0.0f;
        // every direction the node's lights emit in lies within pi/2 of the axis: a point behind
        // the box's extent along the (stored) axis gets nothing (weigh)
        nd.slab = -1.0f;
        if (!all && cone.theta_o + cone.theta_e <= kPi / 2) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) s += std::fabs(double(nd.axis[k])) * double(nd.half[k]);
            nd.slab = float(s * (1.0 + 1e-6));
        }
    }
};

}  // namespace

std::string light_tree_error(const LightTreeInput& in) {
    if (in.m == 0) return "a light tree needs at least one light";
    if (in.m > (size_t(1) << 30)) return "a light tree holds at most 2^30 lights";
    std::vector<uint8_t> seen;
    for (size_t i = 0; i < in.m; ++i) {
        const auto at = [i] { return "light " + std::to_string(i) + ": "; };  // built on error only
        for (int k = 0; k < 3; ++k) {
            const float lo = in.lo[k * in.m + i], hi = in.hi[k * in.m + i], ax = in.axis[k * in.m + i];
            if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo <= hi)) return at() + "bounds must be finite with lo <= hi";
            if (!std::isfinite(ax)) return at() + "axis must be finite";
        }
        if (!(in.cos_o[i] >= -1.0f && in.cos_o[i] <= 1.0f) || !(in.cos_e[i] >= -1.0f && in.cos_e[i] <= 1.0f))
            return at() + "cos_o and cos_e must lie in [-1, 1]";
        // (a denormal energy's importances lose their bits: its pick probability came out inf)
        if (!(in.energy[i] >= std::numeric_limits<double>::min() && in.energy[i] <= 1e200))
            return at() + "energy must lie in [2.2250738585072014e-308 (the smallest normal double), 1e200]";
        if (in.group && in.group[i] < 0) return at() + "group must be >= 0";
        if (in.set && in.set[i] > 63) return at() + "set must lie in 0..63";
        if (in.radius && !(in.radius[i] >= 0.0f)) return at() + "radius must be >= 0 (inf: the box's)";
        const int32_t key = in.key[i];
        if (key < 0 || key >= (int32_t(1) << 30)) return at() + "key must lie in 0..2^30-1";
        if (size_t(key) >= seen.size()) seen.resize(size_t(key) + 1, 0);
        if (seen[size_t(key)]) return at() + "key " + std::to_string(key) + " is not unique";
        seen[size_t(key)] = 1;
    }
    return {};
}

LightTree::LightTree(const LightTreeInput& in) {
    const std::string err = light_tree_error(in);
    if (!err.empty()) throw std::invalid_argument(err);
    // members by group (stable: members keep their order inside a group), one item per group
    std::vector<int32_t> by(in.m);
    std::iota(by.begin(), by.end(), 0);
    if (in.group)
        std::stable_sort(by.begin(), by.end(), [&](int32_t x, int32_t y) { return in.group[x] < in.group[y]; });
    std::vector<Item> items;
    item_start_.clear();
    for (size_t j = 0; j < in.m; ++j) {
        const size_t i = size_t(by[j]);
        const bool fresh = j == 0 || !in.group || in.group[i] != in.group[size_t(by[j - 1])];
        if (fresh) {
            item_start_.push_back(int32_t(j));
            Item it{};
            for (int k = 0; k < 3; ++k) it.lo[k] = INFINITY, it.hi[k] = -INFINITY;
            it.cone = member_cone(in, i);
            it.radius = in.radius ? double(in.radius[i]) : INFINITY;
            it.reach = member_reach(in, i);
            items.push_back(it);
        } else {
            items.back().cone = merge(items.back().cone, member_cone(in, i));
            items.back().radius = INFINITY;     // a group: its box's sphere
            // (a group of lights alike every way stays so; any other is counted on nowhere)
            items.back().reach = items.back().reach == 1 && member_reach(in, i) == 1 ? 1 : 0;
        }
        Item& it = items.back();
        it.sets |= uint64_t(1) << (in.set ? in.set[i] : 0);
        for (int k = 0; k < 3; ++k) {
            it.lo[k] = std::min(it.lo[k], double(in.lo[k * in.m + i]));
            it.hi[k] = std::max(it.hi[k], double(in.hi[k * in.m + i]));
        }
        it.energy += in.energy[i];
    }
    item_start_.push_back(int32_t(in.m));
    // per member (in group order): its key and the cumulative share of its group's energy
    member_key_.resize(in.m);
    member_cdf_.resize(in.m);
    member_share_.resize(in.m);
    leaf_of_key_.assign(size_t(*std::max_element(in.key, in.key + in.m)) + 1, -1);
    slot_of_key_.assign(leaf_of_key_.size(), -1);
    for (size_t g = 0; g + 1 < item_start_.size(); ++g) {
        double run = 0.0;
        for (int32_t j = item_start_[g]; j < item_start_[g + 1]; ++j) {
            run += in.energy[size_t(by[size_t(j)])];
            member_key_[size_t(j)] = in.key[by[size_t(j)]];
            member_cdf_[size_t(j)] = run / items[g].energy;
            member_share_[size_t(j)] = in.energy[size_t(by[size_t(j)])] / items[g].energy;
            slot_of_key_[size_t(member_key_[size_t(j)])] = j;
        }
        member_cdf_[size_t(item_start_[g + 1] - 1)] = 1.0;
    }
    nodes_.reserve(2 * items.size() - 1);
    nodes_.resize(1);
    std::vector<int32_t> leaf_of_item(items.size());
    Builder bld{items, nodes_, leaf_of_item, std::vector<int32_t>(items.size())};
    std::iota(bld.order.begin(), bld.order.end(), 0);
    double lo[3], hi[3];
    Cone cone;
    Reach reach;
    bld.build(0, 0, items.size(), lo, hi, cone, reach);
    for (size_t g = 0; g < items.size(); ++g)
        for (int32_t j = item_start_[g]; j < item_start_[g + 1]; ++j)
            leaf_of_key_[size_t(member_key_[size_t(j)])] = leaf_of_item[g];
    if (in.set) {  // light linking: each node's sets, children (stored after their parent) first
        sets_.assign(nodes_.size(), 0);
        for (size_t at = nodes_.size(); at-- > 0;) {
            const int32_t c = nodes_[at].child;
            sets_[at] = c < 0 ? items[size_t(-1 - c)].sets : sets_[size_t(c)] | sets_[size_t(c) + 1];
        }
    }
    build_stops();
}

void LightTree::build_stops() {
    // From the root down: each stop's targets are its children's children (a leaf child: itself),
    // and each inner target is a stop in turn.
    stop_of_.assign(nodes_.size(), -1);
    hop_from_.assign(nodes_.size(), -1);
    hop_lane_.assign(nodes_.size(), 0);
    stops_.clear();
    stop_sets_.clear();
    std::vector<size_t> todo{0};
    while (!todo.empty()) {
        const size_t at = todo.back();
        todo.pop_back();
        if (nodes_[at].child < 0) continue;
        stop_of_[at] = int32_t(stops_.size());
        Stop q{};
        const size_t c = size_t(nodes_[at].child);
        for (int side = 0; side < 2; ++side) {
            const LightTreeNode& ch = nodes_[c + size_t(side)];
            const bool leaf = ch.child < 0;
            q.target[2 * side] = leaf ? int32_t(c) + side : ch.child;
            q.target[2 * side + 1] = leaf ? -1 : ch.child + 1;
        }
        for (int j = 0; j < 4; ++j) {
            const int32_t t = q.target[j];
            const bool inner = t >= 0 && nodes_[size_t(t)].child >= 0;
            q.node[2 * j] = inner ? nodes_[size_t(t)].child : t;
            q.node[2 * j + 1] = inner ? nodes_[size_t(t)].child + 1 : -1;
            if (t < 0) continue;
            hop_from_[size_t(t)] = int32_t(at);
            hop_lane_[size_t(t)] = uint8_t(j);
            if (inner) todo.push_back(size_t(t));
        }
        for (int k = 0; k < 8; ++k) {
            // an empty lane repeats lane 0's bounds (so it never pushes its four out of float's
            // range on its own) with no energy
            const LightTreeNode& nd = nodes_[size_t(q.node[k] < 0 ? q.node[0] : q.node[k])];
            for (int a = 0; a < 3; ++a) {
                q.center[a][k] = nd.center[a];
                q.half[a][k] = nd.half[a];
                q.axis[a][k] = nd.axis[a];
            }
            q.radius[k] = nd.radius;
            q.cos_o[k] = nd.cos_o;
            q.sin_o[k] = nd.sin_o;
            q.cos_e[k] = nd.cos_e;
            q.slab[k] = nd.slab;
            q.cos_b[k] = nd.cos_b;
            q.cos_s[k] = nd.cos_s;
            q.sin_s[k] = nd.sin_s;
            q.energy[k] = q.node[k] < 0 ? 0.0 : nd.energy;
        }
        stops_.push_back(q);
        if (!sets_.empty()) {  // light linking: the lanes' sets, then the targets'
            for (int k = 0; k < 8; ++k) stop_sets_.push_back(q.node[k] < 0 ? 0 : sets_[size_t(q.node[k])]);
            for (int j = 0; j < 4; ++j) stop_sets_.push_back(q.target[j] < 0 ? 0 : sets_[size_t(q.target[j])]);
        }
    }
}

inline void LightTree::probs_at(size_t at, const TreePoint& point, uint64_t receivers, double p[4]) const {
    const size_t qi = size_t(stop_of_[at]);
    const uint64_t* lane_sets = stop_sets_.empty() || receivers == kAllSets ? nullptr : stop_sets_.data() + 12 * qi;
    target_probs(nodes_.data(), stops_[qi], lane_sets, point, receivers, p);
}

// One stop of a walk: from the probabilities p of stop `at`'s targets, the target whose share of
// [lo, lo + w) holds u (the last possible one where rounding leaves u past them all); lo and w
// narrow to it. Without branches: which target a point takes is random, and a mispredicted
// pick stalled every stop. The shares' bounds are kept in a row and the pick found from bit
// masks, then read by index: GCC compiles a select between two doubles to a branch (the
// earlier selects of run and pick_lo did), but picks between ints to cmov.
inline size_t LightTree::step(size_t at, const double p[4], double u, double& lo, double& w) const {
    return size_t(stops_[size_t(stop_of_[at])].target[pick_of(p, u, lo, w)]);
}

inline int LightTree::pick_of(const double p[4], double u, double& lo, double& w) {
    double run[5];  // run[j]: where target j's share starts (+ 0 where impossible: unchanged)
    run[0] = lo;
    for (int j = 0; j < 4; ++j) run[j + 1] = run[j] + w * p[j];
    unsigned possible = 0, below = 0;
    for (int j = 0; j < 4; ++j) {
        possible |= unsigned(p[j] > 0.0) << j;
        below |= unsigned(u < run[j + 1]) << j;
    }
    const int last = possible ? 31 - __builtin_clz(possible) : 0;  // (none possible: target 0)
    const int first = __builtin_ctz((possible & below) | 16u);      // 4: u past them all
    const int pick = first < 4 ? first : last;
    lo = run[pick];
    w *= p[pick];
    return pick;
}

// std::upper_bound(a, a + n, t) - a for n >= 1 (the first i with t < a[i], else n; the same
// index for every t, NaN too), without branches: which member a walk ends at is random, and
// the search's mispredicted steps were ~8-10% of walk_rows' perf samples (README, manylights).
// The window [base, base + n] always holds the answer; each step halves it by one compare
// whose outcome moves base by an integer select (cmov).
inline size_t upper_slot(const double* a, size_t n, double t) {
    size_t base = 0;
    while (n > 1) {
        const size_t half = n / 2;
        base += t < a[base + half] ? 0 : half;
        n -= half;
    }
    return base + (t < a[base] ? 0 : 1);
}

// The walk's end at leaf `at`: a member of its group by energy, with what is left of u.
inline int32_t LightTree::leaf_pick(size_t at, double u, double lo, double w, double& prob) const {
    const size_t g = size_t(-1 - nodes_[at].child);
    const int32_t b = item_start_[g], e = item_start_[g + 1];
    int32_t slot = b;
    if (e - b > 1) {
        const double t = std::clamp(w > 0.0 ? (u - lo) / w : 0.0, 0.0, 1.0);
        slot = b + int32_t(upper_slot(member_cdf_.data() + b, size_t(e - b), t));
        slot = std::min(slot, e - 1);
        w *= member_share_[size_t(slot)];
    }
    prob = w;
    return member_key_[size_t(slot)];
}

int32_t LightTree::sample(const float P[3], const float* N, double u, double& prob, uint64_t receivers) const {
    // u stays as drawn; the node's share of [0, 1) narrows to [lo, lo + w) on the way down
    // (no rescaling of u: one division per stop, in the probabilities)
    size_t at = 0;
    double lo = 0.0, w = 1.0;
    if (!(u >= 0.0)) u = 0.0;  // (NaN too)
    TreePoint point;
    tree_point(point, P, N);
    while (nodes_[at].child >= 0) {
        double p[4];
        probs_at(at, point, receivers, p);
        at = step(at, p, u, lo, w);
    }
    return leaf_pick(at, u, lo, w, prob);
}

// sample_rows' points, kRows at a time, kept in walk order: a stop's walks [b, e) hold
// positions b.. e - 1 of one of two sets of rows (Walks), from which the stop's lanes weigh them
// in place and pick_rows narrows their lo and w in place; the regroup by target then moves each
// walk (coordinates, normal, u, lo, w and its point's index) into the other set, where the
// next stops find their walks side by side. (Kept by index instead, each stop had copied its
// walks' six coordinates and u, lo, w out to rows and lo, w back: ~35% of walk_rows' perf
// samples, loads scattered by index.) A child stop writes its regroup into the rows its parent
// read, within its own range: the parent is done with them.
struct LightTree::Rows {
    static constexpr size_t kRows = 512, kPad = 16;
    struct Walks {
        float rows[6][kRows + kPad];  // P, N (padded to 16 for the lanes; zeros: no normals)
        double u[kRows], lo[kRows], w[kRows];
        int32_t id[kRows];            // the point's index from base
    };
    bool normal;
    const uint64_t* receivers;  // (per point, null: every set)
    size_t base;                // the first point's index in sample_rows' arrays
    Walks walks[2];             // a stop at depth d reads walks[d % 2], regroups into the other
    uint8_t pick[kRows];
    double t[4][kRows], tm[4][kRows];  // each target's summed importance, largest and smallest
    float g[8][kRows + kPad], gmin[8][kRows + kPad];
    int32_t ok[8][kRows + kPad];
    int32_t fours[2][kRows];  // per walk: lanes 0-3's, 4-7's ok ANDed (-1: in float's range)
};

namespace {

typedef double D4 __attribute__((vector_size(32)));
typedef int64_t L4 __attribute__((vector_size(32)));

// probs_of's shares and pick_of's pick for the walks [0, m) at a stop, four side by side: each
// walk's targets' summed importances t[j][i] (pe: the shares by energy, where their sum is 0 or
// not finite), its u, lo and w (lo, w narrowed in place), its pick into pick[i]. Each lane meets
// the scalar steps' IEEE operations in their order (no contraction: -ffp-contract=off), so the
// same bits; the selects of pick_of's bit masks become lane masks. The scalar pass waited on
// each walk's chain of sums, the division and the pick's dependent load (~1/8 of walk_rows'
// perf samples on one load): four walks per vector overlap those chains.
// Copies per instruction set (as treelanes.cpp), chosen by lane_copy so that DACRT_ISA can pick
// a narrower one and the per-ISA test compares them.
using TargetRows = const double (*)[LightTree::Rows::kRows];
using PickRowsFn = void (*)(TargetRows t, TargetRows tm, const double pe[4], const double* u, double* lo, double* w,
                            size_t m, uint8_t* pick);
inline __attribute__((always_inline)) void pick_rows(TargetRows t, TargetRows tm, const double pe[4], const double* u,
                                                     double* lo, double* w, size_t m, uint8_t* pick) {
    size_t i = 0;
    for (; i + 4 <= m; i += 4) {
        D4 tj[4], mj[4], uv, lov, wv;
        for (int j = 0; j < 4; ++j) std::memcpy(&tj[j], t[j] + i, sizeof(D4));
        for (int j = 0; j < 4; ++j) std::memcpy(&mj[j], tm[j] + i, sizeof(D4));
        std::memcpy(&uv, u + i, sizeof(D4));
        std::memcpy(&lov, lo + i, sizeof(D4));
        std::memcpy(&wv, w + i, sizeof(D4));
        D4 s = D4{} + 0.0, sm = D4{} + 0.0;
        for (int j = 0; j < 4; ++j) {
            s += tj[j];
            sm += mj[j];
        }
        const D4 inv = 1.0 / s, inv_m = 1.0 / sm;
        const D4 inf = D4{} + INFINITY;  // s > 0 and finite, its inverse too (not subnormal)
        const L4 ok = (s > 0.0) & (s < inf) & (inv < inf);
        const L4 ok_m = (sm > 0.0) & (sm < inf) & (inv_m < inf);
        D4 p[4], run[5];
        run[0] = lov;
        for (int j = 0; j < 4; ++j) {  // share()'s operations
            const D4 by_max = tj[j] * inv;
            p[j] = ok ? (ok_m ? 0.5 * (by_max + mj[j] * inv_m) : by_max) : D4{} + pe[j];
            run[j + 1] = run[j] + wv * p[j];
        }
        L4 last = L4{}, first = L4{} + 4;
        for (int j = 0; j < 4; ++j) last = p[j] > 0.0 ? L4{} + j : last;
        for (int j = 3; j >= 0; --j) first = (p[j] > 0.0) & (uv < run[j + 1]) ? L4{} + j : first;
        const L4 k = first < 4 ? first : last;
        D4 nlo = run[0], pk = p[0];
        for (int j = 1; j < 4; ++j) {
            nlo = k == j ? run[j] : nlo;
            pk = k == j ? p[j] : pk;
        }
        wv *= pk;
        std::memcpy(lo + i, &nlo, sizeof(D4));
        std::memcpy(w + i, &wv, sizeof(D4));
        for (int a = 0; a < 4; ++a) pick[i + size_t(a)] = uint8_t(k[a]);
    }
    for (; i < m; ++i) {  // the last 1-3 as probs_of and pick_of
        double s = 0.0, sm = 0.0;
        for (int j = 0; j < 4; ++j) {
            s += t[j][i];
            sm += tm[j][i];
        }
        double p[4];
        const double inv = 1.0 / s, inv_m = 1.0 / sm;
        const bool ok = s > 0.0 && std::isfinite(s) && std::isfinite(inv),
                   ok_m = sm > 0.0 && std::isfinite(sm) && std::isfinite(inv_m);
        for (int j = 0; j < 4; ++j) p[j] = ok ? share(t[j][i], tm[j][i], inv, inv_m, ok_m) : pe[j];
        double run[5];
        run[0] = lo[i];
        for (int j = 0; j < 4; ++j) run[j + 1] = run[j] + w[i] * p[j];
        unsigned possible = 0, below = 0;
        for (int j = 0; j < 4; ++j) {
            possible |= unsigned(p[j] > 0.0) << j;
            below |= unsigned(u[i] < run[j + 1]) << j;
        }
        const int last = possible ? 31 - __builtin_clz(possible) : 0;
        const int first = __builtin_ctz((possible & below) | 16u);
        const int k = first < 4 ? first : last;
        lo[i] = run[k];
        w[i] *= p[k];
        pick[i] = uint8_t(k);
    }
}

#define DACRT_PICK_ISA(NAME, TARGET)                                                                       \
    TARGET void NAME##_pick_rows(TargetRows t, TargetRows tm, const double pe[4], const double* u, double* lo, \
                                 double* w, size_t m, uint8_t* pick) {                                     \
        pick_rows(t, tm, pe, u, lo, w, m, pick);                                                           \
    }
DACRT_PICK_ISA(portable, )
DACRT_PICK_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_PICK_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

// A stop's target sums for the walks [0, m) from its lanes' row weighs (r.g, r.gmin): each
// target's summed importance t[j][i] = e_a g_a + e_c g_c (its lanes' energies times their weighs,
// in float64; a target of one lane e_a g_a alone, none 0) and smallest tm[j][i] likewise; and
// per four lanes whether all their distances lay in float's range at walk i (r.fours: the filled
// lanes' ok ANDed, an empty lane among 4-7 by lane 0's, see walk_rows). Elementwise IEEE
// operations (no contraction), so every copy gives the bits of the scalar passes it replaced;
// copies per instruction set because the generic build ran them two doubles a vector (SSE2: a
// quarter of walk_rows' perf samples, the lanes' ok rows ANDed another tenth).
using TargetSumsFn = void (*)(const LightTree::Stop& q, LightTree::Rows& r, size_t m, bool empty_hi);
inline __attribute__((always_inline)) void target_sums(const LightTree::Stop& q, LightTree::Rows& r, size_t m,
                                                       bool empty_hi) {
    for (int j = 0; j < 4; ++j) {
        double* const t = r.t[j];
        double* const tm = r.tm[j];
        const int a = 2 * j, cl = 2 * j + 1;
        if (q.target[j] < 0) {
            for (size_t i = 0; i < m; ++i) t[i] = 0.0, tm[i] = 0.0;
            continue;
        }
        const double ea = q.energy[a];
        const float* const ga = r.g[a];
        const float* const gma = r.gmin[a];
        if (q.node[cl] < 0) {  // (+ an empty lane's 0.0: t >= +0 or NaN, the same; left out)
            for (size_t i = 0; i < m; ++i) t[i] = ea * double(ga[i]);
            for (size_t i = 0; i < m; ++i) tm[i] = ea * double(gma[i]);
            continue;
        }
        const double ec = q.energy[cl];
        const float* const gc = r.g[cl];
        const float* const gmc = r.gmin[cl];
        for (size_t i = 0; i < m; ++i) t[i] = ea * double(ga[i]) + ec * double(gc[i]);
        for (size_t i = 0; i < m; ++i) tm[i] = ea * double(gma[i]) + ec * double(gmc[i]);
    }
    for (int h = 0; h < 2; ++h) {
        int32_t* const f = r.fours[h];
        const int32_t* ok[5];
        int n = 0;
        for (int k = 4 * h; k < 4 * h + 4; ++k)
            if (q.node[k] >= 0) ok[n++] = r.ok[k];
        if (h == 1 && empty_hi) ok[n++] = r.ok[0];
        for (size_t i = 0; i < m; ++i) f[i] = -1;
        for (int k = 0; k < n; ++k) {
            const int32_t* const o = ok[k];
            for (size_t i = 0; i < m; ++i) f[i] &= o[i];
        }
    }
}

#define DACRT_SUMS_ISA(NAME, TARGET)                                                                   \
    TARGET void NAME##_sums(const LightTree::Stop& q, LightTree::Rows& r, size_t m, bool empty_hi) {   \
        target_sums(q, r, m, empty_hi);                                                                \
    }
DACRT_SUMS_ISA(portable, )
DACRT_SUMS_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))))
DACRT_SUMS_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))))

}  // namespace

// Point i's eight importances at stop q from its row weighs (an empty lane 0.0), and which of
// its fours have a distance out of float's range (bit 0: lanes 0-3, bit 1: 4-7; an empty lane
// repeats lane 0's bounds, so lane 0 decides for it: empty_hi, an empty lane among 4-7).
inline int lane_imps(const LightTree::Stop& q, const LightTree::Rows& r, size_t i, bool empty_hi, double imp[8],
                     double imin[8]) {
    int bad = empty_hi && !r.ok[0][i] ? 2 : 0;
    for (int k = 0; k < 8; ++k) {
        const bool lane = q.node[k] >= 0;
        imp[k] = lane ? q.energy[k] * double(r.g[k][i]) : 0.0;
        imin[k] = lane ? q.energy[k] * double(r.gmin[k][i]) : 0.0;
        if (lane && !r.ok[k][i]) bad |= k < 4 ? 1 : 2;
    }
    return bad;
}

// The walks at positions [b, e) of walks[depth % 2], all at stop node `at`, each on its own to
// its leaf as sample() walks (the same bits: test_light_tree_lanes). walk_rows hands a stop's
// walks here when fewer than kRowsFrom reach it: its rows are weighed 16 points at a time per
// filled lane, so a stop of 1-3 points weighed as many lanes as 16 (300- to 3000-light trees,
// whose deeper stops split a chunk into such batches: tree.sample 449-514 -> 353-365 ns a
// point with 3000 lights).
void LightTree::walk_each(const Rows& r, size_t depth, size_t at, size_t b, size_t e, int32_t key[],
                          double prob[]) const {
    const Rows::Walks& c = r.walks[depth % 2];
    for (size_t i = b; i < e; ++i) {
        const size_t o = r.base + size_t(c.id[i]);
        const float P[3] = {c.rows[0][i], c.rows[1][i], c.rows[2][i]}, N[3] = {c.rows[3][i], c.rows[4][i], c.rows[5][i]};
        TreePoint point;
        tree_point(point, P, r.normal ? N : nullptr);
        const uint64_t rec = r.receivers ? r.receivers[o] : kAllSets;
        const double u = c.u[i];
        double lo = c.lo[i], w = c.w[i];
        size_t s = at;
        while (nodes_[s].child >= 0) {
            double p[4];
            probs_at(s, point, rec, p);
            s = step(s, p, u, lo, w);
        }
        key[o] = leaf_pick(s, u, lo, w, prob[o]);
    }
}

// The walks at positions [b, e) of walks[depth % 2], all at stop node `at`: their lanes weighed
// row by row, each walk's step (probs_of, step: sample()'s), then on by target, stop by stop, to
// their leaves.
void LightTree::walk_rows(Rows& r, size_t depth, size_t at, size_t b, size_t e, int32_t key[], double prob[]) const {
    static const LaneRowsFn weigh_rows = lane_rows_fn();
    constexpr size_t kRowsFrom = 4;
    const size_t qi = size_t(stop_of_[at]), m = e - b;
    if (m < kRowsFrom) {
        walk_each(r, depth, at, b, e, key, prob);
        return;
    }
    const Stop& q = stops_[qi];
    Rows::Walks& c = r.walks[depth % 2];
    const TreeRows rows{{c.rows[0] + b, c.rows[1] + b, c.rows[2] + b},
                        {r.normal ? c.rows[3] + b : nullptr, c.rows[4] + b, c.rows[5] + b}};
    // An empty lane (no node) weighs 0 and repeats lane 0's bounds (build_stops), so its
    // distances are in float's range where lane 0's are: only that decides for its four.
    bool empty_hi = false;
    for (int k = 0; k < 8; ++k) {
        if (q.node[k] >= 0)
            weigh_rows(q, k, rows, m, r.g[k], r.gmin[k], r.ok[k]);
        else
            empty_hi |= k >= 4;
    }
    const uint64_t* sets = stop_sets_.empty() ? nullptr : stop_sets_.data() + 12 * qi;
    if (sets && r.receivers) {  // light linking: a walk at a time, its lanes masked by its sets
        for (size_t i = 0; i < m; ++i) {
            const size_t at_i = b + i;
            double imp[8], imin[8];
            const float P[3] = {c.rows[0][at_i], c.rows[1][at_i], c.rows[2][at_i]},
                        N[3] = {c.rows[3][at_i], c.rows[4][at_i], c.rows[5][at_i]};
            const int bad = lane_imps(q, r, i, empty_hi, imp, imin);
            if (bad) exact_halves(nodes_.data(), q, bad, P, r.normal ? N : nullptr, imp, imin);
            const uint64_t rec = r.receivers[r.base + size_t(c.id[at_i])];
            double p[4];
            probs_of(nodes_.data(), q, rec == kAllSets ? nullptr : sets, rec, imp, imin, p);
            r.pick[i] = uint8_t(pick_of(p, c.u[at_i], c.lo[at_i], c.w[at_i]));
        }
    } else {
        // probs_of's steps pass by pass over the points (each target's summed importance, the
        // four walks of a stop whose distances left float's range redone, then the shares and
        // the pick), so that the walks overlap: the same operations per walk
        static const TargetSumsFn sums = lane_copy<TargetSumsFn>(portable_sums, avx2_sums, avx512_sums);
        sums(q, r, m, empty_hi);
        int32_t* const fours[2] = {r.fours[0], r.fours[1]};
        for (size_t i = 0; i < m; ++i) {
            if ((fours[0][i] & fours[1][i]) == -1) continue;
            const int bad = (fours[0][i] ? 0 : 1) | (fours[1][i] ? 0 : 2);
            double imp[8], imin[8];
            lane_imps(q, r, i, empty_hi, imp, imin);
            const size_t at_i = b + i;
            const float P[3] = {c.rows[0][at_i], c.rows[1][at_i], c.rows[2][at_i]},
                        N[3] = {c.rows[3][at_i], c.rows[4][at_i], c.rows[5][at_i]};
            exact_halves(nodes_.data(), q, bad, P, r.normal ? N : nullptr, imp, imin);
            for (int j = 0; j < 4; ++j) {
                r.t[j][i] = q.target[j] >= 0 ? imp[2 * j] + imp[2 * j + 1] : 0.0;
                r.tm[j][i] = q.target[j] >= 0 ? imin[2 * j] + imin[2 * j + 1] : 0.0;
            }
        }
        double pe[4];  // where all importances are 0 (or their sum is not finite): by energy
        {
            double en = 0.0;
            for (int j = 0; j < 4; ++j) en += q.target[j] >= 0 ? nodes_[size_t(q.target[j])].energy : 0.0;
            const double inv = 1.0 / en;
            for (int j = 0; j < 4; ++j) pe[j] = q.target[j] >= 0 ? nodes_[size_t(q.target[j])].energy * inv : 0.0;
        }
        static const PickRowsFn pick = lane_copy<PickRowsFn>(portable_pick_rows, avx2_pick_rows, avx512_pick_rows);
        pick(r.t, r.tm, pe, c.u + b, c.lo + b, c.w + b, m, r.pick);
    }
    // where every target is a leaf (or none), each walk picks its light where it stands: the
    // regroup below would copy its six rows, u, lo, w and id only for leaf_pick to read u, lo and
    // w back (the last stop of most walks; leaf_pick reads the same values, so the same bits)
    bool inner = false;
    for (int j = 0; j < 4; ++j) inner |= q.target[j] >= 0 && nodes_[size_t(q.target[j])].child >= 0;
    if (!inner) {
        for (size_t i = 0; i < m; ++i) {
            const size_t at_i = b + i, o = r.base + size_t(c.id[at_i]);
            key[o] = leaf_pick(size_t(q.target[r.pick[i]]), c.u[at_i], c.lo[at_i], c.w[at_i], prob[o]);
        }
        return;
    }
    // the walks regrouped by target into the other rows: counts and cursors kept in registers
    // and chosen by masks (a histogram in memory, ++count[pick] and tmp[fill[pick]++], chained
    // each walk to the last one's store: ~11% of walk_rows' perf samples)
    size_t count[4] = {};
    for (size_t i = 0; i < m; ++i)
        for (int j = 0; j < 4; ++j) count[j] += r.pick[i] == j;
    size_t start[5] = {b};
    for (int j = 0; j < 4; ++j) start[j + 1] = start[j] + count[j];
    Rows::Walks& nx = r.walks[(depth + 1) % 2];
    {
        size_t f0 = start[0], f1 = start[1], f2 = start[2], f3 = start[3];
        for (size_t i = 0; i < m; ++i) {
            const size_t k = r.pick[i], from = b + i;
            const size_t m0 = -size_t(k == 0), m1 = -size_t(k == 1), m2 = -size_t(k == 2), m3 = -size_t(k == 3);
            const size_t to = (f0 & m0) | (f1 & m1) | (f2 & m2) | (f3 & m3);
            for (int f = 0; f < 6; ++f) nx.rows[f][to] = c.rows[f][from];
            nx.u[to] = c.u[from], nx.lo[to] = c.lo[from], nx.w[to] = c.w[from];
            nx.id[to] = c.id[from];
            f0 -= m0, f1 -= m1, f2 -= m2, f3 -= m3;
        }
    }
    for (int j = 0; j < 4; ++j) {
        if (!count[j]) continue;
        const size_t t = size_t(q.target[j]), jb = start[j], je = start[j + 1];
        if (nodes_[t].child >= 0) {
            walk_rows(r, depth + 1, t, jb, je, key, prob);
            continue;
        }
        for (size_t i = jb; i < je; ++i) {
            const size_t o = r.base + size_t(nx.id[i]);
            key[o] = leaf_pick(t, nx.u[i], nx.lo[i], nx.w[i], prob[o]);
        }
    }
}

void LightTree::sample_rows(size_t count, const float* P, const float* N, size_t stride, const double u[],
                            const uint64_t* receivers, int32_t key[], double prob[]) const {
    std::unique_ptr<Rows> r(new Rows);
    r->normal = N != nullptr;
    r->receivers = receivers;
    Rows::Walks& c = r->walks[0];
    for (size_t b = 0; b < count; b += Rows::kRows) {
        const size_t m = std::min(Rows::kRows, count - b);
        r->base = b;
        for (size_t a = 0; a < 3; ++a)
            for (size_t i = 0; i < m; ++i)
                c.rows[a][i] = P[a * stride + b + i], c.rows[3 + a][i] = N ? N[a * stride + b + i] : 0.0f;
        for (size_t i = 0; i < m; ++i) {
            c.u[i] = u[b + i] >= 0.0 ? u[b + i] : 0.0;  // (NaN too)
            c.lo[i] = 0.0, c.w[i] = 1.0;
            c.id[i] = int32_t(i);
        }
        if (nodes_[0].child >= 0) {
            walk_rows(*r, 0, 0, 0, m, key, prob);
            continue;
        }
        for (size_t i = 0; i < m; ++i) key[b + i] = leaf_pick(0, c.u[i], c.lo[i], c.w[i], prob[b + i]);
    }
}

void LightTree::stop_weighs(const float P[3], const float* N, double* lanes, double* exact, double* lanes_min,
                            double* exact_min) const {
    TreePoint point;
    tree_point(point, P, N);
    for (size_t s = 0; s < stops_.size(); ++s) {
        double lmin[8];
        lane_weighs(nodes_.data(), stops_[s], point, lanes + 8 * s, lmin);
        for (int k = 0; k < 8; ++k) {
            const int32_t at = stops_[s].node[k];
            double emin = 0.0;
            exact[8 * s + size_t(k)] = at < 0 ? 0.0 : weigh(nodes_[size_t(at)], P, N, emin);
            if (lanes_min) lanes_min[8 * s + size_t(k)] = lmin[k];
            if (exact_min) exact_min[8 * s + size_t(k)] = emin;
        }
    }
}

double LightTree::pdf(const float P[3], const float* N, int64_t key, uint64_t receivers) const {
    if (!member(key)) return 0.0;
    size_t at = size_t(leaf_of_key_[size_t(key)]);
    double p = member_share_[size_t(slot_of_key_[size_t(key)])];
    TreePoint point;
    tree_point(point, P, N);
    while (at != 0) {  // up the walk's stops to the root
        const size_t from = size_t(hop_from_[at]);
        double lp[4];
        probs_at(from, point, receivers, lp);
        p *= lp[hop_lane_[at]];
        at = from;
    }
    return p;
}

double LightTree::pdf(const float P[3], const float* normals, size_t n, size_t i, int64_t key,
                      uint64_t receivers) const {
    if (!normals) return pdf(P, nullptr, key, receivers);
    const float N[3] = {normals[i], normals[n + i], normals[2 * n + i]};
    return pdf(P, N, key, receivers);
}

}  // namespace dacrt
