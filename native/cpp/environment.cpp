// The environment map's tables, radiance, pdf and samples (see environment.h).
#include "environment.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "envcell.h"
#include "envlanes.h"
#include "equirect.h"
#include "parallel.h"
#include "shading.h"

namespace dacrt {

namespace {

using envcell::bilerp;
using envcell::INV_2PI2;

// i modulo size (REPEAT). Lookups and samples only ever step one period out ([-size, 2 size)),
// so that range is wrapped by a compare instead of an integer division (up to ten per sample:
// ~20% of an environment render's light sampling).
inline uint32_t wrap(int64_t i, uint32_t size) {
    const int64_t s = int64_t(size);
    if (i >= 0 && i < s) return uint32_t(i);
    if (i < 0 && i >= -s) return uint32_t(i + s);
    if (i >= s && i < 2 * s) return uint32_t(i - s);
    const int64_t m = i % s;
    return uint32_t(m < 0 ? m + s : m);
}

// Where (u, v) falls for bilinear lookup: the cell between texel centres (row i, column j:
// corners (i, j), (i, j+1), (i+1, j), (i+1, j+1), wrapped) and the place (fx, fy) in it.
struct Cell {
    uint32_t i, j, i1, j1;
    float fx, fy;
};

inline Cell cell_of(const EnvironmentMap& env, float u, float v) {
    const uint32_t w = env.width, h = env.height;
    const float x = u * float(w) - 0.5f, y = v * float(h) - 0.5f;
    const float x0 = std::floor(x), y0 = std::floor(y);
    Cell c;
    c.j = wrap(int64_t(x0), w), c.j1 = wrap(int64_t(x0) + 1, w);
    c.i = wrap(int64_t(y0), h), c.i1 = wrap(int64_t(y0) + 1, h);
    c.fx = x - x0, c.fy = y - y0;
    return c;
}

// Cycles' color_srgb_to_linear (negative -> 0).
inline float srgb_to_linear(float c) {
    return c < 0.04045f ? std::max(c * (1.0f / 12.92f), 0.0f) : std::pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

// An sRGB map's looked-up (blended) encoded value -> radiance.
inline void decode(const EnvironmentMap& env, float out[3]) {
    for (int a = 0; a < 3; ++a) out[a] = srgb_to_linear(out[a]) * env.scale[a];
}

// Radiance at (u, v) in texture space (REPEAT on both axes, as Cycles' environment lookup). A
// channel blending in a NaN texel's (an image's NaN or infinite value: envbuild.cpp) reads 0,
// as Cycles' blend is NaN there and its film's ensure_finite drops it: over the four cells
// around the texel, not its own area only (zeroing the texel had darkened 4x less than Cycles).
void lookup(const EnvironmentMap& env, float u, float v, float out[3]) {
    const uint32_t w = env.width, h = env.height;
    const float* px = env.texel.data();
    if (env.closest) {
        const size_t k = (size_t(wrap(int64_t(std::floor(v * float(h))), h)) * w +
                          wrap(int64_t(std::floor(u * float(w))), w)) * 4;
        for (int a = 0; a < 3; ++a) out[a] = px[k + a];
    } else {
        const Cell c = cell_of(env, u, v);
        const float* p00 = px + (size_t(c.i) * w + c.j) * 4;
        const float* p01 = px + (size_t(c.i) * w + c.j1) * 4;
        const float* p10 = px + (size_t(c.i1) * w + c.j) * 4;
        const float* p11 = px + (size_t(c.i1) * w + c.j1) * 4;
        for (int a = 0; a < 3; ++a) out[a] = bilerp(p00[a], p01[a], p10[a], p11[a], c.fx, c.fy);
    }
    if (env.srgb) decode(env, out);
    for (int a = 0; a < 3; ++a) out[a] = envcell::finite_or_0(out[a]);
}

// The pdf over (u, v) at (u, v): constant per texel ('Closest'), or the cell's scale times the
// bilinear blend of its corners' luminance (proportional to the looked-up radiance's mean).
inline float uv_pdf(const EnvironmentMap& env, float u, float v) {
    const uint32_t w = env.width, h = env.height;
    if (env.closest) {
        const size_t j = std::min(size_t(std::max(0.0f, u * float(w))), size_t(w) - 1);
        const size_t i = std::min(size_t(std::max(0.0f, v * float(h))), size_t(h) - 1);
        return env.cell_pdf[i * w + j];
    }
    const Cell c = cell_of(env, u, v);
    const float* L = env.texel.data() + 3;  // luminance, stride 4
    return env.cell_pdf[size_t(c.i) * w + c.j] * bilerp(L[(size_t(c.i) * w + c.j) * 4], L[(size_t(c.i) * w + c.j1) * 4],
                                                         L[(size_t(c.i1) * w + c.j) * 4],
                                                         L[(size_t(c.i1) * w + c.j1) * 4], c.fx, c.fy);
}

// The index k with c[k] <= u < c[k + 1] among c[0..count], at most count - 1, for a guided CDF.
// std::upper_bound within the bucket, not a branch-free search: its speculation runs ahead
// through a big map's CDF rows, where the dependent loads of a branch-free one made a 2K x 1K
// map's samples 8-20% slower (and a 96 x 48 one's no faster).
template <class T>
inline size_t find_guided(const T* c, size_t count, const uint32_t* g, uint32_t G, T u) {
    const uint32_t b = std::min(uint32_t(u * T(G)), G - 1);
    const size_t k = size_t(std::upper_bound(c + g[b], c + g[b + 1], u) - c);
    return k == 0 ? 0 : std::min(k - 1, count - 1);
}

// Radiance at (u, v) and the solid-angle pdf of sampling it, sin_theta < 0: no direction.
inline void eval_uv(const EnvironmentMap& env, float u, float v, float sin_theta, float Le[3], float& pdf) {
    if (!(sin_theta >= 0.0f)) {
        Le[0] = Le[1] = Le[2] = 0.0f;
        pdf = 0.0f;
        return;
    }
    lookup(env, u, v, Le);
    pdf = env.total > 0 && sin_theta > 0 ? uv_pdf(env, u, v) * INV_2PI2 / sin_theta : 0.0f;
}

// What a map with nothing to sample gives: no direction's value, pdf 0.
inline void no_sample(float wi[3], float value[3], float& pdf) {
    wi[0] = wi[1] = 0.0f, wi[2] = 1.0f;
    value[0] = value[1] = value[2] = 0.0f;
    pdf = 0.0f;
}

// The cell that uniforms u1 (row), u2 (column) pick (env.total > 0), by the guided searches:
// row i, column j and the CDF entries around u1 (r0, r1) and u2 (c0, c1).
struct Picked {
    size_t i, j;
    double r0, r1;
    float c0, c1;
};

inline Picked pick_cell(const EnvironmentMap& env, float u1, float u2) {
    const uint32_t w = env.width, h = env.height;
    Picked p;
    p.i = find_guided(env.row_cdf.data(), h, env.row_guide.data(), env.row_buckets, double(u1));
    p.r0 = env.row_cdf[p.i], p.r1 = env.row_cdf[p.i + 1];
    const float* c = env.col_cdf.data() + p.i * (size_t(w) + 1);
    p.j = find_guided(c, w, env.col_guide.data() + p.i * (size_t(env.guide_buckets) + 1), env.guide_buckets, u2);
    p.c0 = c[p.j], p.c1 = c[p.j + 1];
    return p;
}

// 'Linear': the luminances of the picked cell's corners (i, j), (i, j+1), (i+1, j), (i+1, j+1).
inline void corners(const EnvironmentMap& env, const Picked& p, float& a, float& b, float& c, float& d) {
    const size_t w = env.width, i = p.i, j = p.j;
    const size_t i1 = i + 1 == env.height ? 0 : i + 1, j1 = j + 1 == w ? 0 : j + 1;
    const float* L = env.texel.data() + 3;  // luminance, stride 4
    a = L[(i * w + j) * 4], b = L[(i * w + j1) * 4], c = L[(i1 * w + j) * 4], d = L[(i1 * w + j1) * 4];
    // envcell::sample_linear squares sums of corners, inf past ~9e18 (every direction was NaN):
    // a cell with a corner above 2^60 is placed with its corners x 2^-80, a power of two, which
    // the placement's operations carry exactly (only maps that have such a corner test it)
    if (env.steep && std::max(std::max(a, b), std::max(c, d)) > 0x1p60f) a *= 0x1p-80f, b *= 0x1p-80f, c *= 0x1p-80f, d *= 0x1p-80f;
}

// 'Closest': fu, fv < 1, but the division can round u up onto the next texel's edge, whose
// texel (black, say) the lookup and the pdf would then read: stay inside the sampled one.
inline void keep_inside(const EnvironmentMap& env, const Picked& p, float& u, float& v) {
    while (u * float(env.width) >= float(p.j + 1)) u = std::nextafter(u, 0.0f);
    while (v * float(env.height) >= float(p.i + 1)) v = std::nextafter(v, 0.0f);
}

// The (u, v) that uniforms u1, u2 sample (env.total > 0): a place in the picked texel
// ('Closest') or in the picked cell's bilinear blend ('Linear'), envcell.h.
inline void sample_uv(const EnvironmentMap& env, float u1, float u2, float& u, float& v) {
    const Picked p = pick_cell(env, u1, u2);
    const float fv = envcell::row_fraction(u1, p.r0, p.r1), fu = envcell::column_fraction(u2, p.c0, p.c1);
    const float fw = float(env.width), fh = float(env.height);
    if (env.closest) {
        envcell::closest_place(fu, fv, float(p.j), float(p.i), fw, fh, u, v);
        keep_inside(env, p, u, v);
    } else {
        float a, b, c, d;
        corners(env, p, a, b, c, d);
        envcell::linear_place(fu, fv, a, b, c, d, float(p.j), float(p.i), fw, fh, u, v);
    }
}

// A sample at (u, v) (direction's sin(theta) s): its solid-angle pdf and radiance / pdf.
inline void weigh_sample(const EnvironmentMap& env, float u, float v, float s, float value[3], float& pdf) {
    pdf = s > 0 ? uv_pdf(env, u, v) * INV_2PI2 / s : 0.0f;
    float Le[3];
    lookup(env, u, v, Le);
    const float inv = pdf > 0 ? 1.0f / pdf : 0.0f;
    for (int a = 0; a < 3; ++a) value[a] = Le[a] * inv;
}

// A texel record (r, g, b, luminance) as one 16-byte vector: the four channels' blends in one
// set of operations, each channel's those of bilerp (envcell.h) in order, so the same bits.
typedef float Record __attribute__((vector_size(16)));

// 'Linear' without sRGB: the lookup and the pdf in the cell with rows i, i1 and columns j, j1 at
// (fx, fy), sin(theta) s >= 0: radiance into out[0, stride, 2 stride] (divided by the pdf with
// divide, 0 where it is 0) and the solid-angle pdf (0 without has_pdf or where s is 0).
inline void blend_cell(const EnvironmentMap& env, uint32_t i, uint32_t i1, uint32_t j, uint32_t j1, float fx,
                       float fy, float s, bool has_pdf, bool divide, float* out, size_t stride, float& pdf) {
    const size_t w = env.width;
    const size_t at[4] = {size_t(i) * w + j, size_t(i) * w + j1, size_t(i1) * w + j, size_t(i1) * w + j1};
    Record c[4];
    for (int q = 0; q < 4; ++q) std::memcpy(&c[q], env.texel.data() + at[q] * 4, sizeof(Record));
    const float gx = 1.0f - fx, gy = 1.0f - fy;
    const Record b = (c[0] * gx + c[1] * fx) * gy + (c[2] * gx + c[3] * fx) * fy;
    pdf = has_pdf && s > 0 ? env.cell_pdf[at[0]] * b[3] * INV_2PI2 / s : 0.0f;
    const float inv = pdf > 0 ? 1.0f / pdf : 0.0f;
    // a channel blending in a NaN texel reads 0, as lookup
    for (int a = 0; a < 3; ++a) {
        const float le = envcell::finite_or_0(b[a]);
        out[a * stride] = divide ? le * inv : le;
    }
}

// blend_cell at places (u, v)[k], sin(theta) s[k], k < m, the cells found lane by lane
// (env_cell_lanes; elsewhere than one period of REPEAT by cell_of): out[a * stride + k], pdf[k].
// A place without a direction (s < 0) gets 0 and pdf 0, as eval_uv.
void blend_places(const EnvironmentMap& env, const float* u, const float* v, const float* s, size_t m, EnvCells& c,
                  bool has_pdf, bool divide, float* out, size_t stride, float* pdf) {
    env_cell_lanes(env.width, env.height, u, v, s, m, c);
    for (size_t k = 0; k < m; ++k) {
        if (c.ok[k]) {
            blend_cell(env, c.i0[k], c.i1[k], c.j0[k], c.j1[k], c.fx[k], c.fy[k], s[k], has_pdf, divide, out + k,
                       stride, pdf[k]);
        } else if (s[k] >= 0.0f) {
            const Cell x = cell_of(env, u[k], v[k]);
            blend_cell(env, x.i, x.i1, x.j, x.j1, x.fx, x.fy, s[k], has_pdf, divide, out + k, stride, pdf[k]);
        } else {
            for (int a = 0; a < 3; ++a) out[a * stride + k] = 0.0f;
            pdf[k] = 0.0f;
        }
    }
}

// The lookups and pdfs run through blend_places for 'Linear' maps without sRGB decoding.
inline bool blends_in_lanes(const EnvironmentMap& env) { return !env.closest && !env.srgb; }

// The missed rays of [b, e) in chunks: their (u, v) lane by lane (envlanes.h), then the lookups.
void gather_range(const EnvironmentMap* env, float prob, const float* D, Missed miss, const float* thr,
                  const float* pdf_bsdf, const int64_t* pid, size_t n, float* L, size_t N, float clamp, size_t b, size_t e) {
    constexpr size_t K = 64;
    size_t idx[K];
    float dx[K], dy[K], dz[K], us[K], vs[K], ss[K];
    const bool lanes = blends_in_lanes(*env);
    EnvCells cells;
    float Les[3 * kEnvLanes], pdfs[kEnvLanes];
    size_t i = b;
    while (i < e) {
        // the next K missed rays, branch-free: which rays missed follows no pattern (a branch
        // per ray was the gather's most mispredicted); a ray that hit is written and overwritten
        size_t m = 0;
        for (; i < e && m < K; ++i) {
            idx[m] = i, dx[m] = D[i], dy[m] = D[n + i], dz[m] = D[2 * n + i];
            m += miss(i);
        }
        equirect_uv_lanes(env->to_map, dx, dy, dz, m, us, vs, ss);
        if (lanes) {
            // camera rays (prob 0) weigh nothing by the pdf: it is not computed
            blend_places(*env, us, vs, ss, m, cells, env->total > 0 && prob > 0, false, Les, kEnvLanes, pdfs);
        }
        for (size_t q = 0; q < m; ++q) {
            const size_t r = idx[q];
            float Le[3], pdf;
            if (lanes) {
                for (int a = 0; a < 3; ++a) Le[a] = Les[a * kEnvLanes + q];
                pdf = pdfs[q];
            } else {
                eval_uv(*env, us[q], vs[q], ss[q], Le, pdf);
            }
            float w = 1.0f;
            if (prob > 0) {  // power heuristic of this BSDF ray against sampling the map
                float x = prob * pdf / pdf_bsdf[r];
                x *= x;
                w = 1.0f / (1.0f + x);
            }
            float* out = L + index_at(pid, r, N);
            float v[3];
            for (int a = 0; a < 3; ++a) {
                v[a] = Le[a] * w;
                if (thr) v[a] *= thr[size_t(a) * n + r];
            }
            clamp_light(v, clamp);
            for (int a = 0; a < 3; ++a) out[size_t(a) * N] += v[a];
        }
    }
}

}  // namespace

void environment_eval(const EnvironmentMap& env, const float d[3], float Le[3], float& pdf) {
    float u, v, s;
    equirect_uv_lanes(env.to_map, d, d + 1, d + 2, 1, &u, &v, &s);
    eval_uv(env, u, v, s, Le, pdf);
}

void environment_sample(const EnvironmentMap& env, float u1, float u2, float wi[3], float value[3], float& pdf) {
    if (!(env.total > 0)) {
        no_sample(wi, value, pdf);
        return;
    }
    float u, v, m[3], s;
    sample_uv(env, u1, u2, u, v);
    equirect::from_uv(u, v, m, s);
    const float* M = env.to_map;  // orthogonal: the inverse is the transpose
    for (int a = 0; a < 3; ++a) wi[a] = M[a] * m[0] + M[3 + a] * m[1] + M[6 + a] * m[2];
    weigh_sample(env, u, v, s, value, pdf);
}

void environment_sample_lanes(const EnvironmentMap& env, const float* u1, const float* u2, size_t m, float* wi,
                              float* value, float* pdf, size_t stride) {
    if (!(env.total > 0)) {
        for (size_t k = 0; k < m; ++k) {
            float w[3], val[3];
            no_sample(w, val, pdf[k]);
            for (int a = 0; a < 3; ++a) wi[a * stride + k] = w[a], value[a * stride + k] = val[a];
        }
        return;
    }
    constexpr size_t K = kEnvLanes;
    EnvPicks in;
    EnvCells cells;
    Picked picked[K];
    float us[K], vs[K], ss[K];
    const bool closest = env.closest;
    for (size_t k0 = 0; k0 < m; k0 += K) {
        const size_t c = std::min(K, m - k0);
        for (size_t k = 0; k < c; ++k) {  // the searches and the corners' loads, point by point
            const Picked& p = picked[k] = pick_cell(env, u1[k0 + k], u2[k0 + k]);
            in.u1[k] = u1[k0 + k], in.u2[k] = u2[k0 + k];
            in.r0[k] = p.r0, in.r1[k] = p.r1, in.c0[k] = p.c0, in.c1[k] = p.c1;
            in.fj[k] = float(p.j), in.fi[k] = float(p.i);
            if (!closest) corners(env, p, in.a[k], in.b[k], in.c[k], in.d[k]);
        }
        env_place_lanes(closest, float(env.width), float(env.height), in, c, us, vs);
        if (closest)
            for (size_t k = 0; k < c; ++k) keep_inside(env, picked[k], us[k], vs[k]);
        equirect_dir_lanes(env.to_map, us, vs, c, wi + k0, wi + stride + k0, wi + 2 * stride + k0, ss);
        if (blends_in_lanes(env)) {
            blend_places(env, us, vs, ss, c, cells, true, true, value + k0, stride, pdf + k0);
            continue;
        }
        for (size_t k = 0; k < c; ++k) {
            float val[3];
            weigh_sample(env, us[k], vs[k], ss[k], val, pdf[k0 + k]);
            for (int a = 0; a < 3; ++a) value[a * stride + k0 + k] = val[a];
        }
    }
}

void environment_gather(const EnvironmentMap& env, float prob, const float* D, Missed miss,
                        const float* thr, const float* pdf_bsdf, const int64_t* pid, size_t n, float* L, size_t N,
                        float clamp) {
    const EnvironmentMap* e = &env;
    parallel_for(n, [&](size_t b, size_t end) {
        gather_range(e, prob, D, miss, thr, pdf_bsdf, pid, n, L, N, clamp, b, end);
    });
}

}  // namespace dacrt
