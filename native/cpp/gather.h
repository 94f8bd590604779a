// What lamp_gather (lamps.cpp) adds for each ray and lamp, and its arguments: gather_one, ray
// by ray, and gather_area_lanes (gatherlanes.cpp), the same for an area lamp eight rays at a
// time.
#pragma once

#include <cstddef>
#include <cstdint>

#include "lamps.h"
#include "shading.h"

namespace dacrt {

// lamp_gather's arguments (see lamps.h), passed by value like sample_range's.
struct Gather {
    const LampRecord* rec;
    const int32_t* lamps;
    size_t nl;
    const float *lamp_prob, *O, *D, *t_surf;
    Missed miss;
    const float *thr, *pdf_bsdf;
    const int64_t* pid;
    size_t n;
    float* L;
    size_t N;
    float clamp;
    const LightTree* tree;
    const int32_t* lamp_key;
    const float* normal;
    const uint64_t* receivers;
    size_t t_step;  // t_surf[i * t_step]: 4 reads the t of the tracer's hit records in place
};

// Adds radiance Le (solid-angle pdf pdf_l) of the lamp at list position k (tree key key) that
// ray i sees: the power heuristic against sampling it (BSDF rays), the throughput, the clamp.
__attribute__((always_inline)) inline void gather_add(const Gather& g, const float Le[3], float pdf_l, int32_t key,
                                                      size_t k, size_t i) {
    const size_t n = g.n;
    float w = 1.0f;
    if (g.lamp_prob) {  // power heuristic of this BSDF hit against sampling the lamp
        float p_sel = g.lamp_prob[g.lamps[k]];
        if (key >= 0) {  // as picked from o with the vertex's normal
            const float o[3] = {g.O[i], g.O[n + i], g.O[2 * n + i]};
            p_sel = float(double(p_sel) * g.tree->pdf(o, g.normal, n, i, key,
                                                      g.receivers ? g.receivers[i] : LightTree::kAllSets));
        }
        float r = p_sel * pdf_l / g.pdf_bsdf[i];
        r *= r;
        r += 1.0f;
        w = 1.0f / r;
    }
    float* out = g.L + index_at(g.pid, i, g.N);
    float v[3];
    for (int a = 0; a < 3; ++a) {
        v[a] = Le[a];
        if (g.thr) v[a] *= g.thr[size_t(a) * n + i];
        if (g.lamp_prob) v[a] *= w;
    }
    clamp_light(v, g.clamp);  // each lamp a ray meets is its own contribution, as in Cycles
    for (int a = 0; a < 3; ++a) out[size_t(a) * g.N] += v[a];
}

// Adds what ray i sees of the lamp at list position k (at_infinity(lamp) and tree key hoisted
// by the caller); nothing where it does not see the lamp.
__attribute__((always_inline)) inline void gather_one(const Gather& g, const LampRecord& lamp, bool infinite, int32_t key,
                                                      size_t k, size_t i) {
    const size_t n = g.n;
    const float o[3] = {g.O[i], g.O[n + i], g.O[2 * n + i]};
    const float d[3] = {g.D[i], g.D[n + i], g.D[2 * n + i]};
    float Le[3] = {0.0f, 0.0f, 0.0f}, pdf_l = 0.0f;
    const bool seen = infinite ? g.miss(i) && miss_lamp(lamp, d, Le, pdf_l)
                               : hit_lamp(lamp, o, d, g.t_surf[i * g.t_step], Le, pdf_l);
    // most rays see none of the lamps they are tested against (a sun's disk, a small lamp the
    // boxes or BVH list as near): they add nothing and are done, without the weight, the clamp and the
    // film's three read-modify-writes (many lights: 16.6 -> 14.9 ms of lamp_gather per render)
    if (!seen) return;
    gather_add(g, Le, pdf_l, key, k, i);
}

// gather_one for an area lamp without spread (area_lanes_apply) at list position k, tree key
// key, over rays [b, e) (gatherlanes.cpp).
void gather_area_lanes(const Gather& g, const LampRecord& lamp, int32_t key, size_t k, size_t b, size_t e);

}  // namespace dacrt
