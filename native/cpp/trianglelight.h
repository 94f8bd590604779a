// An emissive triangle as a light seen from a point: where a light sample lands and its
// solid-angle pdf, and the same pdf for a ray that meets the triangle (MIS needs both to agree).
//
// A triangle that is large for its distance is sampled uniformly by solid angle (Arvo 1995,
// "Stratified Sampling of Spherical Triangles"), the others uniformly by area. Near a large
// emitter, area sampling's estimate varies with 1/r^2 and the emitter's cosine across the
// triangle without bound: bmw27's two-triangle 82 m^2 ceiling panel left DACRT 1.8x noisier
// than Cycles, which makes the same switch (kernel/light/triangle.h). Cycles' test compares the
// longest edge with a plane distance divided by twice the area, which depends on the scene's
// units; ours compares the longest edge with the distance to the centroid, the same at any scale,
// and never picks solid angle for a far triangle seen edge-on. The spherical arithmetic is in
// double: the corner directions of a small spherical triangle nearly coincide.
//
// geo: 15 rows of M per triangle: v0 (0-2), v1 - v0 (3-5), v2 - v0 (6-8), unit normal (9-11),
// self-intersection step of the front side (12-14).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "shading.h"

namespace dacrt {

namespace tri_light {

inline double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

inline void cross3(const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

// a - (a . b) b normalised (the tangent at unit b toward a); false when a is parallel to b.
inline bool tangent(const double a[3], const double b[3], double out[3]) {
    const double k = dot3(a, b);
    for (int i = 0; i < 3; ++i) out[i] = a[i] - k * b[i];
    const double len = std::sqrt(dot3(out, out));
    if (!(len > 0)) return false;
    for (int i = 0; i < 3; ++i) out[i] /= len;
    return true;
}

}  // namespace tri_light

// Whether triangle w is sampled by solid angle from point p: its longest edge is longer than
// the distance from p to its centroid.
inline bool by_solid_angle(const float* geo, size_t M, size_t w, const double p[3]) {
    auto g = [&](int row) { return double(geo[size_t(row) * M + w]); };
    double l1 = 0, l2 = 0, l3 = 0, c2 = 0;
    for (int a = 0; a < 3; ++a) {
        const double e1 = g(3 + a), e2 = g(6 + a), e3 = e2 - e1;
        l1 += e1 * e1;
        l2 += e2 * e2;
        l3 += e3 * e3;
        const double c = g(a) + (e1 + e2) / 3.0 - p[a];
        c2 += c * c;
    }
    return std::max(l1, std::max(l2, l3)) > c2;
}

// Unit directions A, B, C from p to the corners of triangle w and the solid angle they span
// (Van Oosterom and Strackee's formula); 0 when p lies in the triangle's plane or on a corner.
inline double spherical_triangle(const float* geo, size_t M, size_t w, const double p[3], double A[3], double B[3],
                                 double C[3]) {
    auto g = [&](int row) { return double(geo[size_t(row) * M + w]); };
    for (int a = 0; a < 3; ++a) {
        A[a] = g(a) - p[a];
        B[a] = A[a] + g(3 + a);
        C[a] = A[a] + g(6 + a);
    }
    for (double* v : {A, B, C}) {
        const double len = std::sqrt(tri_light::dot3(v, v));
        if (!(len > 0)) return 0.0;
        for (int a = 0; a < 3; ++a) v[a] /= len;
    }
    double cross[3];
    tri_light::cross3(B, C, cross);
    const double triple = std::fabs(tri_light::dot3(A, cross));
    const double omega = 2.0 * std::atan2(triple, 1.0 + tri_light::dot3(A, B) + tri_light::dot3(B, C) +
                                                      tri_light::dot3(C, A));
    return std::isfinite(omega) && omega > 0 ? omega : 0.0;
}

// A direction uniform in the solid angle of the spherical triangle ABC of area omega (Arvo):
// u1 picks the sub-triangle A B C' of area u1 omega, u2 a point on the arc from B to C'.
// False when the triangle is too thin for the construction (the sample is then dropped).
inline bool arvo_direction(const double A[3], const double B[3], const double C[3], double omega, double u1,
                           double u2, double D[3]) {
    double tb[3], tc[3];
    if (!tri_light::tangent(B, A, tb) || !tri_light::tangent(C, A, tc)) return false;
    // the angle alpha at A by its cosine and sine; s, t = sin, cos of (u1 omega - alpha)
    const double cos_alpha = tri_light::dot3(tb, tc);
    double cross[3];
    tri_light::cross3(tb, tc, cross);
    const double sin_alpha = std::sqrt(tri_light::dot3(cross, cross));
    const double cos_c = tri_light::dot3(A, B);
    const double sin_x = std::sin(u1 * omega), cos_x = std::cos(u1 * omega);
    const double s = sin_x * cos_alpha - cos_x * sin_alpha, t = cos_x * cos_alpha + sin_x * sin_alpha;
    const double u = t - cos_alpha, v = s + sin_alpha * cos_c;
    const double q = ((v * t - u * s) * cos_alpha - v) / ((v * s + u * t) * sin_alpha);
    if (!std::isfinite(q)) return false;
    const double qc = std::clamp(q, -1.0, 1.0), sq = std::sqrt(1.0 - qc * qc);
    double Cp[3], tcb[3];
    for (int a = 0; a < 3; ++a) Cp[a] = qc * A[a] + sq * tc[a];
    const double z = 1.0 - u2 * (1.0 - tri_light::dot3(Cp, B));
    const double sz = std::sqrt(std::max(0.0, 1.0 - z * z));
    if (!tri_light::tangent(Cp, B, tcb)) {  // C' = B: the arc is a point
        for (int a = 0; a < 3; ++a) D[a] = B[a];
        return true;
    }
    for (int a = 0; a < 3; ++a) D[a] = z * B[a] + sz * tcb[a];
    return true;
}

// A point on triangle w seen from P: uniform by solid angle or by area (see the top), random
// numbers u1, u2. Writes the unit direction wi toward it, its distance, the solid-angle pdf (0
// where it cannot be seen: edge-on, coincident) and the point the shadow ray must end at
// (stepped off the emitter toward P). Radiance and pdf use the exact point.
inline void triangle_light(const float* geo, const float* area, size_t M, size_t w, const float P[3], float u1,
                           float u2, float wi[3], float& dist, float& pdf, float target[3]) {
    auto g = [&](int row) { return geo[size_t(row) * M + w]; };
    const double p[3] = {P[0], P[1], P[2]};
    float q[3], d[3], len;
    const bool solid = by_solid_angle(geo, M, w, p);
    double omega = 0.0;
    if (solid) {  // seen edge-on (omega 0) or a failed construction: no sample, as triangle_light_pdf says
        double A[3], B[3], C[3], D[3];
        omega = spherical_triangle(geo, M, w, p, A, B, C);
        const double n[3] = {g(9), g(10), g(11)}, to_v0[3] = {g(0) - p[0], g(1) - p[1], g(2) - p[2]};
        bool found = omega > 0 && arvo_direction(A, B, C, omega, u1, u2, D);
        const double dn = found ? tri_light::dot3(n, D) : 0.0, t = found ? tri_light::dot3(n, to_v0) / dn : 0.0;
        found = found && dn != 0 && t > 0 && std::isfinite(t);
        for (int a = 0; a < 3; ++a) {
            d[a] = found ? float(D[a]) : 0.0f;
            q[a] = found ? float(p[a] + D[a] * t) : P[a];
        }
        len = found ? float(t) : 0.0f;
    } else {
        // uniform point by area: barycentrics (u2 sqrt(u1), 1 - sqrt(u1)) of vertices 1, 2
        const float su = std::sqrt(u1);
        const float b1 = u2 * su, b2 = 1.0f - su;
        for (int a = 0; a < 3; ++a) {
            float x = g(3 + a) * b1;
            x += g(6 + a) * b2;
            x += g(a);
            q[a] = x;
            d[a] = x - P[a];
        }
        len = length3(d);
        const float inv = len > 0 && len < kFloatMax ? 1.0f / len : 0.0f;
        for (int a = 0; a < 3; ++a) d[a] *= inv;
    }
    float cos_l = g(9) * d[0] + g(10) * d[1] + g(11) * d[2];
    const float side = cos_l <= 0 ? 1.0f : -1.0f;  // the emitter face that sees P
    cos_l = std::fabs(cos_l);
    const bool ok = cos_l > 0 && len > 0;
    const float p_l = !ok ? 0.0f : solid ? float(1.0 / omega) : len * len / (area[w] * cos_l);
    // The shadow ray must end in front of the emitter by more than where its end can drift: a
    // few ULPs of its origin's coordinates and of its length, which can exceed the emitter's
    // own step (a small emitter seen from afar). 8 ULPs of the larger.
    float big = len;
    for (int a = 0; a < 3; ++a) big = std::max(big, std::fabs(P[a]));
    const float own = std::sqrt(g(12) * g(12) + g(13) * g(13) + g(14) * g(14));
    const float reach = 8.0f * ulp_of(std::max(big, 0x1p-100f));
    const float scale = own >= reach || !(own > 0) ? side : side * (reach / own);
    for (int a = 0; a < 3; ++a) {
        wi[a] = d[a];
        target[a] = q[a] + g(12 + a) * scale;
    }
    dist = len;
    pdf = std::isfinite(p_l) ? p_l : 0.0f;
}

// The solid-angle pdf with which triangle_light, called at point o, samples the direction d
// that meets triangle w at distance t (0: never sampled that way).
inline float triangle_light_pdf(const float* geo, const float* area, size_t M, size_t w, const float o[3],
                                const float d[3], float t) {
    const double p[3] = {o[0], o[1], o[2]};
    if (by_solid_angle(geo, M, w, p)) {
        double A[3], B[3], C[3];
        const double omega = spherical_triangle(geo, M, w, p, A, B, C);
        const float pdf = omega > 0 ? float(1.0 / omega) : 0.0f;
        return std::isfinite(pdf) ? pdf : 0.0f;
    }
    const float cos_l =
        std::fabs(geo[9 * M + w] * d[0] + geo[10 * M + w] * d[1] + geo[11 * M + w] * d[2]);
    const float pdf = t * t / (area[w] * cos_l);
    return std::isfinite(pdf) ? pdf : 0.0f;
}

}  // namespace dacrt
