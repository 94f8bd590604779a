// A diffuse path vertex shaded in one pass (bounce.cpp): what continue_paths, next_event and
// cosine_scatter do one after another, each a threaded pass over every surviving path, done
// block by block while a block's columns are in cache: the survivors' throughputs and surface
// points, their light samples and shadow rays, and their bounce directions and rays. The same
// per-path code (survivor_range, event_range, scatter_range), so the same bits.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nextevent.h"
#include "ray.h"

namespace dacrt {

// The paths arriving at the vertex (n) and what shades them. hits, hit, live, albedo, thr and
// u_rr as survivors() and survivor_throughput() take them (hit null: the records' prim >= 0;
// u_rr null: no roulette); geo,
// normals (null: flat) and D as surface(); pid, keys and pick (null: none) the path columns
// the survivors keep; (nee_ka, nee_kb) the light sample's dimension words; with scatter,
// (ka, kb) the bounce direction's.
struct BounceIn {
    const Hit* hits;
    const uint8_t* hit;
    size_t n;
    const uint8_t* live;
    const float* albedo;
    size_t M;
    const float* geo;
    const float* normals;
    const float* D;
    const float* records;  // geo's hit-point records (hitrecords.h) or null: the rows
    const float* thr;
    const float* u_rr;
    const int64_t* pid;
    const uint32_t* keys;
    const double* pick;
    uint32_t nee_ka, nee_kb;
    float shorten;
    bool skip_work;
    bool scatter;
    uint32_t ka, kb;
    // rough diffuses (null: none; orennayar.h): each triangle's material (M), the materials'
    // Oren-Nayar terms (4 rows of rough_M, rough_rows' params) and colours (3 rows of rough_M):
    // light samples and the bounce take the factor
    const int32_t* rough_mat = nullptr;
    const float* rough_params = nullptr;
    const float* rough_rho = nullptr;
    size_t rough_M = 0;
    // drawn instead of taken (u_rr, pick null): with draw_rr, roulette by uniform_pick's second
    // uniform of pair (draw_ka, draw_kb) of the paths' keys (survivors_drawn); with draw_pick,
    // the survivors' pick, its first
    bool draw_rr = false, draw_pick = false;
    uint32_t draw_ka = 0, draw_kb = 0;
};

// The survivors' columns (k each, idx from survivors()): thr (3 rows), surf (P, ng, P_off and,
// with normals, ns: 12 or 9 rows), prim, pid, keys (2 rows), pick (null without); the light
// samples as next_event writes them (nee: value, contrib, rays, send, skip of k); with
// scatter, the bounce directions as cosine_scatter writes them (wi, pdf, ok, rays from P_off).
struct BounceOut {
    float* thr;
    float* surf;
    int32_t* prim;
    int64_t* pid;
    uint32_t* keys;
    double* pick;
    NextEventOut nee;
    float* wi;
    float* pdf;
    uint8_t* ok;
    Ray* rays;
};

// survivors() with the roulette uniforms drawn from the paths' keys (2 rows, stride n): the
// second uniform of uniform_pick(keys, ka, kb), the same bits without its array (survival.cpp).
size_t survivors_drawn(const Hit* hits, const uint8_t* hit, size_t n, const uint8_t* live, size_t M,
                       const float* thr, const uint32_t* keys, uint32_t ka, uint32_t kb, int64_t* idx,
                       size_t* dead_black, size_t* dead_rr);

// Shades the k survivors idx of in (survivors()) with light sampling from lights (no
// terminator, light linking or bump maps); returns the shadow rays written, *skipped the
// samples that could not contribute. Blocks go to whichever thread is free.
size_t shade_bounce(const BounceIn& in, const LightChoice& lights, const int64_t* idx, size_t k,
                    const BounceOut& out, size_t* skipped);

}  // namespace dacrt
