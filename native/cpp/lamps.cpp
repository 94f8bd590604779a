// Batched, threaded lamp kernels (see lamps.h): light samples for the samples that picked a
// lamp, and what camera/BSDF rays see of the lamps, in one pass over the rays for all lamps
// instead of one numpy pass per lamp and operation.
#include "lamps.h"

#include <algorithm>
#include <vector>

#include "arealanes.h"
#include "gather.h"
#include "lampboxes.h"
#include "lampbvh.h"
#include "parallel.h"
#include "shading.h"

namespace dacrt {

std::string lamp_record_error(const LampRecord& r) {
    const float* f = reinterpret_cast<const float*>(&r);
    for (size_t k = 0; k < LAMP_RECORD_WIDTH; ++k)
        if (!std::isfinite(f[k])) return "field " + std::to_string(k) + " is not finite (" + std::to_string(f[k]) + ")";
    const int kind = int(r.kind), shape = int(r.shape);
    if (float(kind) != r.kind || kind < 0 || kind >= LAMP_NUM_KINDS)
        return "kind " + std::to_string(r.kind) + " is not a lamp kind code 0.." + std::to_string(LAMP_NUM_KINDS - 1);
    static const int shapes[LAMP_NUM_KINDS] = {3, 3, 2, 3, 1};  // shape codes per kind
    if (float(shape) != r.shape || shape < 0 || shape >= shapes[kind])
        return "shape " + std::to_string(r.shape) + " is not a shape code 0.." + std::to_string(shapes[kind] - 1) +
               " of lamp kind " + std::to_string(kind);
    // the divisors the formulas rely on
    if ((kind == LAMP_POINT || kind == LAMP_SPOT) && shape != POINT_DELTA && !(r.radius > 0))
        return "a point/spot lamp with a radius needs radius > 0";
    if (kind == LAMP_SUN && shape == SUN_CONE && !(r.omc > 0 && r.pdf > 0))
        return "a sun with an angle needs omc > 0 and pdf > 0";
    if (kind == LAMP_BACKGROUND && !(r.pdf > 0)) return "the background needs pdf > 0";
    if (kind == LAMP_AREA && !(r.area > 0)) return "an area lamp needs area > 0";
    if (r.ies != 0 && ((kind == LAMP_SUN && shape != SUN_CONE) || kind == LAMP_BACKGROUND))
        return "an IES profile applies to point, spot, area and sun (with an angle) lamps";
    if (std::string e = ies_id_error(r.ies); !e.empty()) return e;
    if ((r.falloff_power != 0 || r.falloff_smooth != 0) && (kind == LAMP_SUN || kind == LAMP_BACKGROUND))
        return "a Light Falloff applies to point, spot and area lamps (a sun's ray length is infinite)";
    if (!(r.falloff_power == 0 || r.falloff_power == 1 || r.falloff_power == 2) || !(r.falloff_smooth >= 0))
        return "falloff_power must be 0, 1 or 2 and falloff_smooth >= 0";
    return {};
}

namespace {

// Listed lamps from which lamp_gather goes ray by ray through its candidates (LampBoxes, or a
// LampBVH for more than 64 lamps) rather than lamp by lamp over the rays. Measured (1M cosine rays from a 40 m floor, 2 threads): 1 lamp 8 ns per
// ray either way; 2 lamps 15 vs 12 ns, also when the two nearly touch; 1024 lamps 7.5 us vs 58 ns.
constexpr size_t kLampBVHMin = 2;

// The loops take every argument by value, so they live in registers or the thread's own
// stack. Inside a parallel_for lambda they would be read through the captured references
// after every (not inlined) sample_lamp call, from the calling thread's stack frame, whose
// cache lines that thread keeps writing: measured 5-8x slower with two threads.
void sample_range(const LampRecord* rec, size_t R, const int32_t* entry, const float* P, const float* u1,
                  const float* u2, size_t n, float* wi, float* dist, float* value, float* pdf, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
        const int32_t j = entry[i];
        if (j < 0 || size_t(j) >= R) continue;  // another sampler's entry: untouched
        const float p[3] = {P[i], P[n + i], P[2 * n + i]};
        const LampSample s = sample_lamp(rec[j], p, u1[i], u2[i]);
        for (int a = 0; a < 3; ++a) {
            wi[size_t(a) * n + i] = s.wi[a];
            value[size_t(a) * n + i] = s.value[a];
        }
        dist[i] = s.dist;
        pdf[i] = s.pdf;
    }
}

inline int32_t tree_key(const Gather& g, size_t k) {  // the lamp's key in the light tree, or -1
    return g.tree && g.lamp_key ? g.lamp_key[g.lamps[k]] : -1;
}

// gather_one of a lamp at infinity (list position k) over rays [b, e), the rays that see it
// listed first, 64 at a time and without a branch per ray (which rays missed follows no
// pattern: ray by ray, the test mispredicted as environment_gather's had), then added in
// gather_one's operations, so the same bits.
void gather_infinite(const Gather& g, const LampRecord& lamp, int32_t key, size_t k, size_t b, size_t e) {
    const bool sun = int(lamp.kind) == LAMP_SUN;
    if (sun && int(lamp.shape) == SUN_DELTA) return;  // (never seen)
    constexpr size_t K = 64;
    uint32_t idx[K];
    const size_t n = g.n;
    const float *Dx = g.D, *Dy = g.D + n, *Dz = g.D + 2 * n;
    for (size_t i0 = b; i0 < e; i0 += K) {
        const size_t c = std::min(K, e - i0);
        size_t m = 0;
        for (size_t q = 0; q < c; ++q) {  // miss_lamp's test: a sun's disk, or everywhere
            const size_t i = i0 + q;
            const float d[3] = {Dx[i], Dy[i], Dz[i]};
            idx[m] = uint32_t(q);
            m += size_t(g.miss(i)) & size_t(!sun || in_sun_disk(lamp, d));
        }
        for (size_t q = 0; q < m; ++q) {  // each listed ray sees the lamp: miss_lamp's radiance
            const size_t i = i0 + idx[q];
            const float d[3] = {Dx[i], Dy[i], Dz[i]};
            float Le[3], pdf_l;
            infinite_radiance(lamp, d, Le, pdf_l);
            gather_add(g, Le, pdf_l, key, k, i);
        }
    }
}

// gather_range for a list of lamps at infinity only.
void gather_range_infinite(Gather g, size_t b, size_t e) {
    for (size_t k = 0; k < g.nl; ++k) gather_infinite(g, g.rec[g.lamps[k]], tree_key(g, k), k, b, e);
}

// Lamp by lamp over the rays (each ray still adds its lamps in list order).
void gather_range(Gather g, size_t b, size_t e) {
    for (size_t k = 0; k < g.nl; ++k) {
        const LampRecord& lamp = g.rec[g.lamps[k]];
        const bool infinite = at_infinity(lamp);
        const int32_t key = tree_key(g, k);
        if (area_lanes_apply(lamp)) {
            gather_area_lanes(g, lamp, key, k, b, e);
            continue;
        }
        for (size_t i = b; i < e; ++i) gather_one(g, lamp, infinite, key, k, i);
    }
}

// A list of up to 64 lamps as runs in list order: each either the bits of consecutive finite
// lamps (those the boxes may find) or one lamp at infinity.
struct ListRun {
    uint64_t finite;  // the run's list positions, a bit each; 0: the lamp at infinity at k
    size_t k;
};

std::vector<ListRun> list_runs(const LampRecord* rec, const int32_t* lamps, size_t nl) {
    std::vector<ListRun> runs;
    for (size_t k = 0; k < nl; ++k) {
        if (at_infinity(rec[lamps[k]]))
            runs.push_back({0, k});
        else if (!runs.empty() && runs.back().finite)
            runs.back().finite |= uint64_t(1) << k;
        else
            runs.push_back({uint64_t(1) << k, k});
    }
    return runs;
}

// gather_range's additions for lists of up to 64 lamps, kBlock rays at a time, run after run
// in list order (so each ray adds its lamps in list order): a run's finite lamps ray by ray
// over those whose boxes the ray may meet (LampBoxes, a bit each), a lamp at infinity over the
// block's rays that missed it (gather_infinite, without a branch per ray: a ray's bits for
// the sun and the world, taken with its box bits, had sent it through a loop whose length and
// lamp kinds followed no pattern). A delta lamp, or one a ray passes far from, adds nothing in
// gather_range either. Measured (lamp_gather, 256K random rays in a 16 x 8 x 3 m street among
// lamps of every kind, CPU per ray), against the LampBVH walk it replaced for these lists: 2
// lamps 23 -> 10.5 ns, 12 lamps 66 -> 19.5 ns, 64 lamps 132 -> 64 ns.
void gather_range_boxes(Gather g, const LampBoxes& boxes, const std::vector<ListRun>& runs, size_t b, size_t e) {
    constexpr size_t K = LampBoxes::kRays, kBlock = 8 * K;
    for (size_t i0 = b; i0 < e; i0 += kBlock) {
        const size_t count = std::min(kBlock, e - i0);
        uint64_t cand[kBlock] = {};
        if (!boxes.empty())
            for (size_t s = 0; s < count; s += K)
                boxes.meets(g.O, g.D, g.t_surf, g.t_step, g.n, i0 + s, std::min(K, count - s), cand + s);
        for (const ListRun& run : runs) {
            if (!run.finite) {
                gather_infinite(g, g.rec[g.lamps[run.k]], tree_key(g, run.k), run.k, i0, i0 + count);
                continue;
            }
            for (size_t q = 0; q < count; ++q) {
                for (uint64_t c = cand[q] & run.finite; c; c &= c - 1) {
                    const size_t k = size_t(__builtin_ctzll(c));
                    gather_one(g, g.rec[g.lamps[k]], false, tree_key(g, k), k, i0 + q);
                }
            }
        }
    }
}

// Ray by ray, over the lamps the BVH finds near it and those at infinity, in list order: the
// same additions in the same order as gather_range, without the lamps a ray passes far from
// (a delta lamp is never seen: the linear loop adds 0 for it). For lists of more than 64 lamps
// (shorter ones: gather_range_boxes), the candidates a list sorted per ray.
void gather_range_bvh(Gather g, const LampBVH& bvh, const std::vector<int32_t>& infinite, size_t b, size_t e) {
    std::vector<int32_t> cand;
    for (size_t i = b; i < e; ++i) {
        cand.clear();
        const float o[3] = {g.O[i], g.O[g.n + i], g.O[2 * g.n + i]};
        const float d[3] = {g.D[i], g.D[g.n + i], g.D[2 * g.n + i]};
        bvh.visit(o, d, g.t_surf[i * g.t_step], cand);
        if (!infinite.empty() && g.miss(i)) cand.insert(cand.end(), infinite.begin(), infinite.end());
        std::sort(cand.begin(), cand.end());
        for (int32_t k : cand) {
            const LampRecord& lamp = g.rec[g.lamps[k]];
            gather_one(g, lamp, at_infinity(lamp), tree_key(g, size_t(k)), size_t(k), i);
        }
    }
}

}  // namespace

void lamp_sample(const LampRecord* rec, size_t R, const int32_t* entry, const float* P, const float* u1,
                 const float* u2, size_t n, float* wi, float* dist, float* value, float* pdf) {
    parallel_for(n, [&](size_t b, size_t e) { sample_range(rec, R, entry, P, u1, u2, n, wi, dist, value, pdf, b, e); });
}

void lamp_gather(const LampRecord* rec, const int32_t* lamps, size_t nl, const float* lamp_prob, const float* O,
                 const float* D, const float* t_surf, Missed miss, const float* thr, const float* pdf_bsdf,
                 const int64_t* pid, size_t n, float* L, size_t N, float clamp, const LightTree* tree,
                 const int32_t* lamp_key, const float* normal, const uint64_t* receivers, size_t t_step) {
    const Gather g{rec,  lamps, nl, lamp_prob, O,     D,        t_surf, miss,   thr,      pdf_bsdf,
                   pid,  n,     L,  N,         clamp, tree,     lamp_key, normal, receivers, t_step};
    if (std::all_of(lamps, lamps + nl, [&](int32_t j) { return at_infinity(rec[j]); })) {
        // the sun and the world: lamp by lamp over the rays that missed (each ray still adds
        // its lamps in list order), no boxes or candidates
        parallel_for(n, [&](size_t b, size_t e) { gather_range_infinite(g, b, e); });
        return;
    }
    if (nl < kLampBVHMin) {
        parallel_for(n, [&](size_t b, size_t e) { gather_range(g, b, e); });
        return;
    }
    if (nl <= LampBoxes::kMaxLamps) {
        const LampBoxes boxes(rec, lamps, nl);
        const std::vector<ListRun> runs = list_runs(rec, lamps, nl);
        parallel_for(n, [&](size_t b, size_t e) { gather_range_boxes(g, boxes, runs, b, e); });
        return;
    }
    std::vector<int32_t> infinite;  // the sun and background among the lamps, in list order
    for (size_t k = 0; k < nl; ++k)
        if (at_infinity(rec[lamps[k]])) infinite.push_back(int32_t(k));
    const LampBVH bvh(rec, lamps, nl);
    parallel_for(n, [&](size_t b, size_t e) { gather_range_bvh(g, bvh, infinite, b, e); });
}

}  // namespace dacrt
