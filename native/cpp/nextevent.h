// Next-event estimation at a path vertex in one pass (nextevent.cpp): pick a light (lamps and
// emissive triangles share one selection table), sample it, weight the sample by MIS against
// the BSDF and write the shadow ray that tests it. Per vertex this replaces a dozen kernels and
// numpy steps, each its own pass over the paths' arrays, with one.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "environment.h"
#include "lamps.h"
#include "lighttree.h"
#include "ray.h"

namespace dacrt {

// What light sampling chooses from: entries 0..num_lamps-1 are lamps, num_lamps + j is
// emissive triangle j of tri_geo (15 rows of num_tris, as surface() reads; area per triangle;
// emission: radiance, 3 rows of num_tris), and the last, num_lamps + num_tris, is the
// environment map when env is not null. Per entry: cdf (the choice), prob (its probability),
// no_mis (sampled without MIS: weight 1, as a delta light), shadow (its samples need a shadow ray).
struct LightChoice {
    const LampRecord* lamps;
    size_t num_lamps;
    const float* tri_geo;
    const float* tri_area;
    const float* tri_emission;
    size_t num_tris;
    const EnvironmentMap* env;
    const double* cdf;
    const float* prob;
    const uint8_t* no_mis;
    const uint8_t* shadow;
    size_t entries;  // num_lamps + num_tris (+ 1 with env)
    // Light linking (null: none): each entry's light set (0..63); a point lights by an entry
    // only when bit light_set[entry] of its receiver mask (VertexPoints::receivers) is set.
    const uint8_t* light_set = nullptr;
    // Many lights (null: none): the entries that are the tree's members (keys) share one slot
    // of cdf (the others of them have no mass of their own) and each has prob = that slot's
    // mass; a pick that lands there picks the member by the tree at the point (lighttree.h),
    // its probability prob x the tree's.
    const LightTree* tree = nullptr;
    // (null: unknown) the triangle each emissive triangle entry is, in the points' prim
    // numbering: a point never lights itself from its own triangle (a plane emits nothing
    // into itself; from within rounding of it, solid-angle sampling saw half the sphere)
    const int32_t* tri_prim = nullptr;
    // (runs 0: none) cdf by runs of equal values (choiceruns.h): each run's value and first
    // entry, searched instead of the whole cdf, the same entries
    const double* run_cdf = nullptr;
    const uint32_t* run_entry = nullptr;
    size_t runs = 0;
};

// The entry whose share of the cdf holds u: std::upper_bound's over cdf (the last entry where u
// lies past them all, or is NaN), by the runs where L has them.
inline size_t cdf_entry(const LightChoice& L, double u) {
    if (L.runs) {
        const size_t r = size_t(std::upper_bound(L.run_cdf, L.run_cdf + L.runs, u) - L.run_cdf);
        return r < L.runs ? size_t(L.run_entry[r]) : L.entries - 1;
    }
    const size_t e = size_t(std::upper_bound(L.cdf, L.cdf + L.entries, u) - L.cdf);
    return e < L.entries ? e : L.entries - 1;
}

// The light entry a point at P (the shadow ray's origin, as a BSDF ray's MIS sees it) with
// shading normal N (and, with light linking, the receiver mask of its object) picks with the
// uniform u, and its selection probability.
inline size_t choose_light(const LightChoice& L, const float P[3], const float N[3], double u, float& p_sel,
                           uint64_t receivers = LightTree::kAllSets) {
    size_t e = cdf_entry(L, u);
    p_sel = L.prob[e];
    if (L.tree && L.tree->member(int64_t(e))) {
        const double lo = e ? L.cdf[e - 1] : 0.0, mass = L.cdf[e] - lo;
        double pt = 0.0;
        e = size_t(L.tree->sample(P, N, mass > 0 ? (u - lo) / mass : 0.0, pt, receivers));
        p_sel = float(double(L.prob[e]) * pt);
    }
    return e;
}

// Cycles' shadow terminator per triangle (pathvertex.h): the geometry offset's cutoff (null or
// 0: none, as on flat triangles) and the shading offset's frequency multiplier (null or <= 1:
// none), with the triangle table (15 rows of M), the corner normals (9 rows of M) and each
// point's barycentrics (u, v: n each) the lift is computed from (needed with a cutoff).
struct Terminator {
    const float* geo;
    const float* normals;
    size_t M;
    const float* cutoff;
    const float* freq;
    const float* u;
    const float* v;
};

// The n shading points of one vertex. P: surface points, P_off: shadow-ray origins; ns, ng:
// shading and geometric normals (ng null: same as ns; a light sample needs only to be in front
// of ns, as in Cycles, whose diffuse closure leaves the rest to the shadow ray); thr: throughput including this vertex's
// albedo (null: 1); all 3 rows of stride n. keys: path keys (2 rows), (ka, kb): the light
// position's dimension words; pick: the light-choice uniforms (null: entry 0, a single light);
// prim: the triangle each point lies on (null: no skip output). shorten: a shadow ray aimed
// at an emitter point ends that fraction of the way. skip_work false: every sample gets its
// shadow ray, those that cannot contribute with value 0 (the reference the skips are tested
// against). term (null: none; needs prim): the shadow terminator of the points' triangles.
struct VertexPoints {
    const float* P;
    const float* P_off;
    const float* ns;
    const float* ng;
    const float* thr;
    const uint32_t* keys;
    uint32_t ka, kb;
    const double* pick;
    const int32_t* prim;
    size_t n;
    float shorten;
    bool skip_work;
    const Terminator* term;
    const uint64_t* receivers = nullptr;  // light linking: the light sets each point receives (n)
    // normal maps: (4, n) the smooth normal before the map (rows 0-2; ns where there is none)
    // and the material's Bump Map Correction (row 3, 0 or 1): samples take bump_shadowing
    const float* bump = nullptr;
    // rough diffuse points (null: none): kRoughRows rows of n (orennayar.h); each sample takes
    // Cycles' Oren-Nayar factor over the view-averaged albedo
    const float* rough = nullptr;
};

// The entry point i picks and its selection probability p_sel: entry 0 without a pick, else
// choose_light at its shadow ray's origin with its shading normal (and receiver mask).
inline size_t pick_entry(const LightChoice& L, const VertexPoints& p, size_t i, float& p_sel) {
    p_sel = L.prob[0];
    if (!p.pick) return 0;
    const size_t n = p.n;
    const float Q[3] = {p.P_off[i], p.P_off[n + i], p.P_off[2 * n + i]};
    const float N[3] = {p.ns[i], p.ns[n + i], p.ns[2 * n + i]};
    return choose_light(L, Q, N, p.pick[i], p_sel, L.light_set && p.receivers ? p.receivers[i] : LightTree::kAllSets);
}

// value (3 rows of n): the sample's contribution, thr x radiance / pdf x cos/pi x MIS / p_sel;
// contrib[i] = 1 where it adds to the image unless its shadow ray is occluded. The shadow rays
// (ids 0..m-1, in path order) go to rays[0..m), their path columns to send and, with prim, the
// triangle each leaves to skip; rays, send and skip must hold n. Returns m; *skipped counts
// the samples that could not contribute (no shadow ray traced).
struct NextEventOut {
    float* value;
    uint8_t* contrib;
    Ray* rays;
    int64_t* send;
    int32_t* skip;
    int32_t* entry = nullptr;  // the entry each point picked (n; null: not wanted), e.g. for light groups
    // (3, n) the point sampled on an emissive triangle (just in front of it: the shadow ray's
    // target), e.g. to read a textured emission there; other entries leave theirs untouched
    float* point = nullptr;
};

size_t next_event(const LightChoice& lights, const VertexPoints& pts, const NextEventOut& out, size_t* skipped);

// next_event in pieces, for a pass that shades its points block by block (bounce.h): points
// [b, e) of a block of at most kEventBlock (b a multiple of it) write their shadow rays (each
// numbered by its position), send and skip to out from position b on, and return their count
// (*skipped: the samples that could not contribute). event_blocks runs block(q, &bad) for the
// blocks q < blocks on whichever worker is free (block returns event_range's count and bad) and
// moves each block's rays to follow the one before as the blocks are done, renumbering the
// moved ones, as next_event leaves them; it returns their number (*skipped: the bads' sum).
// Written in place, a block's rays had gone through a buffer of their own first: one more
// write and read of 48 bytes per ray (1-2% of a Cornell render's CPU).
// areas: draws_area_lanes(lights).
constexpr size_t kEventBlock = 4096;  // points per block: blocks compact their shadow rays on their own

bool draws_area_lanes(const LightChoice& lights);
size_t event_range(const LightChoice& lights, bool areas, const VertexPoints& pts, const NextEventOut& out, size_t b,
                   size_t e, size_t* skipped);
size_t event_blocks(const NextEventOut& out, size_t blocks, const std::function<size_t(size_t, size_t*)>& block,
                    size_t* skipped);

// L[:, pid[i]] (stride N) += values[:, i] (stride n) where mask[i], each clamped to clamp
// (clamp_light); pid distinct. False (L untouched) when some pid is outside 0..N-1.
bool accumulate_masked(float* L, size_t N, const int64_t* pid, const float* values, const uint8_t* mask, size_t n,
                       float clamp);

}  // namespace dacrt
