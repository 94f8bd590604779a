// The light tree (see lighttree.h): a build by the surface area orientation heuristic, cones
// merged as Cycles' light tree does, and the importance that splits a point's choice between
// two children.
#include "lighttree.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace dacrt {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Squared distances below this count as this: energy (< 1e210) / d2 stays finite.
constexpr double kMinDist2 = 1e-60;

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
// wholly below its horizon count 0.
double weigh(const LightTreeNode& nd, const float P[3], const float* N) {
    const double v[3] = {double(nd.center[0]) - P[0], double(nd.center[1]) - P[1], double(nd.center[2]) - P[2]};
    const double dd = dot3(v, v), r = nd.radius, r2 = r * r;
    if (N) {  // the box wholly below the tangent plane at P (its highest corner on or under it)
        const double reach = double(N[0]) * v[0] + double(N[1]) * v[1] + double(N[2]) * v[2] +
                             std::fabs(N[0]) * nd.half[0] + std::fabs(N[1]) * nd.half[1] + std::fabs(N[2]) * nd.half[2];
        if (!(reach > 0.0)) return 0.0;
    }
    // within the bounds (or NaN): no culling, and the distance to the centre at least half the
    // radius (Cycles)
    if (!(dd > r2)) return nd.energy / std::max(std::max(dd, 0.25 * r2), kMinDist2);
    double f = 1.0;
    const double d = std::sqrt(dd);
    const double sin_u = r / d, cos_u = std::sqrt(std::max(0.0, 1.0 - sin_u * sin_u));
    if (N) {  // the smallest angle of incidence any light of the node can have: theta_i - theta_u
        const double n[3] = {N[0], N[1], N[2]};
        const double cos_i = std::clamp(dot3(n, v) / d, -1.0, 1.0);
        if (cos_i < cos_u) {
            const double sin_i = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i));
            const double c = cos_i * cos_u + sin_i * sin_u;  // cos(theta_i - theta_u)
            if (!(c > 0.0)) return 0.0;
            f = c;
        }
    }
    if (nd.cos_o > -1.0f) {
        // phi = theta_o + theta_u: the widest angle from the axis at which a light of the node
        // can be seen from P's direction
        const double cos_p = nd.cos_o * cos_u - nd.sin_o * sin_u, sin_p = nd.sin_o * cos_u + nd.cos_o * sin_u;
        const double ax[3] = {nd.axis[0], nd.axis[1], nd.axis[2]};
        const double cos_t = std::clamp(-dot3(ax, v) / d, -1.0, 1.0);  // axis vs. node -> P
        if (sin_p >= 0.0 && cos_t < cos_p) {                           // phi <= pi and theta > phi
            const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
            const double cos_r = cos_t * cos_p + sin_t * sin_p;        // cos(theta - phi)
            if (cos_r <= nd.cos_e) return 0.0;
            f *= cos_r;
        }
    }
    return nd.energy * f / std::max(dd, kMinDist2);
}

// A node's importance at P: energy x f / d2 (weigh), looking one level further down for an
// inner node (the sum of its children's, whose tighter bounds see more: a group of spots all
// aimed away from P, or lights all behind its surface, is 0 even where their merged cone and
// sphere are not).
// With light linking (sets: each node's light sets, null: none), what a point lit by the sets
// in `receivers` cannot reach counts nothing.
double importance(const LightTreeNode* nodes, size_t at, const float P[3], const float* N,
                  const uint64_t* sets = nullptr, uint64_t receivers = LightTree::kAllSets) {
    const LightTreeNode& nd = nodes[at];
    if (nd.child < 0) return weigh(nd, P, N);
    const size_t c = size_t(nd.child);
    if (sets)
        return ((sets[c] & receivers) ? weigh(nodes[c], P, N) : 0.0) +
               ((sets[c + 1] & receivers) ? weigh(nodes[c + 1], P, N) : 0.0);
    return weigh(nodes[c], P, N) + weigh(nodes[c + 1], P, N);
}

// The probabilities of going to either of the two children c, c + 1 at P: by importance, by
// energy where both importances are 0 (or their sum is not finite). Each share is its own
// quotient, not 1 - the other: a faint light's 1e-19 would round to 0 that way, and a delta
// light must never become impossible.
struct Shares {
    double left, right;
};
Shares shares(const LightTreeNode* nodes, size_t c, const float P[3], const float* N,
              const uint64_t* sets = nullptr, uint64_t receivers = LightTree::kAllSets) {
    // light linking: a child holding none of the point's sets is never taken (unless neither
    // does: then the point is lit by no light of this node, and either way gives it nothing)
    const bool ra = !sets || (sets[c] & receivers), rb = !sets || (sets[c + 1] & receivers);
    if (ra != rb) return {ra ? 1.0 : 0.0, rb ? 1.0 : 0.0};
    const double a = importance(nodes, c, P, N, sets, receivers), b = importance(nodes, c + 1, P, N, sets, receivers);
    const double s = a + b;
    if (s > 0.0 && std::isfinite(s)) {
        const double inv = 1.0 / s;
        return {a * inv, b * inv};
    }
    const double inv = 1.0 / (nodes[c].energy + nodes[c + 1].energy);
    return {nodes[c].energy * inv, nodes[c + 1].energy * inv};
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
};

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

    int bin_of(int32_t i, int k, double lo, double extent, int bins) const {
        const int c = int((centroid(i, k) - lo) / extent * bins);
        return std::clamp(c, 0, bins - 1);
    }

    // Fills node `at` over items order[b, e); returns its box (lo, hi) and cone.
    void build(size_t at, size_t b, size_t e, int32_t parent, double lo[3], double hi[3], Cone& cone) {
        nodes[at].parent = parent;
        if (e - b == 1) {
            const int32_t i = order[b];
            const Item& it = items[size_t(i)];
            for (int k = 0; k < 3; ++k) lo[k] = it.lo[k], hi[k] = it.hi[k];
            cone = it.cone;
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
            build(child, b, mid, int32_t(at), llo, lhi, lc);
            build(child + 1, mid, e, int32_t(at), rlo, rhi, rc);
            for (int k = 0; k < 3; ++k) lo[k] = std::min(llo[k], rlo[k]), hi[k] = std::max(lhi[k], rhi[k]);
            cone = merge(lc, rc);
            nodes[at].energy = nodes[child].energy + nodes[child + 1].energy;
            nodes[at].child = int32_t(child);
        }
        LightTreeNode& nd = nodes[at];
        double r2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double c = 0.5 * (lo[k] + hi[k]), h = 0.5 * (hi[k] - lo[k]);
            nd.center[k] = float(c);
            // the float centre is off the box's by up to half an ULP: the radius covers that
            const double off = std::fabs(double(nd.center[k]) - c);
            r2 += (h + off) * (h + off);
            nd.half[k] = float((h + off) * (1.0 + 1e-6));
        }
        nd.radius = float(std::sqrt(r2) * (1.0 + 1e-6));
        const bool all = cone.theta_o >= kPi;
        for (int k = 0; k < 3; ++k) nd.axis[k] = float(cone.axis[k]);
        nd.cos_o = all ? -1.0f : float(std::cos(cone.theta_o));
        nd.sin_o = all ? 0.0f : float(std::sin(cone.theta_o));
        nd.cos_e = float(std::cos(std::min(cone.theta_e, kPi / 2)));
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
        if (!(in.energy[i] > 0.0 && in.energy[i] <= 1e200)) return at() + "energy must be > 0 and at most 1e200";
        if (in.group && in.group[i] < 0) return at() + "group must be >= 0";
        if (in.set && in.set[i] > 63) return at() + "set must lie in 0..63";
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
            items.push_back(it);
        } else {
            items.back().cone = merge(items.back().cone, member_cone(in, i));
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
    bld.build(0, 0, items.size(), -1, lo, hi, cone);
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
}

int32_t LightTree::sample(const float P[3], const float* N, double u, double& prob, uint64_t receivers) const {
    const uint64_t* sets = sets_.empty() || receivers == kAllSets ? nullptr : sets_.data();
    // u stays as drawn; the node's share of [0, 1) narrows to [lo, lo + w) on the way down
    // (no rescaling of u: one division per level, in shares)
    size_t at = 0;
    double lo = 0.0, w = 1.0;
    if (!(u >= 0.0)) u = 0.0;  // (NaN too)
    while (nodes_[at].child >= 0) {
        const size_t c = size_t(nodes_[at].child);
        const Shares sh = shares(nodes_.data(), c, P, N, sets, receivers);
        const double split = lo + w * sh.left;
        // selected, not branched on: which way a point goes follows no pattern
        const bool right = !(u < split) & (sh.right > 0.0);
        lo = right ? split : lo;
        w *= right ? sh.right : sh.left;
        at = c + size_t(right);
    }
    // the leaf's group: a member by energy, with what is left of u
    const size_t g = size_t(-1 - nodes_[at].child);
    const int32_t b = item_start_[g], e = item_start_[g + 1];
    int32_t slot = b;
    if (e - b > 1) {
        const double t = std::clamp(w > 0.0 ? (u - lo) / w : 0.0, 0.0, 1.0);
        slot = int32_t(std::upper_bound(member_cdf_.begin() + b, member_cdf_.begin() + e, t) - member_cdf_.begin());
        slot = std::min(slot, e - 1);
        w *= member_share_[size_t(slot)];
    }
    prob = w;
    return member_key_[size_t(slot)];
}

double LightTree::pdf(const float P[3], const float* N, int64_t key, uint64_t receivers) const {
    if (!member(key)) return 0.0;
    const uint64_t* sets = sets_.empty() || receivers == kAllSets ? nullptr : sets_.data();
    size_t at = size_t(leaf_of_key_[size_t(key)]);
    double p = member_share_[size_t(slot_of_key_[size_t(key)])];
    while (nodes_[at].parent >= 0) {
        const size_t up = size_t(nodes_[at].parent), c = size_t(nodes_[up].child);
        const Shares sh = shares(nodes_.data(), c, P, N, sets, receivers);
        p *= at == c ? sh.left : sh.right;
        at = up;
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
