// Next-event estimation's area-lamp draws (areadraws.h). Compiled with -fno-trapping-math
// (CMakeLists.txt): the lane loops vectorise only when a select after a division or a
// comparison is not kept for a possible floating-point trap (values are IEEE's either way); on
// all of nextevent.cpp the flag made its point-by-point loop ~11% slower.
#include "areadraws.h"

#include <algorithm>

#include "arealanes.h"
#include "random.h"

namespace dacrt {

namespace {

// What event_block's first steps give the chunk's points js[0..m) (positions in the chunk of
// points i0.., words wa, wb) that all picked the area lamp `lamp` (area_lanes_apply) with
// selection probabilities p_sel (per position) and its no_mis: sample_lamp and nee_scale,
// kLampLanes points at a time (arealanes.h; a short last group repeats its last point), the
// same operations per lane, so the same bits; out[js[k]] gets each. Cloned per instruction set:
// baseline x86-64 runs the lanes 4 wide.
__attribute__((target_clones("avx512f", "avx2", "default")))
void draw_area_lanes(const LampRecord& lamp, bool no_mis, const float* p_sel, const VertexPoints& p, size_t i0,
                     const uint16_t* js, size_t m, const uint32_t* wa, const uint32_t* wb, Drawn* out) {
    constexpr size_t K = kLampLanes;
    const size_t n = p.n;
    for (size_t k0 = 0; k0 < m; k0 += K) {
        float P[3][K], ns[3][K], thr[3][K], u1[K], u2[K], sel[K];
        const size_t j0 = js[k0];
        if (k0 + K <= m && js[k0 + K - 1] == j0 + (K - 1)) {
            // K consecutive points (the usual group: most points pick the one area lamp of a
            // room): the columns' runs loaded as vectors instead of a gather lane by lane
            const size_t i = i0 + j0;
            for (int a = 0; a < 3; ++a)
                for (size_t k = 0; k < K; ++k) {
                    P[a][k] = p.P[size_t(a) * n + i + k];
                    ns[a][k] = p.ns[size_t(a) * n + i + k];
                    thr[a][k] = p.thr ? p.thr[size_t(a) * n + i + k] : 1.0f;
                }
            for (size_t k = 0; k < K; ++k) {
                u1[k] = unit24(wa[j0 + k]);
                u2[k] = unit24(wb[j0 + k]);
                sel[k] = p_sel[j0 + k];
            }
        } else {
            for (size_t k = 0; k < K; ++k) {
                const size_t j = js[std::min(k0 + k, m - 1)], i = i0 + j;
                for (int a = 0; a < 3; ++a) {
                    P[a][k] = p.P[size_t(a) * n + i];
                    ns[a][k] = p.ns[size_t(a) * n + i];
                    thr[a][k] = p.thr ? p.thr[size_t(a) * n + i] : 1.0f;
                }
                u1[k] = unit24(wa[j]);
                u2[k] = unit24(wb[j]);
                sel[k] = p_sel[j];
            }
        }
        LampLanes s;
        sample_area_lanes(lamp, P[0], P[1], P[2], u1, u2, s);
        int ok[K];
        for (size_t k = 0; k < K; ++k) {  // nee_scale, its divisions in every lane
            const float inv_pi = 0.3183098861837907f;
            const float pdf = no_mis ? lampmath::INF : s.pdf[k];
            const float cos_s = ns[0][k] * s.wi[0][k] + ns[1][k] * s.wi[1][k] + ns[2][k] * s.wi[2][k];
            float r = cos_s * inv_pi;
            r /= sel[k] * pdf;
            r *= r;
            r += 1.0f;
            float scale = cos_s * inv_pi;
            scale /= r * sel[k];
            float mx = -1.0f;
            for (int a = 0; a < 3; ++a) {
                float v = s.value[a][k];
                v *= thr[a][k];  // (1 without a throughput: the same bits)
                v *= scale;
                s.value[a][k] = v;
                mx = mx < v ? v : mx;
            }
            ok[k] = (cos_s > 0) & (mx > 0);
        }
        for (size_t k = 0; k < K && k0 + k < m; ++k) {
            Drawn& o = out[js[k0 + k]];
            for (int a = 0; a < 3; ++a) o.wi[a] = s.wi[a][k], o.value[a] = s.value[a][k];
            o.dist = s.dist[k];
            o.ok = ok[k];
        }
    }
}

}  // namespace

void pick_entries(const LightChoice& L, const VertexPoints& p, size_t i0, size_t cnt, uint32_t* entry, float* p_sel) {
    if (!L.tree) {  // pick_entry without a tree, in this loop: no call per point
        for (size_t j = 0; j < cnt; ++j) {
            const size_t e = p.pick ? cdf_entry(L, p.pick[i0 + j]) : 0;
            entry[j] = uint32_t(e);
            p_sel[j] = L.prob[e];
        }
        return;
    }
    if (!p.pick) {
        for (size_t j = 0; j < cnt; ++j) entry[j] = uint32_t(pick_entry(L, p, i0 + j, p_sel[j]));
        return;
    }
    // the points whose pick lands on the tree walk it stop by stop (LightTree::sample_rows), the
    // others take their entry (pick_entry's, the same bits)
    constexpr size_t C = kWordChunk;
    const size_t n = p.n;
    for (size_t j0 = 0; j0 < cnt; j0 += C) {
        const size_t c = std::min(C, cnt - j0);
        float Q[3][C], N[3][C];
        double u[C];
        uint64_t receivers[C];
        uint16_t walk[C];
        size_t m = 0;
        const bool linked = L.light_set && p.receivers;
        for (size_t s = 0; s < c; ++s) {
            const size_t k = i0 + j0 + s;
            const size_t e = cdf_entry(L, p.pick[k]);  // (choose_light's)
            if (!L.tree->member(int64_t(e))) {
                entry[j0 + s] = uint32_t(e);
                p_sel[j0 + s] = L.prob[e];
                continue;
            }
            for (size_t a = 0; a < 3; ++a) Q[a][m] = p.P_off[a * n + k], N[a][m] = p.ns[a * n + k];
            const double lo = e ? L.cdf[e - 1] : 0.0, mass = L.cdf[e] - lo;
            u[m] = mass > 0 ? (p.pick[k] - lo) / mass : 0.0;
            receivers[m] = linked ? p.receivers[k] : LightTree::kAllSets;
            walk[m++] = uint16_t(s);
        }
        int32_t key[C];
        double pt[C];
        L.tree->sample_rows(m, Q[0], N[0], C, u, linked ? receivers : nullptr, key, pt);
        for (size_t w = 0; w < m; ++w) {
            entry[j0 + walk[w]] = uint32_t(key[w]);
            p_sel[j0 + walk[w]] = float(double(L.prob[size_t(key[w])]) * pt[w]);
        }
    }
}

void draw_chunk(const LightChoice& L, const VertexPoints& p, size_t i0, size_t cnt, const uint32_t* entry,
                const float* p_sel, const uint32_t* wa, const uint32_t* wb, Drawn* out, uint8_t* drawn) {
    constexpr int kMaxLamps = 4;
    uint32_t lamps[kMaxLamps];
    uint16_t js[kMaxLamps][kWordChunk];
    size_t m[kMaxLamps];
    int nl = 0;
    // one pass, each entry looked at once per run of equal entries: most points of a chunk pick
    // the entry the point before picked, and the lamp record test (area_lanes_apply) per point
    // had been most of this function's time
    uint32_t last = ~0u;
    int slot = -1;  // the last entry's: its lamp's place in lamps, -1 where not drawn in lanes
    for (size_t j = 0; j < cnt; ++j) {
        const uint32_t e = entry[j];
        if (e != last) {
            last = e;
            slot = -1;
            if (e < L.num_lamps && area_lanes_apply(L.lamps[e])) {
                int k = 0;
                while (k < nl && lamps[k] != e) ++k;
                if (k == nl && nl < kMaxLamps) lamps[nl] = e, m[nl++] = 0;
                if (k < nl) slot = k;
            }
        }
        drawn[j] = slot >= 0;
        if (slot >= 0) js[slot][m[slot]++] = uint16_t(j);
    }
    for (int k = 0; k < nl; ++k)
        draw_area_lanes(L.lamps[lamps[k]], L.no_mis[lamps[k]], p_sel, p, i0, js[k], m[k], wa, wb, out);
}

}  // namespace dacrt
