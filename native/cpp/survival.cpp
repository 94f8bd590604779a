// Path survival after a vertex (see shading.h): black surfaces and Russian roulette (Cycles'
// survival probability), then the throughputs of the paths that go on.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "bounce.h"
#include "hitrecords.h"
#include "parallel.h"
#include "pathvertex.h"
#include "random.h"
#include "shading.h"
#include "survivorlanes.h"

namespace dacrt {

namespace {

// Cycles' survival probability: min(sqrt(largest throughput channel), 1); thr null: 1.
inline float survival(const float* thr, size_t n, size_t i) {
    const float m = thr ? std::max(std::max(thr[i], thr[n + i]), thr[2 * n + i]) : 1.0f;
    return std::min(std::sqrt(m), 1.0f);
}

}  // namespace

// survivors() with roulette uniform u(i) (null: no roulette), for whichever source the caller has.
template <class Uniform>
size_t survivors_of(const Hit* hits, const uint8_t* hit, size_t n, const uint8_t* live, size_t M, const float* thr,
                    bool roulette, const Uniform& u, int64_t* idx, size_t* dead_black, size_t* dead_rr) {
    std::vector<uint8_t> keep(n);
    std::atomic<size_t> black{0}, rr{0};
    parallel_for(n, [&](size_t b, size_t e) {
        // the inputs as locals of the chunk: keep[]'s byte stores may alias any memory, so
        // through the captured references every pointer (and the counts) was loaded again
        // for each path (the flag pass: ~1-1.6% of a Cornell / outdoor render)
        const Hit* const H = hits;
        const uint8_t* const on_hit = hit;
        const uint8_t* const on_live = live;
        const float* const T = thr;
        const size_t tri = M, paths = n;
        const bool rl = roulette;
        uint8_t* const kept = keep.data();
        size_t nb = 0, nr = 0;
        u(b, e, [&](size_t i, float u_rr) {
            // branch-free per path (hits, black surfaces and roulette follow no pattern); the
            // triangle index is clamped before live[] is read
            const int32_t p = __atomic_load_n(&H[i].prim, __ATOMIC_RELAXED);
            // (no flags: every path whose record holds a triangle, prim >= 0, is a hit)
            const bool on = (!on_hit || on_hit[i] != 0) & (p >= 0) & (size_t(p) < tri);
            const bool alive = on & (on_live[on ? size_t(p) : 0] != 0);
            const bool lucky = !rl || u_rr < survival(T, paths, i);
            nb += on & !alive;
            nr += alive & !lucky;
            kept[i] = alive & lucky;
        });
        black += nb;
        rr += nr;
    });
    *dead_black = black.load();
    *dead_rr = rr.load();
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {  // branch-free: which paths survive is not predictable
        idx[k] = int64_t(i);
        k += keep[i];
    }
    return k;
}

size_t survivors(const Hit* hits, const uint8_t* hit, size_t n, const uint8_t* live, size_t M, const float* thr,
                 const float* u_rr, int64_t* idx, size_t* dead_black, size_t* dead_rr) {
    auto given = [&](size_t b, size_t e, auto&& path) {
        const float* const r = u_rr;  // (a local: see survivors_of)
        for (size_t i = b; i < e; ++i) path(i, r ? r[i] : 0.0f);
    };
    return survivors_of(hits, hit, n, live, M, thr, u_rr != nullptr, given, idx, dead_black, dead_rr);
}

size_t survivors_drawn(const Hit* hits, const uint8_t* hit, size_t n, const uint8_t* live, size_t M,
                       const float* thr, const uint32_t* keys, uint32_t ka, uint32_t kb, int64_t* idx,
                       size_t* dead_black, size_t* dead_rr) {
    auto drawn = [&](size_t b, size_t e, auto&& path) {  // uniform_pick's second uniform, a chunk at a time
        for_words(keys, n, ka, kb, b, e, [&](size_t i0, size_t m, const uint32_t*, const uint32_t* w) {
            for (size_t j = 0; j < m; ++j) path(i0 + j, unit24(w[j]));
        });
    };
    return survivors_of(hits, hit, n, live, M, thr, true, drawn, idx, dead_black, dead_rr);
}

void survivor_range(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                    const int64_t* idx, size_t k, float* thr_out, const float* geo, const float* normals,
                    const float* D, float* surf_out, int32_t* prim_out, size_t b, size_t e, const float* records) {
    if (geo && records)  // whole groups of survivors in lanes (the same bits), the rest one at a time
        b = survivor_lanes(hits, n, albedo, M, thr, roulette, idx, k, thr_out, records, normals != nullptr, D,
                           surf_out, prim_out, b, e);
    for (size_t j = b; j < e; ++j) {
        const size_t i = size_t(idx[j]);
        const Hit& h = hits[i];
        const size_t p = prim_at(h, M);  // checked by the first pass, but the caller's array
        const float q = roulette ? survival(thr, n, i) : 1.0f;
        const float inv_q = q > 0 ? 1.0f / q : 1.0f;
        for (int a = 0; a < 3; ++a) {
            float t = thr ? thr[size_t(a) * n + i] : 1.0f;
            if (roulette) t = t * inv_q;
            thr_out[size_t(a) * k + j] = albedo[size_t(a) * M + p] * t;
        }
        if (!geo) continue;
        const float d[3] = {D[i], D[n + i], D[2 * n + i]};
        SurfacePoint sp;
        surface_point_at(geo, M, normals, records, h, d, sp);  // survivors have 0 <= prim < M
        for (int a = 0; a < 3; ++a) {
            surf_out[size_t(a) * k + j] = sp.P[a];
            surf_out[size_t(3 + a) * k + j] = sp.ng[a];
            surf_out[size_t(6 + a) * k + j] = sp.P_off[a];
            if (normals) surf_out[size_t(9 + a) * k + j] = sp.ns[a];
        }
        prim_out[j] = int32_t(p);
    }
}

void survivor_throughput(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                         const int64_t* idx, size_t k, float* thr_out, const float* geo, const float* normals,
                         const float* D, float* surf_out, int32_t* prim_out, const float* records) {
    parallel_for(k, [&](size_t b, size_t e) {
        survivor_range(hits, n, albedo, M, thr, roulette, idx, k, thr_out, geo, normals, D, surf_out, prim_out, b, e,
                       records);
    });
}

}  // namespace dacrt
