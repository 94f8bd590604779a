// lamp_gather's lane-by-lane path for area lamps (gather.h). Compiled with -fno-trapping-math
// (CMakeLists.txt): its lane loops vectorise only when a select after a division or a
// comparison is not kept for a possible floating-point trap (values are IEEE's either way);
// for all of lamps.cpp that flag made gather_one's other lamps ~2x slower. The lane loop is
// compiled for AVX2 too (target_clones), with the same bits (-ffp-contract=off).
#include <cmath>

#include "arealanes.h"
#include "gather.h"

namespace dacrt {

namespace {

// What gather_one adds for kLampLanes rays i0.. that meet lamp k where hit[q], with solid-angle
// pdf[q]: the tree's pdf for the rays that meet it, then the power heuristic, the throughput,
// the clamp and the add (0 where not met, as gather_one adds), lane by lane in its operations.
void add_lanes(const Gather& g, const LampRecord& lamp, int32_t key, size_t k, size_t i0, const int* hit,
               const float* pdf) {
    constexpr size_t K = kLampLanes;
    const size_t n = g.n;
    const bool mis = g.lamp_prob != nullptr;
    float p_sel[K], pb[K], thr[3][K], v[3][K];
    for (size_t q = 0; q < K; ++q) {
        p_sel[q] = mis ? g.lamp_prob[g.lamps[k]] : 1.0f;
        if (!(mis && key >= 0 && hit[q])) continue;
        const size_t i = i0 + q;
        const float o[3] = {g.O[i], g.O[n + i], g.O[2 * n + i]};
        p_sel[q] = float(double(p_sel[q]) * g.tree->pdf(o, g.normal, n, i, key,
                                                        g.receivers ? g.receivers[i] : LightTree::kAllSets));
    }
    for (int a = 0; a < 3; ++a)
        for (size_t q = 0; q < K; ++q) thr[a][q] = g.thr ? g.thr[size_t(a) * n + i0 + q] : 1.0f;
    for (size_t q = 0; q < K; ++q) pb[q] = mis ? g.pdf_bsdf[i0 + q] : 1.0f;
    for (size_t q = 0; q < K; ++q) {
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

// gather_one for an area lamp without spread (area_lanes_apply) over rays [b, e), kLampLanes
// at a time: hit_area<false>'s float32 operations as a lane loop that vectorises (the same
// bits; its divisions were one latency-bound chain per ray), the solid-angle pdf (sph_rect)
// only for the rays that meet the lamp, then add_lanes. A last short group goes through
// gather_one.

}  // namespace

__attribute__((target_clones("avx2", "default")))
void gather_area_lanes(const Gather& g, const LampRecord& lamp, int32_t key, size_t k, size_t b, size_t e) {
    using namespace lampmath;
    constexpr size_t K = kLampLanes;
    const size_t n = g.n;
    const bool ellipse = int(lamp.shape) == AREA_ELLIPSE, rect = int(lamp.shape) == AREA_RECT;
    const float plane = dot3(lamp.pos, lamp.normal);
    const float* N = lamp.normal;
    const float *Ox = g.O, *Oy = g.O + n, *Oz = g.O + 2 * n, *Dx = g.D, *Dy = g.D + n, *Dz = g.D + 2 * n;
    size_t i0 = b;
    for (; i0 + K <= e; i0 += K) {
        float pdf[K], tmax[K], O[3][K], D[3][K];
        int hit[K];
        for (size_t q = 0; q < K; ++q) {
            tmax[q] = g.t_surf[(i0 + q) * g.t_step];
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
        // Most groups meet the lamp nowhere (a ceiling lamp fills a small part of a vertex's
        // hemisphere): they add nothing and are done. Branching per group is predictable where
        // branching per ray was not; adding their zeros had cost more than finding the hits.
        int any = 0;
        for (size_t q = 0; q < K; ++q) any |= hit[q];
        if (!any) continue;
        if (rect)
            for (size_t q = 0; q < K; ++q) {  // sample_lamp's pdf at the ray's origin: its sph_rect decides
                if (!hit[q]) continue;
                const float o[3] = {O[0][q], O[1][q], O[2][q]};
                const SphRect r = sph_rect(lamp, o, -0.5f, 0.5f, -0.5f, 0.5f);
                pdf[q] = r.use ? 1.0f / r.S : pdf[q];
            }
        add_lanes(g, lamp, key, k, i0, hit, pdf);
    }
    for (size_t i = i0; i < e; ++i) gather_one(g, lamp, false, key, k, i);  // (an area lamp: finite)
}

}  // namespace dacrt
