// Next-event estimation at a path vertex in one pass (see nextevent.h). The steps and their
// float32 arithmetic are those of the separate kernels it fuses (uniform2_rows, the light
// choice, sample_lamp / triangle_light, nee_scale, shadow_record), so it gives the same bits.
#include "nextevent.h"
#include "orennayar.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <functional>
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

// A chunk's points that all drew their samples in lanes (draw_chunk: area lamps), for
// event_block's PLAIN loop without an environment map: its steps for such points, which read
// neither the shading normal (its cosine only decides a terminator's lift) nor the throughput
// (weighted in the lanes), with no branch per point: each point's ray is written at the next
// place and counted where it is traced (a place not counted is written over by the next point or
// lies past the block's count, which event_blocks never moves). The same operations on the
// same values as event_block's, so the same bits; ~20% of a Cornell box's samples cannot
// contribute, in no pattern, which the loop's branch on them mispredicted.
void drawn_points(const LightChoice& L, const VertexPoints& p, const NextEventOut& out, size_t i0, size_t cnt,
                  const Drawn* drawn, const uint32_t* entries, const float* sels, size_t& m, size_t& bad) {
    const size_t n = p.n;
    const float* const P = p.P;
    const float* const P_off = p.P_off;
    const float* const ng = p.ng ? p.ng : p.ns;
    const int32_t* const prim = p.prim;
    const uint8_t* const shadow = L.shadow;
    const bool skip_work = p.skip_work;
    float* const value_out = out.value;
    uint8_t* const contrib = out.contrib;
    Ray* const rays = out.rays;
    int64_t* const send = out.send;
    int32_t* const skip = out.skip;
    size_t mc = m, badc = bad;
    for (size_t j = 0; j < cnt; ++j) {
        const size_t i = i0 + j;
        const Drawn& d = drawn[j];
        const bool sel = sels[j] > 0.0f;  // (a tree pick below float's range: no value)
        bool ok = sel && d.ok;
        float value[3];
        for (int a = 0; a < 3; ++a) value[a] = sel ? d.value[a] : 0.0f;
        if (!skip_work) {  // every sample is traced; one that cannot contribute adds 0
            for (int a = 0; a < 3; ++a) value[a] = ok ? value[a] : 0.0f;
            ok = true;
        }
        for (int a = 0; a < 3; ++a) value_out[size_t(a) * n + i] = value[a];
        const float ngw = ng[i] * d.wi[0] + ng[n + i] * d.wi[1] + ng[2 * n + i] * d.wi[2];
        // toward the back of the surface the step off it is mirrored (event_block's reason)
        Ray r;
        for (int a = 0; a < 3; ++a) {
            const float o = P_off[size_t(a) * n + i], q = P[size_t(a) * n + i];
            r.org[a] = ngw < 0.0f ? q + (q - o) : o;
        }
        const bool good = d.dist > 0;  // shadow_record along wi over dist: a zero-length ray adds nothing
        for (int a = 0; a < 3; ++a) r.dir[a] = good ? d.wi[a] : (a == 2 ? 1.0f : 0.0f);
        r.tfar = good ? d.dist : 0.0f;
        r.id = uint32_t(mc);
        rays[mc] = r;
        send[mc] = int64_t(i);
        if (skip) skip[mc] = prim ? prim[i] : -1;
        const bool cast = shadow[entries[j]] != 0;
        badc += !ok;
        mc += ok & cast & good;
        contrib[i] = ok & (!cast | good);
    }
    m = mc;
    bad = badc;
}

// AREAS: some lamp is drawn lane by lane (area_lanes_apply): its points are drawn first per chunk
// (draw_chunk); also with a light tree, whose walks pick_entries takes side by side. ENV: an environment map, whose points' samples are drawn first per chunk too
// (environment_sample_lanes). Without either, the loop is that of one point at a time only: the
// chunk's arrays and its pass picking the entries first had cost scenes without area lamps ~11%.
// PLAIN (plain_points): no bump, rough, terminator, light linking, entry or point output; the
// loop without their code keeps fewer pointers live (fewer spills in the per-point loop).
template <bool AREAS, bool ENV, bool PLAIN>
size_t event_block(LightChoice L, VertexPoints p, const NextEventOut& out, size_t b, size_t e, size_t* skipped) {
    float* value_out = out.value;
    uint8_t* contrib = out.contrib;
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
        // compile-time nulls in the PLAIN loop, their code left out (set here, not captured: a
        // captured null is not folded where for_words stays a call of its own)
        int32_t* const entry_out = PLAIN ? nullptr : out.entry;
        float* const point_out = PLAIN ? nullptr : out.point;
        const float* const bump = PLAIN ? nullptr : p.bump;
        const float* const rough = PLAIN ? nullptr : p.rough;
        const Terminator* const term = PLAIN ? nullptr : p.term;
        const uint8_t* const light_set = PLAIN ? nullptr : L.light_set;
        if constexpr (AREAS || ENV) pick_entries(L, p, i0, cnt, c.entries, c.sels);
        if constexpr (AREAS) draw_chunk(L, p, i0, cnt, c.entries, c.sels, wa, wb, c.drawn, c.is_drawn);
        if constexpr (AREAS && PLAIN && !ENV) {
            uint8_t all = 1;
            for (size_t j = 0; j < cnt; ++j) all &= c.is_drawn[j];
            if (all) return drawn_points(L, p, out, i0, cnt, c.drawn, c.entries, c.sels, m, bad);
        }
        [[maybe_unused]] size_t q = 0;  // ENV: the next of the chunk's map samples
        if constexpr (ENV) {
            size_t m_env = 0;
            for (size_t j = 0; j < cnt; ++j)
                if (c.entries[j] == env_entry) ec.u1[m_env] = unit24(wa[j]), ec.u2[m_env] = unit24(wb[j]), ++m_env;
            environment_sample_lanes(*L.env, ec.u1, ec.u2, m_env, ec.wi, ec.value, ec.pdf, kWordChunk);
        }
        // the per-point loop reads copies: p and L reached pick_entries and draw_chunk by reference,
        // and out, the outputs and counts are captured, so each byte store (contrib, the chunk's
        // flags) had every field and pointer it reads loaded again from memory
        const VertexPoints pv = p;
        const LightChoice Lv = L;
        const NextEventOut ov = out;
        float* const vo = value_out;
        uint8_t* const co = contrib;
        size_t mc = m, badc = bad;
        for (size_t j = 0; j < cnt; ++j) {
            const size_t i = i0 + j;
            const float u1 = unit24(wa[j]), u2 = unit24(wb[j]);
            const float P[3] = {pv.P[i], pv.P[n + i], pv.P[2 * n + i]};
            float p_sel;
            size_t entry;
            bool lanes = false;
            if constexpr (AREAS || ENV) {
                p_sel = c.sels[j];
                entry = c.entries[j];
                if constexpr (AREAS) lanes = c.is_drawn[j];
            } else {
                entry = pick_entry(Lv, pv, i, p_sel);
            }
            if (entry_out) entry_out[i] = int32_t(entry);
            float wi[3], dist, pdf, value[3], target[3];
            const bool lamp = entry < Lv.num_lamps;
            bool own = false;  // the point's own emissive triangle: it adds nothing
            if (lanes) {  // drawn and weighted already
                if constexpr (AREAS) {
                    // whole-array copies: three 4-byte stores of wi could not forward to the
                    // 8-byte load the direction's dot products below compile to (a stall per
                    // point, ~15% of this loop's samples in perf annotate)
                    std::memcpy(wi, c.drawn[j].wi, sizeof wi);
                    std::memcpy(value, c.drawn[j].value, sizeof value);
                    dist = c.drawn[j].dist;
                }
                pdf = 0.0f;  // (weighted with it)
            } else if (lamp) {
                const LampSample s = sample_lamp(Lv.lamps[entry], P, u1, u2);
                std::memcpy(wi, s.wi, sizeof wi);
                std::memcpy(value, s.value, sizeof value);
                dist = s.dist;
                pdf = s.pdf;
            } else if (entry == env_entry) {  // the environment map (entries has it last)
                if constexpr (ENV) {
                    for (int a = 0; a < 3; ++a)
                        wi[a] = ec.wi[a * kWordChunk + q], value[a] = ec.value[a * kWordChunk + q];
                    pdf = ec.pdf[q++];
                } else {
                    environment_sample(*Lv.env, u1, u2, wi, value, pdf);
                }
                dist = lampmath::INF;
            } else {
                const size_t w = entry - Lv.num_lamps;
                own = Lv.tri_prim && pv.prim && Lv.tri_prim[w] == pv.prim[i];
                triangle_light(Lv.tri_geo, Lv.tri_area, T, w, P, u1, u2, wi, dist, pdf, target);
                if (point_out)
                    for (int a = 0; a < 3; ++a) point_out[size_t(a) * n + i] = target[a];
                const float scale = pdf > 0 ? 1.0f / pdf : 0.0f;
                for (int a = 0; a < 3; ++a) value[a] = Lv.tri_emission[size_t(a) * T + w] * scale;
            }
            if (Lv.no_mis[entry]) pdf = lampmath::INF;
            float ns[3], ng[3], thr[3];
            for (int a = 0; a < 3; ++a) {
                ns[a] = pv.ns[size_t(a) * n + i];
                ng[a] = pv.ng ? pv.ng[size_t(a) * n + i] : ns[a];
                if (pv.thr) thr[a] = pv.thr[size_t(a) * n + i];
            }
            // In front of the shading normal is enough: a sample below the geometric one is
            // the shadow ray's to decide (it leaves through its own, skipped, triangle), as in
            // Cycles, whose diffuse eval has no geometric test.
            bool weighed = false;  // by draw_chunk already
            if constexpr (AREAS) weighed = c.drawn[j].ok;
            bool ok = p_sel > 0.0f &&
                      (lanes ? weighed : nee_scale(ns, nullptr, wi, pdf, p_sel, pv.thr ? thr : nullptr, value));
            if (!(p_sel > 0.0f) || own) value[0] = value[1] = value[2] = 0.0f;  // (a tree pick below float's range)
            ok = ok && !own;
            if (bump) {  // a normal-mapped point: Cycles' bump shadowing of the sample
                const float Ns[3] = {bump[i], bump[n + i], bump[2 * n + i]};
                const float g = bump_shadowing(Ns, ns, wi, bump[3 * n + i] != 0.0f);
                for (int a = 0; a < 3; ++a) value[a] *= g;
                ok = ok && g > 0.0f;
            }
            if (rough) rough_diffuse_scale(rough, n, i, ns, wi, value);
            if (light_set && pv.receivers && !((pv.receivers[i] >> light_set[entry]) & 1u)) {
                ok = false;  // light linking: the light does not reach this point's object
                value[0] = value[1] = value[2] = 0.0f;
            }
            const float NL = ns[0] * wi[0] + ns[1] * wi[1] + ns[2] * wi[2];
            size_t tri = 0;
            float cutoff = 0.0f;
            if (term) {
                tri = index_at(pv.prim, i, term->M);
                cutoff = term->cutoff ? term->cutoff[tri] : 0.0f;
                const float f = term->freq ? term->freq[tri] : 1.0f;
                if (f > 1.0f && NL > 0) {
                    const float s = shift_cos_in(NL, f);
                    for (int a = 0; a < 3; ++a) value[a] *= s;
                    ok = ok && s > 0;
                }
            }
            if (!pv.skip_work) {  // every sample is traced; one that cannot contribute adds 0
                if (!ok) value[0] = value[1] = value[2] = 0.0f;
                ok = true;
            }
            for (int a = 0; a < 3; ++a) vo[size_t(a) * n + i] = value[a];
            bool adds = ok;
            if (!ok) {
                ++badc;
            } else if (Lv.shadow[entry]) {
                float O[3] = {pv.P_off[i], pv.P_off[n + i], pv.P_off[2 * n + i]};
                const bool geometry = !lamp && entry < Lv.num_lamps + T;  // a triangle: aim at its point
                const float* aim = geometry ? target : nullptr;
                float shorten = pv.shorten, lamp_point[3];
                int32_t skip = pv.prim ? pv.prim[i] : -1;
                const float ngw = ng[0] * wi[0] + ng[1] * wi[1] + ng[2] * wi[2];
                // Cycles' shadow_ray_offset: the geometric normal on the side of L (by ns)
                const float sign = NL < 0 ? -1.0f : 1.0f;
                const float Ng[3] = {ng[0] * sign, ng[1] * sign, ng[2] * sign}, NgL = ngw * sign;
                const float amount = cutoff > 0.0f ? terminator_amount(NL * sign, NgL, cutoff) : 0.0f;
                if (amount > 0.0f) {
                    float lift[3];
                    terminator_lift(term->geo, term->normals, term->M, tri, term->u[i], term->v[i], Ng, lift);
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
                adds = shadow_record(O, wi, dist, aim, shorten, ov.rays[mc]);
                ov.rays[mc].id = uint32_t(mc);  // its place if its block's rays stay (event_blocks)
                if (adds) {
                    ov.send[mc] = int64_t(i);
                    if (ov.skip) ov.skip[mc] = skip;
                    ++mc;
                }
            }
            co[i] = adds;
        }
        m = mc;
        bad = badc;
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

namespace {

// Whether event_block<..., true> serves these points: none of the per-point features it leaves out.
bool plain_points(const LightChoice& lights, const VertexPoints& pts, const NextEventOut& out) {
    return !pts.bump && !pts.rough && !pts.term && !(lights.light_set && pts.receivers) && !out.entry && !out.point;
}

}  // namespace

size_t event_range(const LightChoice& lights, bool areas, const VertexPoints& pts, const NextEventOut& out, size_t b,
                   size_t e, size_t* skipped) {
    const bool env = lights.env != nullptr;
    // with a light tree, the chunk's picks first (pick_entries): its walks go side by side
    const bool chunks = areas || (lights.tree && pts.pick);
    const auto block = plain_points(lights, pts, out)
                           ? (chunks ? (env ? event_block<true, true, true> : event_block<true, false, true>)
                                     : (env ? event_block<false, true, true> : event_block<false, false, true>))
                           : (chunks ? (env ? event_block<true, true, false> : event_block<true, false, false>)
                                     : (env ? event_block<false, true, false> : event_block<false, false, false>));
    return block(lights, pts, out, b, e, skipped);
}

namespace {

// Block k's c shadow rays (at k * kEventBlock) moved to follow the blocks before, from m on,
// with send and skip; each ray's id is its index: event_block wrote those of rays left in place,
// a moved ray's is set after the move, on lines it has just written. (Moved one at a time with
// the id set on the way, the generic build took the records apart into scalar stores: 4% of
// shade_bounce's perf samples on a Cornell render's calls, beside the memmove of send.)
void move_block(const NextEventOut& out, size_t k, size_t c, size_t m) {
    const size_t src = k * kEventBlock;
    if (src == m || !c) return;  // (m < src: a block's rays only move toward the front)
    Ray* const rays = out.rays;
    std::memmove(rays + m, rays + src, c * sizeof(Ray));
    for (size_t d = 0; d < c; ++d) rays[m + d].id = uint32_t(m + d);
    std::memmove(out.send + m, out.send + src, c * sizeof(int64_t));
    if (out.skip) std::memmove(out.skip + m, out.skip + src, c * sizeof(int32_t));
}

// The blocks' rays placed as the blocks are done: whichever worker finds the first unplaced
// block done moves it and every done block after it (a block's destination ends before the
// next block's rays begin, so moving it never touches a block still being shaded). The moves
// then run while the other worker shades, instead of on the calling thread after the pass.
class Placement {
  public:
    Placement(const NextEventOut& out, size_t blocks)
        : out_(out), blocks_(blocks), count_(blocks), bad_(blocks), ready_(new std::atomic<uint8_t>[blocks]) {
        for (size_t k = 0; k < blocks; ++k) ready_[k].store(0, std::memory_order_relaxed);
    }

    void done(size_t k, size_t count, size_t bad) {
        count_[k] = count;
        bad_[k] = bad;
        ready_[k].store(1, std::memory_order_seq_cst);
        // (seq_cst both sides: a worker whose exchange finds the other placing, and the other
        // after its release, cannot both miss a block that became ready between)
        while (front_.load(std::memory_order_seq_cst) < blocks_ &&
               ready_[front_.load(std::memory_order_seq_cst)].load(std::memory_order_seq_cst)) {
            if (busy_.exchange(1, std::memory_order_seq_cst)) return;  // the other worker places
            advance();
            busy_.store(0, std::memory_order_seq_cst);
        }
    }

    // After every block is done: what no worker placed, then the number of rays.
    size_t finish(size_t* skipped) {
        advance();
        *skipped = skipped_;
        return m_;
    }

  private:
    void advance() {  // holding busy_ (or alone)
        size_t f = front_.load(std::memory_order_relaxed);
        for (; f < blocks_ && ready_[f].load(std::memory_order_acquire); ++f) {
            move_block(out_, f, count_[f], m_);
            m_ += count_[f];
            skipped_ += bad_[f];
        }
        front_.store(f, std::memory_order_seq_cst);
    }

    const NextEventOut& out_;
    const size_t blocks_;
    std::vector<size_t> count_, bad_;
    std::unique_ptr<std::atomic<uint8_t>[]> ready_;
    std::atomic<size_t> front_{0};
    std::atomic<int> busy_{0};
    size_t m_ = 0, skipped_ = 0;  // (changed only while placing)
};

}  // namespace

size_t event_blocks(const NextEventOut& out, size_t blocks, const std::function<size_t(size_t, size_t*)>& block,
                    size_t* skipped) {
    Placement place(out, blocks);
    auto run = [&](size_t q) {
        size_t bad = 0;
        const size_t c = block(q, &bad);
        place.done(q, c, bad);
    };
    // blocks to whichever worker is free, in order: one descheduled worker (a busy machine)
    // does not hold the pass back by its share, and the placed front follows the shading
    const int workers = int(std::min<size_t>(size_t(default_threads()), blocks));
    if (workers <= 1) {
        for (size_t q = 0; q < blocks; ++q) run(q);
    } else {
        std::atomic<size_t> next{0};
        run_workers(workers, [&](int) {
            for (size_t q; (q = next.fetch_add(1, std::memory_order_relaxed)) < blocks;) run(q);
        });
    }
    return place.finish(skipped);
}

size_t next_event(const LightChoice& lights, const VertexPoints& pts, const NextEventOut& out, size_t* skipped) {
    const size_t n = pts.n, blocks = (n + kEventBlock - 1) / kEventBlock;
    const bool areas = draws_area_lanes(lights);  // area lamps' samples are drawn kLampLanes points at a time
    return event_blocks(out, blocks, [&](size_t k, size_t* bad) {
        return event_range(lights, areas, pts, out, k * kEventBlock, std::min(n, (k + 1) * kEventBlock), bad);
    }, skipped);
}

namespace {

// Whether every pid[i] is in 0..N-1: one vectorised pass on the calling thread (a pass of its
// own on the workers had cost a hand-off per call for ~10 us of work at a render's batch sizes).
__attribute__((target_clones("avx512f", "avx2", "default")))
bool ids_in_range(const int64_t* pid, size_t n, size_t N) {
    uint64_t out = 0;
    for (size_t i = 0; i < n; ++i) out |= uint64_t(uint64_t(pid[i]) >= uint64_t(N));  // (negative: huge)
    return out == 0;
}

}  // namespace

bool accumulate_masked(float* L, size_t N, const int64_t* pid, const float* values, const uint8_t* mask, size_t n,
                       float clamp) {
    // Split from kAccumulateSplit columns: a render's shadow batches are 10^4..2x10^5 paths, and
    // from 2^17 per thread (as it was) this add ran on the calling thread alone while the other
    // cores idled (Cornell 256 spp: 0.070 s CPU, all on one thread). pid are distinct: no two
    // threads add into one column, and each column's sum is the same on any thread count.
    constexpr size_t kAccumulateSplit = size_t(1) << 14;
    if (!ids_in_range(pid, n, N)) return false;  // checked first: a refused call leaves L as it was
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
