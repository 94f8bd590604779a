// Next-event estimation at a path vertex in one pass (see nextevent.h). The steps and their
// float32 arithmetic are those of the separate kernels it fuses (uniform2_rows, the light
// choice, sample_lamp / triangle_light, nee_scale, shadow_record), so it gives the same bits.
#include "nextevent.h"
#include "orennayar.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "areadraws.h"
#include "arealanes.h"
#include "parallel.h"
#include "pathvertex.h"
#include "random.h"
#include "trianglelight.h"

namespace dacrt {

namespace {

// AREAS: some lamp is drawn lane by lane (area_lanes_apply): its points are drawn first per chunk
// (draw_chunk); also with a light tree, whose walks pick_entries takes side by side. ENV: an environment map, whose points' samples are drawn first per chunk too
// (environment_sample_lanes). Without either, the loop is that of one point at a time only: the
// chunk's arrays and its pass picking the entries first had cost scenes without area lamps ~11%.
template <bool AREAS, bool ENV>
size_t event_block(LightChoice L, VertexPoints p, const NextEventOut& out, size_t b, size_t e, size_t* skipped) {
    float* value_out = out.value;
    uint8_t* contrib = out.contrib;
    int32_t* entry_out = out.entry;
    float* point_out = out.point;
    const size_t n = p.n, T = L.num_tris;
    size_t m = b, bad = 0;
    struct Chunk {
        Drawn drawn[kWordChunk];
        uint8_t is_drawn[kWordChunk];
        uint32_t entries[kWordChunk];
        float sels[kWordChunk];
    };
    struct EnvChunk {  // the samples of the chunk's points that picked the map, in point order
        float u1[kWordChunk], u2[kWordChunk], wi[3 * kWordChunk], value[3 * kWordChunk], pdf[kWordChunk];
    };
    struct None {};
    std::conditional_t<AREAS || ENV, Chunk, None> c;
    std::conditional_t<ENV, EnvChunk, None> ec;
    const size_t env_entry = L.num_lamps + T;
    for_words(p.keys, n, p.ka, p.kb, b, e, [&](size_t i0, size_t cnt, const uint32_t* wa, const uint32_t* wb) {
        if constexpr (AREAS || ENV) pick_entries(L, p, i0, cnt, c.entries, c.sels);
        if constexpr (AREAS) draw_chunk(L, p, i0, cnt, c.entries, c.sels, wa, wb, c.drawn, c.is_drawn);
        [[maybe_unused]] size_t q = 0;  // ENV: the next of the chunk's map samples
        if constexpr (ENV) {
            size_t m_env = 0;
            for (size_t j = 0; j < cnt; ++j)
                if (c.entries[j] == env_entry) ec.u1[m_env] = unit24(wa[j]), ec.u2[m_env] = unit24(wb[j]), ++m_env;
            environment_sample_lanes(*L.env, ec.u1, ec.u2, m_env, ec.wi, ec.value, ec.pdf, kWordChunk);
        }
        for (size_t j = 0; j < cnt; ++j) {
            const size_t i = i0 + j;
            const float u1 = unit24(wa[j]), u2 = unit24(wb[j]);
            const float P[3] = {p.P[i], p.P[n + i], p.P[2 * n + i]};
            float p_sel;
            size_t entry;
            bool lanes = false;
            if constexpr (AREAS || ENV) {
                p_sel = c.sels[j];
                entry = c.entries[j];
                if constexpr (AREAS) lanes = c.is_drawn[j];
            } else {
                entry = pick_entry(L, p, i, p_sel);
            }
            if (entry_out) entry_out[i] = int32_t(entry);
            float wi[3], dist, pdf, value[3], target[3];
            const bool lamp = entry < L.num_lamps;
            bool own = false;  // the point's own emissive triangle: it adds nothing
            if (lanes) {  // drawn and weighted already
                if constexpr (AREAS) {
                    for (int a = 0; a < 3; ++a) wi[a] = c.drawn[j].wi[a], value[a] = c.drawn[j].value[a];
                    dist = c.drawn[j].dist;
                }
                pdf = 0.0f;  // (weighted with it)
            } else if (lamp) {
                const LampSample s = sample_lamp(L.lamps[entry], P, u1, u2);
                for (int a = 0; a < 3; ++a) wi[a] = s.wi[a], value[a] = s.value[a];
                dist = s.dist;
                pdf = s.pdf;
            } else if (entry == env_entry) {  // the environment map (entries has it last)
                if constexpr (ENV) {
                    for (int a = 0; a < 3; ++a)
                        wi[a] = ec.wi[a * kWordChunk + q], value[a] = ec.value[a * kWordChunk + q];
                    pdf = ec.pdf[q++];
                } else {
                    environment_sample(*L.env, u1, u2, wi, value, pdf);
                }
                dist = lampmath::INF;
            } else {
                const size_t w = entry - L.num_lamps;
                own = L.tri_prim && p.prim && L.tri_prim[w] == p.prim[i];
                triangle_light(L.tri_geo, L.tri_area, T, w, P, u1, u2, wi, dist, pdf, target);
                if (point_out)
                    for (int a = 0; a < 3; ++a) point_out[size_t(a) * n + i] = target[a];
                const float scale = pdf > 0 ? 1.0f / pdf : 0.0f;
                for (int a = 0; a < 3; ++a) value[a] = L.tri_emission[size_t(a) * T + w] * scale;
            }
            if (L.no_mis[entry]) pdf = lampmath::INF;
            float ns[3], ng[3], thr[3];
            for (int a = 0; a < 3; ++a) {
                ns[a] = p.ns[size_t(a) * n + i];
                ng[a] = p.ng ? p.ng[size_t(a) * n + i] : ns[a];
                if (p.thr) thr[a] = p.thr[size_t(a) * n + i];
            }
            // In front of the shading normal is enough: a sample below the geometric one is
            // the shadow ray's to decide (it leaves through its own, skipped, triangle), as in
            // Cycles, whose diffuse eval has no geometric test.
            bool weighed = false;  // by draw_chunk already
            if constexpr (AREAS) weighed = c.drawn[j].ok;
            bool ok = p_sel > 0.0f &&
                      (lanes ? weighed : nee_scale(ns, nullptr, wi, pdf, p_sel, p.thr ? thr : nullptr, value));
            if (!(p_sel > 0.0f) || own) value[0] = value[1] = value[2] = 0.0f;  // (a tree pick below float's range)
            ok = ok && !own;
            if (p.bump) {  // a normal-mapped point: Cycles' bump shadowing of the sample
                const float Ns[3] = {p.bump[i], p.bump[n + i], p.bump[2 * n + i]};
                const float g = bump_shadowing(Ns, ns, wi, p.bump[3 * n + i] != 0.0f);
                for (int a = 0; a < 3; ++a) value[a] *= g;
                ok = ok && g > 0.0f;
            }
            if (p.rough) rough_diffuse_scale(p.rough, n, i, ns, wi, value);
            if (L.light_set && p.receivers && !((p.receivers[i] >> L.light_set[entry]) & 1u)) {
                ok = false;  // light linking: the light does not reach this point's object
                value[0] = value[1] = value[2] = 0.0f;
            }
            const float NL = ns[0] * wi[0] + ns[1] * wi[1] + ns[2] * wi[2];
            size_t tri = 0;
            float cutoff = 0.0f;
            if (p.term) {
                tri = index_at(p.prim, i, p.term->M);
                cutoff = p.term->cutoff ? p.term->cutoff[tri] : 0.0f;
                const float f = p.term->freq ? p.term->freq[tri] : 1.0f;
                if (f > 1.0f && NL > 0) {
                    const float s = shift_cos_in(NL, f);
                    for (int a = 0; a < 3; ++a) value[a] *= s;
                    ok = ok && s > 0;
                }
            }
            if (!p.skip_work) {  // every sample is traced; one that cannot contribute adds 0
                if (!ok) value[0] = value[1] = value[2] = 0.0f;
                ok = true;
            }
            for (int a = 0; a < 3; ++a) value_out[size_t(a) * n + i] = value[a];
            bool adds = ok;
            if (!ok) {
                ++bad;
            } else if (L.shadow[entry]) {
                float O[3] = {p.P_off[i], p.P_off[n + i], p.P_off[2 * n + i]};
                const bool geometry = !lamp && entry < L.num_lamps + T;  // a triangle: aim at its point
                const float* aim = geometry ? target : nullptr;
                float shorten = p.shorten, lamp_point[3];
                int32_t skip = p.prim ? p.prim[i] : -1;
                const float ngw = ng[0] * wi[0] + ng[1] * wi[1] + ng[2] * wi[2];
                // Cycles' shadow_ray_offset: the geometric normal on the side of L (by ns)
                const float sign = NL < 0 ? -1.0f : 1.0f;
                const float Ng[3] = {ng[0] * sign, ng[1] * sign, ng[2] * sign}, NgL = ngw * sign;
                const float amount = cutoff > 0.0f ? terminator_amount(NL * sign, NgL, cutoff) : 0.0f;
                if (amount > 0.0f) {
                    float lift[3];
                    terminator_lift(p.term->geo, p.term->normals, p.term->M, tri, p.term->u[i], p.term->v[i], Ng, lift);
                    for (int a = 0; a < 3; ++a) O[a] += lift[a] * amount;
                    // below the geometric normal the lifted ray is meant to meet its own triangle
                    if (NgL <= 0.0f) skip = -1;
                    if (!aim && dist < lampmath::INF) {  // still to the sampled point of the lamp
                        for (int a = 0; a < 3; ++a) lamp_point[a] = P[a] + wi[a] * dist;
                        aim = lamp_point;
                        shorten = 1.0f;
                    }
                } else if (ngw < 0.0f) {
                    // toward the back of the surface: the step off it is mirrored to that side,
                    // so the ray cannot cross the plane beyond its own (skipped) triangle
                    for (int a = 0; a < 3; ++a) O[a] = P[a] + (P[a] - O[a]);
                }
                // a zero-length ray (the point lies on the light) is not traced and adds nothing
                adds = shadow_record(O, wi, dist, aim, shorten, out.rays[m]);
                if (adds) {
                    out.send[m] = int64_t(i);
                    if (out.skip) out.skip[m] = skip;
                    ++m;
                }
            }
            contrib[i] = adds;
        }
    });
    *skipped = bad;
    return m - b;
}

}  // namespace

bool draws_area_lanes(const LightChoice& lights) {
    bool areas = false;
    for (size_t k = 0; k < lights.num_lamps; ++k) areas |= area_lanes_apply(lights.lamps[k]);
    return areas;
}

size_t event_range(const LightChoice& lights, bool areas, const VertexPoints& pts, const NextEventOut& out, size_t b,
                   size_t e, size_t* skipped) {
    const bool env = lights.env != nullptr;
    // with a light tree, the chunk's picks first (pick_entries): its walks go side by side
    const bool chunks = areas || (lights.tree && pts.pick);
    const auto block = chunks ? (env ? event_block<true, true> : event_block<true, false>)
                             : (env ? event_block<false, true> : event_block<false, false>);
    return block(lights, pts, out, b, e, skipped);
}

size_t place_shadow_rays(const NextEventOut& out, size_t blocks, const std::vector<size_t>& count,
                         const std::vector<size_t>& bad, size_t* skipped) {
    size_t m = 0, skip_count = 0;
    for (size_t k = 0; k < blocks; ++k) {  // each block's rays left to follow the last's, in order
        const size_t src = k * kEventBlock, c = count[k];
        if (src != m && c) {  // (m < src: a block's rays only move toward the front)
            std::memmove(out.rays + m, out.rays + src, c * sizeof(Ray));
            std::memmove(out.send + m, out.send + src, c * sizeof(int64_t));
            if (out.skip) std::memmove(out.skip + m, out.skip + src, c * sizeof(int32_t));
        }
        m += c;
        skip_count += bad[k];
    }
    parallel_for(m, [&](size_t b, size_t e) {
        for (size_t d = b; d < e; ++d) out.rays[d].id = uint32_t(d);
    }, size_t(1) << 16);
    *skipped = skip_count;
    return m;
}

size_t next_event(const LightChoice& lights, const VertexPoints& pts, const NextEventOut& out, size_t* skipped) {
    const size_t n = pts.n, blocks = (n + kEventBlock - 1) / kEventBlock;
    std::vector<size_t> count(blocks), bad(blocks);
    const bool areas = draws_area_lanes(lights);  // area lamps' samples are drawn kLampLanes points at a time
    parallel_for(blocks, [&](size_t b0, size_t b1) {
        for (size_t k = b0; k < b1; ++k)
            count[k] = event_range(lights, areas, pts, out, k * kEventBlock, std::min(n, (k + 1) * kEventBlock), &bad[k]);
    }, 1);
    return place_shadow_rays(out, blocks, count, bad, skipped);
}

bool accumulate_masked(float* L, size_t N, const int64_t* pid, const float* values, const uint8_t* mask, size_t n,
                       float clamp) {
    // Split from kAccumulateSplit columns: a render's shadow batches are 10^4..2x10^5 paths, and
    // from 2^17 per thread (as it was) this add ran on the calling thread alone while the other
    // cores idled (Cornell 256 spp: 0.070 s CPU, all on one thread). pid are distinct: no two
    // threads add into one column, and each column's sum is the same on any thread count.
    constexpr size_t kAccumulateSplit = size_t(1) << 14;
    std::atomic<bool> in_range{true};
    parallel_for(n, [&in_range, pid, N](size_t b, size_t e) {
        bool ok = true;
        for (size_t i = b; i < e; ++i) ok &= pid[i] >= 0 && uint64_t(pid[i]) < N;
        if (!ok) in_range.store(false, std::memory_order_relaxed);
    }, kAccumulateSplit);
    if (!in_range.load()) return false;  // checked first: a refused call leaves L as it was
    // Branch-free: adding 0 where the mask is clear costs less than mispredicting it (~half
    // the samples of a vertex are occluded or skipped, in no pattern). Captured by value: the
    // workers read no pointer from the calling thread's stack in the loop.
    parallel_for(n, [L, N, pid, values, mask, n, clamp](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const bool on = mask[i];
            const size_t j = index_at(pid, i, N);  // checked above, but the caller's array
            float v[3] = {values[i], values[n + i], values[2 * n + i]};
            clamp_light(v, clamp);
            for (int a = 0; a < 3; ++a) L[size_t(a) * N + j] += on ? v[a] : 0.0f;
        }
    }, kAccumulateSplit);
    return true;
}

}  // namespace dacrt
