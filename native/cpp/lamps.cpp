// Batched, threaded lamp kernels (see lamps.h): light samples for the samples that picked a
// lamp, and what camera/BSDF rays see of the lamps, in one pass over the rays for all lamps
// instead of one numpy pass per lamp and operation.
#include "lamps.h"

#include <algorithm>

#include "arealanes.h"
#include <vector>

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
    return {};
}

namespace {

// Listed lamps from which lamp_gather goes ray by ray through a LampBVH rather than lamp by
// lamp over the rays. Measured (1M cosine rays from a 40 m floor, 2 threads): 1 lamp 8 ns per
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

// lamp_gather's arguments (see lamps.h), passed by value like sample_range's.
struct Gather {
    const LampRecord* rec;
    const int32_t* lamps;
    size_t nl;
    const float *lamp_prob, *O, *D, *t_surf;
    const uint8_t* miss;
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
};

// Adds what ray i sees of the lamp at list position k (kind and tree key hoisted by the
// caller). The add is selected, not branched on: whether a ray sees a lamp follows no pattern.
__attribute__((always_inline)) inline void gather_one(const Gather& g, const LampRecord& lamp, int kind, int32_t key,
                                                      size_t k, size_t i) {
    const size_t n = g.n;
    const float o[3] = {g.O[i], g.O[n + i], g.O[2 * n + i]};
    const float d[3] = {g.D[i], g.D[n + i], g.D[2 * n + i]};
    float Le[3] = {0.0f, 0.0f, 0.0f}, pdf_l = 0.0f;
    const bool seen = kind == LAMP_SUN || kind == LAMP_BACKGROUND ? g.miss[i] && miss_lamp(lamp, d, Le, pdf_l)
                                                                  : hit_lamp(lamp, o, d, g.t_surf[i], Le, pdf_l);
    float w = 1.0f;
    if (g.lamp_prob) {  // power heuristic of this BSDF hit against sampling the lamp
        float p_sel = g.lamp_prob[g.lamps[k]];
        if (key >= 0 && seen)  // as picked from o with the vertex's normal
            p_sel = float(double(p_sel) * g.tree->pdf(o, g.normal, n, i, key,
                                                      g.receivers ? g.receivers[i] : LightTree::kAllSets));
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
    for (int a = 0; a < 3; ++a) out[size_t(a) * g.N] += seen ? v[a] : 0.0f;
}

inline int32_t tree_key(const Gather& g, size_t k) {  // the lamp's key in the light tree, or -1
    return g.tree && g.lamp_key ? g.lamp_key[g.lamps[k]] : -1;
}

// gather_one for an area lamp without spread (area_lanes_apply) over rays [b, e), kLampLanes
// at a time: hit_area<false>'s and the MIS weight's float32 operations as lane loops that
// vectorise (the same bits; the divisions were one latency-bound chain per ray), the solid-
// angle pdf (sph_rect) and the tree's pdf only for the lanes that meet the lamp. A last short
// group goes through gather_one.
void gather_area_lanes(const Gather& g, const LampRecord& lamp, int32_t key, size_t k, size_t b, size_t e) {
    using namespace lampmath;
    constexpr size_t K = kLampLanes;
    const size_t n = g.n;
    const bool ellipse = int(lamp.shape) == AREA_ELLIPSE, rect = int(lamp.shape) == AREA_RECT;
    const float plane = dot3(lamp.pos, lamp.normal);
    const float* N = lamp.normal;
    const float *Ox = g.O, *Oy = g.O + n, *Oz = g.O + 2 * n, *Dx = g.D, *Dy = g.D + n, *Dz = g.D + 2 * n;
    const float sel0 = g.lamp_prob ? g.lamp_prob[g.lamps[k]] : 1.0f;
    size_t i0 = b;
    for (; i0 + K <= e; i0 += K) {
        float pdf[K], tmax[K], thr[3][K], pb[K], v[3][K];
        int hit[K];
        for (size_t q = 0; q < K; ++q) tmax[q] = g.t_surf[i0 + q];
        for (int a = 0; a < 3; ++a)
            for (size_t q = 0; q < K; ++q) thr[a][q] = g.thr ? g.thr[size_t(a) * n + i0 + q] : 1.0f;
        for (size_t q = 0; q < K; ++q) pb[q] = g.lamp_prob ? g.pdf_bsdf[i0 + q] : 1.0f;
        float O[3][K], D[3][K];
        for (size_t q = 0; q < K; ++q) {
            O[0][q] = Ox[i0 + q], O[1][q] = Oy[i0 + q], O[2][q] = Oz[i0 + q];
            D[0][q] = Dx[i0 + q], D[1][q] = Dy[i0 + q], D[2][q] = Dz[i0 + q];
        }
        for (size_t q = 0; q < K; ++q) {  // hit_area<false>
            const float o0 = O[0][q], o1 = O[1][q], o2 = O[2][q], d0 = D[0][q], d1 = D[1][q], d2 = D[2][q];
            const float denom = d0 * N[0] + d1 * N[1] + d2 * N[2];
            const float t = (plane - (o0 * N[0] + o1 * N[1] + o2 * N[2])) / denom;
            const float r0 = (d0 * t + o0) - lamp.pos[0], r1 = (d1 * t + o1) - lamp.pos[1],
                        r2 = (d2 * t + o2) - lamp.pos[2];
            const float lx = r0 * lamp.inv_x[0] + r1 * lamp.inv_x[1] + r2 * lamp.inv_x[2];
            const float ly = r0 * lamp.inv_y[0] + r1 * lamp.inv_y[1] + r2 * lamp.inv_y[2];
            // (ints, not bools: mixed mask types keep the loop scalar)
            const int in_ellipse = lx * lx + ly * ly <= 0.25f;
            const int in_rect = int(std::fabs(lx) <= 0.5f) & int(std::fabs(ly) <= 0.5f);
            pdf[q] = t * t / (lamp.area * -denom);
            hit[q] = int(denom < 0) & int(t > 0) & int(t < tmax[q]) & (ellipse ? in_ellipse : in_rect);
        }
        float p_sel[K];
        for (size_t q = 0; q < K; ++q) {  // what only a ray that meets the lamp needs
            p_sel[q] = sel0;
            if (!hit[q]) continue;
            const size_t i = i0 + q;
            const float o[3] = {Ox[i], Oy[i], Oz[i]};
            if (rect) {
                const SphRect r = sph_rect(lamp, o, -0.5f, 0.5f, -0.5f, 0.5f);
                pdf[q] = r.use ? 1.0f / r.S : pdf[q];
            }
            if (g.lamp_prob && key >= 0)
                p_sel[q] = float(double(p_sel[q]) * g.tree->pdf(o, g.normal, n, i, key,
                                                                g.receivers ? g.receivers[i] : LightTree::kAllSets));
        }
        const bool mis = g.lamp_prob != nullptr;
        for (size_t q = 0; q < K; ++q) {  // the power heuristic and the throughput
            float r = p_sel[q] * pdf[q] / pb[q];
            r *= r;
            r += 1.0f;
            const float w = mis ? 1.0f / r : 1.0f;  // (x 1: the same bits as no weight)
            v[0][q] = lamp.emit[0] * thr[0][q] * w;
            v[1][q] = lamp.emit[1] * thr[1][q] * w;
            v[2][q] = lamp.emit[2] * thr[2][q] * w;
        }
        for (size_t q = 0; q < K; ++q) {
            float c[3] = {v[0][q], v[1][q], v[2][q]};
            clamp_light(c, g.clamp);
            float* out = g.L + index_at(g.pid, i0 + q, g.N);
            for (int a = 0; a < 3; ++a) out[size_t(a) * g.N] += hit[q] ? c[a] : 0.0f;
        }
    }
    for (size_t i = i0; i < e; ++i) gather_one(g, lamp, LAMP_AREA, key, k, i);
}

// Lamp by lamp over the rays (each ray still adds its lamps in list order).
void gather_range(Gather g, size_t b, size_t e) {
    for (size_t k = 0; k < g.nl; ++k) {
        const LampRecord& lamp = g.rec[g.lamps[k]];
        const int kind = int(lamp.kind);
        const int32_t key = tree_key(g, k);
        if (area_lanes_apply(lamp)) {
            gather_area_lanes(g, lamp, key, k, b, e);
            continue;
        }
        for (size_t i = b; i < e; ++i) gather_one(g, lamp, kind, key, k, i);
    }
}

// Ray by ray, over the lamps the BVH finds near it and those at infinity, in list order: the
// same additions in the same order as gather_range, without the lamps a ray passes far from
// (a delta lamp is never seen: the linear loop adds 0 for it).
void gather_range_bvh(Gather g, const LampBVH& bvh, const std::vector<int32_t>& at_infinity, size_t b, size_t e) {
    std::vector<int32_t> cand;
    for (size_t i = b; i < e; ++i) {
        cand.clear();
        const float o[3] = {g.O[i], g.O[g.n + i], g.O[2 * g.n + i]};
        const float d[3] = {g.D[i], g.D[g.n + i], g.D[2 * g.n + i]};
        bvh.visit(o, d, g.t_surf[i], cand);
        if (g.miss[i]) cand.insert(cand.end(), at_infinity.begin(), at_infinity.end());
        std::sort(cand.begin(), cand.end());
        for (int32_t k : cand) {
            const LampRecord& lamp = g.rec[g.lamps[k]];
            gather_one(g, lamp, int(lamp.kind), tree_key(g, size_t(k)), size_t(k), i);
        }
    }
}

}  // namespace

void lamp_sample(const LampRecord* rec, size_t R, const int32_t* entry, const float* P, const float* u1,
                 const float* u2, size_t n, float* wi, float* dist, float* value, float* pdf) {
    parallel_for(n, [&](size_t b, size_t e) { sample_range(rec, R, entry, P, u1, u2, n, wi, dist, value, pdf, b, e); });
}

void lamp_gather(const LampRecord* rec, const int32_t* lamps, size_t nl, const float* lamp_prob, const float* O,
                 const float* D, const float* t_surf, const uint8_t* miss, const float* thr, const float* pdf_bsdf,
                 const int64_t* pid, size_t n, float* L, size_t N, float clamp, const LightTree* tree,
                 const int32_t* lamp_key, const float* normal, const uint64_t* receivers) {
    const Gather g{rec,  lamps, nl, lamp_prob, O,     D,        t_surf, miss,   thr,      pdf_bsdf,
                   pid,  n,     L,  N,         clamp, tree,     lamp_key, normal, receivers};
    if (nl < kLampBVHMin) {
        parallel_for(n, [&](size_t b, size_t e) { gather_range(g, b, e); });
        return;
    }
    const LampBVH bvh(rec, lamps, nl);
    std::vector<int32_t> at_infinity;  // the sun and background among the lamps, in list order
    for (size_t k = 0; k < nl; ++k) {
        const int kind = int(rec[lamps[k]].kind);
        if (kind == LAMP_SUN || kind == LAMP_BACKGROUND) at_infinity.push_back(int32_t(k));
    }
    parallel_for(n, [&](size_t b, size_t e) { gather_range_bvh(g, bvh, at_infinity, b, e); });
}

}  // namespace dacrt
