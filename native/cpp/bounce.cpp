// A diffuse path vertex shaded in one pass (see bounce.h).
#include "bounce.h"

#include <algorithm>
#include <memory>

#include "orennayar.h"
#include "parallel.h"
#include "random.h"
#include "shading.h"

namespace dacrt {

namespace {

// The path columns survivors b..e-1 (idx) keep: pid, keys (2 rows) and pick (null: none). The
// pointers are parameters, so the stores cannot be taken for writes to them: read through the
// block's captured references they had been loaded again for each survivor.
void take_path_columns(const int64_t* pid, const uint32_t* keys, const double* pick, size_t n, const int64_t* idx,
                       size_t k, size_t b, size_t e, int64_t* pid_out, uint32_t* keys_out, double* pick_out) {
    for (size_t j = b; j < e; ++j) {
        const size_t i = size_t(idx[j]);
        pid_out[j] = pid[i];
        keys_out[j] = keys[i];
        keys_out[k + j] = keys[n + i];
    }
    if (pick)
        for (size_t j = b; j < e; ++j) pick_out[j] = pick[size_t(idx[j])];
}

}  // namespace

size_t shade_bounce(const BounceIn& in, const LightChoice& lights, const int64_t* idx, size_t k,
                    const BounceOut& out, size_t* skipped) {
    const size_t n = in.n, blocks = (k + kEventBlock - 1) / kEventBlock;
    float* surf = out.surf;
    const float* ng = surf + 3 * k;
    const float* P_off = surf + 6 * k;
    const float* ns = in.normals ? surf + 9 * k : ng;
    VertexPoints pts{};
    pts.P = surf;
    pts.P_off = P_off;
    pts.ns = ns;
    pts.ng = in.normals ? ng : nullptr;  // (flat: ns is ng)
    pts.thr = out.thr;
    pts.keys = out.keys;
    pts.ka = in.nee_ka;
    pts.kb = in.nee_kb;
    pts.pick = out.pick;
    pts.prim = out.prim;
    pts.n = k;
    pts.shorten = in.shorten;
    pts.skip_work = in.skip_work;
    std::unique_ptr<float[]> rough;  // the survivors' rough diffuse table (kRoughRows x k)
    if (in.rough_mat) rough.reset(new float[size_t(kRoughRows) * (k ? k : 1)]);
    pts.rough = rough.get();
    const bool areas = draws_area_lanes(lights);
    auto block = [&](size_t q, size_t* bad) {
        const size_t b = q * kEventBlock, e = std::min(k, b + kEventBlock);
        survivor_range(in.hits, n, in.albedo, in.M, in.thr, in.u_rr || in.draw_rr, idx, k, out.thr, in.geo, in.normals,
                       in.D, surf, out.prim, b, e, in.records);
        take_path_columns(in.pid, in.keys, in.pick, n, idx, k, b, e, out.pid, out.keys, out.pick);
        if (in.draw_pick)  // uniform_pick's first uniform of the survivors' own keys
            for_words(out.keys, k, in.draw_ka, in.draw_kb, b, e,
                      [&](size_t j0, size_t m, const uint32_t* w, const uint32_t*) {
                          for (size_t j = 0; j < m; ++j) out.pick[j0 + j] = double(w[j]) * (1.0 / 4294967296.0);
                      });
        if (in.rough_mat)
            for (size_t j = b; j < e; ++j) {
                const size_t i = size_t(idx[j]), m = size_t(in.rough_mat[out.prim[j]]), M = in.rough_M;
                const float rho[3] = {in.rough_rho[m], in.rough_rho[M + m], in.rough_rho[2 * M + m]},
                            d[3] = {in.D[i], in.D[n + i], in.D[2 * n + i]}, N[3] = {ns[j], ns[k + j], ns[2 * k + j]};
                rough_row(in.rough_params, M, m, rho, d, N, rough.get(), k, j);
            }
        const size_t count = event_range(lights, areas, pts, out.nee, b, e, bad);
        if (in.scatter) {
            scatter_range(out.keys, k, in.ka, in.kb, ns, in.normals ? ng : nullptr, out.wi, out.pdf, out.ok, P_off,
                          out.rays, nullptr, b, e);
            if (in.rough_mat)  // the bounce's throughput: the factor for its direction
                for (size_t j = b; j < e; ++j) {
                    const float N[3] = {ns[j], ns[k + j], ns[2 * k + j]},
                                w[3] = {out.wi[j], out.wi[k + j], out.wi[2 * k + j]};
                    float t[3] = {out.thr[j], out.thr[k + j], out.thr[2 * k + j]};
                    rough_diffuse_scale(rough.get(), k, j, N, w, t);
                    for (int c = 0; c < 3; ++c) out.thr[size_t(c) * k + j] = t[c];
                }
        }
        return count;
    };
    return event_blocks(out.nee, blocks, block, skipped);  // (the blocks to whichever worker is free)
}

}  // namespace dacrt
