// Batched, threaded lamp kernels (see lamps.h): light samples for the samples that picked a
// lamp, and what camera/BSDF rays see of the lamps, in one pass over the rays for all lamps
// instead of one numpy pass per lamp and operation.
#include "lamps.h"

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
    static const int shapes[LAMP_NUM_KINDS] = {3, 3, 2, 2, 1};  // shape codes per kind
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

void gather_range(const LampRecord* rec, const int32_t* lamps, size_t nl, const float* lamp_prob, const float* O,
                  const float* D, const float* t_surf, const uint8_t* miss, const float* thr, const float* pdf_bsdf,
                  const int64_t* pid, size_t n, float* L, size_t N, float clamp, const LightTree* tree,
                  const int32_t* lamp_key, const float* normal, size_t b, size_t e) {
    // Lamp by lamp over the rays (each ray still adds its lamps in list order), and the add is
    // selected, not branched on: whether a ray sees a lamp follows no pattern.
    for (size_t k = 0; k < nl; ++k) {
        const LampRecord& lamp = rec[lamps[k]];
        const int kind = int(lamp.kind);
        const int32_t key = tree && lamp_key ? lamp_key[lamps[k]] : -1;  // a light of the tree
        for (size_t i = b; i < e; ++i) {
            const float o[3] = {O[i], O[n + i], O[2 * n + i]};
            const float d[3] = {D[i], D[n + i], D[2 * n + i]};
            float Le[3] = {0.0f, 0.0f, 0.0f}, pdf_l = 0.0f;
            const bool seen = kind == LAMP_SUN || kind == LAMP_BACKGROUND ? miss[i] && miss_lamp(lamp, d, Le, pdf_l)
                                                                          : hit_lamp(lamp, o, d, t_surf[i], Le, pdf_l);
            float w = 1.0f;
            if (lamp_prob) {  // power heuristic of this BSDF hit against sampling the lamp
                float p_sel = lamp_prob[lamps[k]];
                if (key >= 0 && seen)  // as picked from o with the vertex's normal
                    p_sel = float(double(p_sel) * tree->pdf(o, normal, n, i, key));
                float r = p_sel * pdf_l / pdf_bsdf[i];
                r *= r;
                r += 1.0f;
                w = 1.0f / r;
            }
            float* out = L + index_at(pid, i, N);
            float v[3];
            for (int a = 0; a < 3; ++a) {
                v[a] = Le[a];
                if (thr) v[a] *= thr[size_t(a) * n + i];
                if (lamp_prob) v[a] *= w;
            }
            clamp_light(v, clamp);  // each lamp a ray meets is its own contribution, as in Cycles
            for (int a = 0; a < 3; ++a) out[size_t(a) * N] += seen ? v[a] : 0.0f;
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
                 const int32_t* lamp_key, const float* normal) {
    parallel_for(n, [&](size_t b, size_t e) {
        gather_range(rec, lamps, nl, lamp_prob, O, D, t_surf, miss, thr, pdf_bsdf, pid, n, L, N, clamp, tree, lamp_key,
                     normal, b, e);
    });
}

}  // namespace dacrt
