// The steps of shading one path vertex, as inline functions on one path: hit-point
// reconstruction, the next-event weight, the shadow ray,
// the cosine-weighted bounce and the tracer's record of a ray. The kernels (surface.cpp,
// emitters.cpp, nee.cpp, scatter.cpp, camera.cpp, raypack.cpp) share them; the arithmetic and
// its float32 order are those of the numpy code the kernels replaced.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ray.h"
#include "shading.h"

namespace dacrt {

// Hit point P, geometric and shading normals facing the incoming direction d, and P stepped
// off the surface toward d's side (geo: 15 rows of M; normals: 9 rows of M or null = flat).
// The step (the table's: P's error along the normal, of at most 8 ULPs of the triangle's largest
// coordinate; on a plane z = c ULPs of c, shading.h triangle_table) is cut to half the
// distance the ray's origin lay off the triangle's plane (h.t |ng . d|): the point never moves
// back past where the ray came from. A step larger than a wall's thickness had carried points
// through it where a ray met the wall's back from inside at t ~ 0 (a corner of a 2 mm wall 10
// km from the origin: 8 ULPs are 7.8 mm there), and their light samples then saw the far room.
// P itself keeps at least edge_margin from each edge (inside_edges): a point reconstructed
// on an edge rounds up to an ULP past it, and where a wall meets the triangle there (a room's
// concave corner) that is outside the wall, which the step along the normal runs parallel to.
struct SurfacePoint {
    float P[3], ng[3], ns[3], P_off[3];
};

// The hit point's margin from its triangle's edges (inside_edges): 8 ULPs of the triangle's
// largest coordinate (from the table's v0 and edges), the whole self-intersection step (the
// table's step along the normal is only the share P's error there needs, shading.h
// triangle_table). Within it a neighbour's float test, erring by ULPs of that neighbour's
// coordinates in every axis, could take the point.
template <class G>
inline float edge_margin(const G& g) {
    float top = 0x1p-100f;
    for (int a = 0; a < 3; ++a) {
        const float v0 = g(a);
        top = std::max(top, std::max(std::fabs(v0), std::max(std::fabs(v0 + g(3 + a)), std::fabs(v0 + g(6 + a)))));
    }
    return 8.0f * ulp_of(top);
}

// What inside_edges and the step need of a triangle besides its rows: its edge margin
// (edge_margin), twice its area along its unit normal, its edges' squared lengths (opposite
// corners 0, 1, 2) and the step's squared length and length. Computed from the rows alone, so a
// per-triangle record holding it (hitrecords.h) gives the same bits as computing it per hit.
struct TriangleShape {
    float margin, area2, len2[3], step2, step_len;
};

template <class G>
inline TriangleShape shape_of(const G& g) {
    TriangleShape sh;
    sh.margin = edge_margin(g);
    float e[3][3];  // edges opposite corners 0, 1, 2: v2 - v1, v2 - v0, v1 - v0
    for (int a = 0; a < 3; ++a) {
        e[0][a] = g(6 + a) - g(3 + a);
        e[1][a] = g(6 + a);
        e[2][a] = g(3 + a);
    }
    // twice the area, along the table's unit normal (e1 x e2 . n)
    const float c0 = e[2][1] * e[1][2] - e[2][2] * e[1][1], c1 = e[2][2] * e[1][0] - e[2][0] * e[1][2],
                c2 = e[2][0] * e[1][1] - e[2][1] * e[1][0];
    sh.area2 = c0 * g(9) + c1 * g(10) + c2 * g(11);
    for (int k = 0; k < 3; ++k) sh.len2[k] = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
    sh.step2 = g(12) * g(12) + g(13) * g(13) + g(14) * g(14);
    sh.step_len = std::sqrt(sh.step2);
    return sh;
}

// Barycentrics (u, v) of a triangle of shape sh moved, where needed, to at least
// `margin` from each edge: a weight w_k whose edge lies nearer is raised to margin / (its
// altitude), the largest weight paying for it. Points farther in keep their (u, v) bit for bit.
// The margins are capped at 1/4 of a weight (a triangle narrower than 4 margins: toward its
// middle) and the move at 2 margins (a sharp corner: as far as that goes), so the point never
// travels farther than that: a thin wall standing on the triangle stays on its side. (That is
// inside_edges below; move_inside, the rare move itself, is out of line so that the hot loops
// inlining inside_edges stay short: the rows path had measured 61-65 -> 69-76 ns a hit inlined.)
[[gnu::noinline, gnu::cold]] inline void move_inside(const TriangleShape& sh, float w[3], float& u, float& v) {
    const float margin = sh.margin, area2 = sh.area2;
    const float* len2 = sh.len2;
    float len[3], need[3];
    for (int k = 0; k < 3; ++k) {
        len[k] = std::sqrt(len2[k]);
        need[k] = std::min(margin * len[k] / area2, 0.25f);
    }
    const int big = (w[0] >= w[1] && w[0] >= w[2]) ? 0 : (w[1] >= w[2] ? 1 : 2);  // >= 1/3 > need
    float raise[3] = {0.0f, 0.0f, 0.0f}, travel = 0.0f;
    for (int k = 0; k < 3; ++k) {
        if (k == big) continue;
        raise[k] = std::max(need[k] - w[k], 0.0f);
        travel += raise[k] * len[3 - k - big];  // along the edge from corner big to corner k
    }
    const float cut = travel > 2.0f * margin ? 2.0f * margin / travel : 1.0f;
    for (int k = 0; k < 3; ++k) {
        if (k == big) continue;
        w[k] += raise[k] * cut;
        w[big] -= raise[k] * cut;
    }
    u = w[1];
    v = w[2];
}

inline void inside_edges(const TriangleShape& sh, float& u, float& v) {
    const float margin = sh.margin, area2 = sh.area2;
    if (!(area2 > 0) || !(margin > 0) || !(area2 < kFloatMax)) return;  // degenerate, no step, NaN
    float w[3] = {1.0f - u - v, u, v};
    // the common case, without roots or divisions: distance w_k area2 / len_k >= margin
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
        const float wa = w[k] * area2;
        inside = inside && wa >= 0 && wa * wa >= margin * margin * sh.len2[k];
    }
    if (!inside) move_inside(sh, w, u, v);
}

// surface_point on a triangle's rows g(0..14) (the table's), its corner-normal rows nr(0..8)
// (read only when smooth) and its shape (shape_of g).
template <class G, class N>
inline void surface_point_of(const G& g, const N& nr, bool smooth, const TriangleShape& sh, const Hit& h,
                             const float d[3], SurfacePoint& s) {
    const float len2 = sh.step2, step_len = sh.step_len;
    float u = h.u, v = h.v;
    inside_edges(sh, u, v);
    for (int a = 0; a < 3; ++a) {
        float x = g(3 + a) * u;
        x += g(6 + a) * v;
        x += g(a);
        s.P[a] = x;
    }
    const float dn = g(9) * d[0] + g(10) * d[1] + g(11) * d[2];
    const float flip = dn > 0 ? -1.0f : 1.0f;
    float step = flip;  // the step's scale: its sign, cut where the origin was nearer the plane
    const float half_back = 0.5f * h.t * std::fabs(dn);
    if (half_back * half_back < len2) step *= half_back / step_len;  // (t NaN: the full step)
    for (int a = 0; a < 3; ++a) {
        s.ng[a] = g(9 + a) * flip;
        s.P_off[a] = s.P[a] + g(12 + a) * step;
        s.ns[a] = s.ng[a];
    }
    if (smooth) {
        float n[3];
        for (int a = 0; a < 3; ++a) {
            float x = nr(3 + a) * u;
            x += nr(6 + a) * v;
            x += nr(a);
            n[a] = x;
        }
        const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        // a zero interpolated normal (opposite corner normals) falls back to ng
        if (len > 0 && std::isfinite(len)) {
            const float inv = flip / len;
            for (int a = 0; a < 3; ++a) s.ns[a] = n[a] * inv;
        }
    }
}

inline void surface_point(const float* geo, size_t M, const float* normals, const Hit& h, const float d[3],
                          SurfacePoint& s) {
    const size_t p = prim_at(h, M);
    auto g = [&](int row) { return geo[size_t(row) * M + p]; };
    auto nr = [&](int row) { return normals[size_t(row) * M + p]; };
    surface_point_of(g, nr, normals != nullptr, shape_of(g), h, d, s);
}

// value (radiance / pdf of a light sample) times thr (null = 1) x cos/pi x the power-heuristic
// weight against BSDF sampling / p_sel; whether the sample can contribute (in front of the
// shading and geometric (null: same) normals, some positive channel).
inline bool nee_scale(const float ns[3], const float* ng, const float wi[3], float pdf, float p_sel, const float* thr,
                      float value[3]) {
    const float inv_pi = 0.3183098861837907f;
    const float cos_s = ns[0] * wi[0] + ns[1] * wi[1] + ns[2] * wi[2];
    // power heuristic w = 1 / (1 + (pdf_bsdf / (p_sel pdf_light))^2); delta lights: 1
    float r = cos_s * inv_pi;
    r /= p_sel * pdf;
    r *= r;
    r += 1.0f;
    float scale = cos_s * inv_pi;
    scale /= r * p_sel;
    float m = -1.0f;
    for (int a = 0; a < 3; ++a) {
        float v = value[a];
        if (thr) v *= thr[a];
        v *= scale;
        value[a] = v;
        m = std::max(m, v);  // (m < v) ? v : m ignores a NaN v: a NaN channel alone never counts
    }
    bool good = cos_s > 0 && m > 0;
    if (ng) good = good && (ng[0] * wi[0] + ng[1] * wi[1] + ng[2] * wi[2]) > 0;
    return good;
}

// Cycles' bump_shadowing_term (closure/bsdf.h) of a diffuse closure whose normal N a normal
// map bent away from the smooth normal Ns, toward the unit direction I: 1 where N is Ns; 0
// where I and N lie on different sides of the smooth surface; else, with the material's Bump
// Map Correction (correction), the GGX shadowing G1 of alpha^2 = tan^2(angle(Ns, N)) / 8 at
// I (Conty Estevez et al., "A Microfacet-Based Shadowing Function to Solve the Bump Terminator
// Problem"), which softens the light a bent normal would catch past the terminator.
inline float bump_shadowing(const float Ns[3], const float N[3], const float I[3], bool correction) {
    if (Ns[0] == N[0] && Ns[1] == N[1] && Ns[2] == N[2]) return 1.0f;
    const float cosNsI = Ns[0] * I[0] + Ns[1] * I[1] + Ns[2] * I[2];
    const float cosNsN = Ns[0] * N[0] + Ns[1] * N[1] + Ns[2] * N[2];
    const float cosNI = N[0] * I[0] + N[1] * I[1] + N[2] * I[2];
    if (cosNsI * cosNsN * cosNI < 0.0f) return 0.0f;
    if (!correction) return 1.0f;
    const float cos_i = std::fabs(cosNsI), cos_d = std::fabs(cosNsN);
    if (cos_d >= 1.0f || cos_i >= 1.0f) return 1.0f;
    if (cos_i < 1e-6f) return 0.0f;
    const float tan2_d = 1.0f / (cos_d * cos_d) - 1.0f;
    const float alpha2 = std::min(std::max(0.125f * tan2_d, 0.0f), 1.0f);
    const float tan2_i = (1.0f - cos_i * cos_i) / (cos_i * cos_i);
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha2 * tan2_i));
}

// Cycles' shadow terminator (light/sample.h, closure/bsdf.h): what a smooth-shaded low-poly
// mesh needs so its light does not end in the facets' steps.
//
// Geometry offset: how far (0..1) a shadow ray toward unit L is lifted off a smooth triangle
// whose object has the offset cutoff > 0 (Cycles' shadow_ray_offset), from the cosines with
// the shading normal (NL = |ns . L|) and with the geometric normal on L's side (NgL).
inline float terminator_amount(float NL, float NgL, float cutoff) {
    const float a = NL < cutoff ? 2.0f - (NgL + NL) / cutoff : 1.0f - NgL / cutoff;
    return std::min(std::max(a, 0.0f), 1.0f);
}

// The lift itself (shadow_ray_smooth_surface_offset): the point (u, v) of triangle p moved
// onto the smooth surface its corner normals describe (a parabolic fit, bounded by each
// corner's tangent plane), in world space; Ng: the geometric normal on the side the ray
// leaves. geo: the triangle table (15 rows of M), normals: corner rows (9 rows of M).
inline void terminator_lift(const float* geo, const float* normals, size_t M, size_t p, float u, float v,
                            const float Ng[3], float lift[3]) {
    float V[3][3], N[3][3];
    for (int a = 0; a < 3; ++a) {
        const float v0 = geo[size_t(a) * M + p], n0 = normals[size_t(a) * M + p];
        V[0][a] = v0;
        V[1][a] = v0 + geo[size_t(3 + a) * M + p];
        V[2][a] = v0 + geo[size_t(6 + a) * M + p];
        N[0][a] = n0;
        N[1][a] = n0 + normals[size_t(3 + a) * M + p];
        N[2][a] = n0 + normals[size_t(6 + a) * M + p];
    }
    auto dot_diff = [](const float* a, const float* b, const float* n) {  // (a - b) . n
        return (a[0] - b[0]) * n[0] + (a[1] - b[1]) * n[1] + (a[2] - b[2]) * n[2];
    };
    const float w0 = 1.0f - u - v;
    float P[3], n[3];
    for (int a = 0; a < 3; ++a) {
        P[a] = V[0][a] * w0 + V[1][a] * u + V[2][a] * v;
        n[a] = N[0][a] * w0 + N[1][a] * u + N[2][a] * v;  // not normalised, as in Cycles
    }
    float d20[3], d21[3], d10[3];
    for (int a = 0; a < 3; ++a) d20[a] = N[2][a] - N[0][a], d21[a] = N[2][a] - N[1][a], d10[a] = N[1][a] - N[0][a];
    const float pa = dot_diff(V[0], V[2], d20), pb = dot_diff(V[1], V[2], d21), pc = dot_diff(V[1], V[0], d10);
    float h = pa * w0 * (w0 - 1) + (pa + pb + pc) * w0 * u + pb * u * (u - 1);
    if (n[0] * Ng[0] + n[1] * Ng[1] + n[2] * Ng[2] > 0) {
        float e[3];
        for (int k = 0; k < 3; ++k) {
            const int i = (k + 1) % 3, j = (k + 2) % 3;
            e[k] = std::max(std::max(dot_diff(V[i], V[k], N[k]), dot_diff(V[j], V[k], N[k])), 0.0f);
            e[k] = std::max(dot_diff(V[k], P, N[k]) + e[k], 0.0f);
        }
        h = std::max(std::min(std::min(e[0], e[1]), e[2]), h * 0.5f);
    } else {
        float e[3];
        for (int k = 0; k < 3; ++k) {
            const int i = (k + 1) % 3, j = (k + 2) % 3;
            e[k] = std::max(std::max(dot_diff(V[k], V[i], N[k]), dot_diff(V[k], V[j], N[k])), 0.0f);
            e[k] = std::max(dot_diff(P, V[k], N[k]) + e[k], 0.0f);
        }
        h = std::min(-std::min(std::min(e[0], e[1]), e[2]), h * 0.5f);
    }
    for (int a = 0; a < 3; ++a) lift[a] = n[a] * h;
}

// Shading offset: the factor on a diffuse reflection toward a direction at cosine c to the
// shading normal, for Cycles' frequency multiplier 1 / (1 - offset / 2) (> 1; Appleseed's
// shift_cos_in): the cosine's angle stretched, so the light falls off before the terminator.
inline float shift_cos_in(float c, float freq) {
    c = std::min(c, 1.0f);
    return std::max(std::cos(std::acos(c) * freq), 0.0f) / c;
}

// The tracer's record of ray i from origins O and directions D (3 rows, stride n).
inline void ray_record(const float* O, const float* D, size_t n, size_t i, float tfar, Ray& r) {
    for (int a = 0; a < 3; ++a) {
        r.org[a] = O[size_t(a) * n + i];
        r.dir[a] = D[size_t(a) * n + i];
    }
    r.tfar = tfar;
    r.id = uint32_t(i);
}

// The shadow ray from O along wi over dist or, with a target (non-null, not NaN), toward it
// over that distance x shorten. False (record tfar 0, never occluded) for a zero-length ray.
inline bool shadow_record(const float O[3], const float wi[3], float dist, const float* target, float shorten,
                          Ray& r) {
    float d[3], len;
    for (int a = 0; a < 3; ++a) r.org[a] = O[a];
    if (target && !std::isnan(target[0])) {
        for (int a = 0; a < 3; ++a) d[a] = target[a] - r.org[a];
        len = length3(d);
        const float inv = len > 0 ? 1.0f / len : 0.0f;
        for (int a = 0; a < 3; ++a) d[a] *= inv;
        len *= shorten;
        if (!(len <= kFloatMax)) len = 0.0f;   // a target beyond float range: no ray
    } else {
        for (int a = 0; a < 3; ++a) d[a] = wi[a];
        len = dist;
    }
    const bool good = len > 0;
    for (int a = 0; a < 3; ++a) r.dir[a] = good ? d[a] : (a == 2 ? 1.0f : 0.0f);
    r.tfar = good ? len : 0.0f;
    return good;
}

// sin and cos of 2 pi u for u in [0, 1): quadrant by the top bits, Taylor polynomials on
// [0, pi/2] (truncation < 6e-8). Branch-free plain IEEE operations, so per-ISA clones
// vectorise it and agree bit for bit (libm's sinf/cosf are scalar calls).
inline void sincos_turn(float u, float& s, float& c) {
    const float q4 = u * 4.0f;
    const int q = int(q4);
    const float x = (q4 - float(q)) * 1.5707963267948966f, x2 = x * x;
    const float sn = x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880 +
                     x2 * (-1.0f / 39916800))))));
    const float cs = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 + x2 * (
                     -1.0f / 3628800 + x2 * (1.0f / 479001600))))));
    // rotate by q quarter turns: (s, c) = (sn, cs), (cs, -sn), (-sn, -cs), (-cs, sn)
    const bool swap = q & 1, neg_s = q & 2, neg_c = (q + 1) & 2;
    s = swap ? cs : sn;
    c = swap ? sn : cs;
    s = neg_s ? -s : s;
    c = neg_c ? -c : c;
}

// Cosine-weighted direction around the unit normal n (Malley: a uniform disk point lifted to
// the hemisphere, in Duff et al.'s branchless basis); returns its pdf cos / pi (0: grazing).
inline float malley(float u1, float u2, const float n[3], float wi[3]) {
    const float inv_pi = 0.3183098861837907f;
    float sp, cp;
    sincos_turn(u2, sp, cp);
    const float rad = std::sqrt(u1);
    const float lx = rad * cp, ly = rad * sp;
    const float lz = std::sqrt(std::max(1.0f - u1, 0.0f));
    const float nx = n[0], ny = n[1], nz = n[2];
    const float sign = nz >= 0 ? 1.0f : -1.0f;
    const float a = -1.0f / (sign + nz);
    const float bb = nx * ny * a;
    const float t0 = 1.0f + sign * nx * a * nx, t1 = sign * bb, t2 = -sign * nx;
    const float b0 = bb, b1 = sign + ny * ny * a, b2 = -ny;
    wi[0] = t0 * lx + b0 * ly + nx * lz;
    wi[1] = t1 * lx + b1 * ly + ny * lz;
    wi[2] = t2 * lx + b2 * ly + nz * lz;
    return lz * inv_pi;
}

}  // namespace dacrt
