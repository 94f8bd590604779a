// Light samples of one area lamp (without spread) toward kLampLanes shading points at once:
// sample_lamp's float32 operations (lamps.h: sph_rect, sph_rect_sample, the draw by area) in its
// order, written as loops over lanes. sample_lamp runs one point's long chain of dependent
// divisions and square roots at a time, with branches between them; here each step runs for
// every lane, both of a rectangle's draws (by solid angle and by area) are computed and the lane
// keeps the one sample_lamp would take, so the compiler keeps the lanes in vector registers.
// Per lane the bits are sample_lamp's (tests/integrator/test_next_event.py compares them).
#pragma once

#include <cmath>
#include <limits>

#include "lamps.h"

namespace dacrt {

// 16: one AVX-512 vector per step (two AVX2 ones): with 8, a Cornell render's shade_bounce took
// 5% more CPU and its lamp_gather (AVX2 clone) 24% more.
constexpr int kLampLanes = 16;

struct LampLanes {
    float wi[3][kLampLanes], dist[kLampLanes], value[3][kLampLanes], pdf[kLampLanes];
};

// Whether sample_area_lanes draws lamp L's samples: an area lamp without spread.
// (an IES profile's or a Light Falloff's area lamp goes through sample_lamp and hit_area, one
// sample at a time)
inline bool area_lanes_apply(const LampRecord& L) {
    return int(L.kind) == LAMP_AREA && L.spread_norm == 0 && L.ies == 0 && !has_falloff(L);
}

namespace lanes {
// lamps.h's helpers as plain selects, the same results (NaN included) where vectorised
inline float vmax(float a, float b) { return a < b ? b : a; }         // std::max(a, b)
inline float max_sel(float c, float x) { return x > c ? x : c; }      // lampmath::max_sel
inline float min_sel(float c, float x) { return x < c ? x : c; }      // lampmath::min_sel
// lampmath::atan2_4 of one lane: the same operations and selects
inline float atan2(float y, float x) {
    using namespace lampmath;
    const float ax = std::fabs(x), ay = std::fabs(y);
    const bool swap = ay > ax;
    const float num = swap ? ax : ay, den = swap ? ay : ax;
    const bool mid = num > 0.41421356f * den;
    const float r = (mid ? num - den : num) / (mid ? num + den : den);
    const float z = r * r;
    float p = 8.05374449538e-2f * z - 1.38776856032e-1f;
    p = p * z + 1.99777106478e-1f;
    p = p * z - 3.33329491539e-1f;
    float a = p * z * r + r;
    a = a + (mid ? PI_4 : 0.0f);
    a = swap ? PI_2 - a : a;
    a = 0.0f > x ? PI - a : a;
    return 0.0f > y ? -a : a;
}
}  // namespace lanes

// Samples of area lamp L (area_lanes_apply) toward the points (Px, Py, Pz)[k] with uniforms
// u1[k], u2[k], k < kLampLanes: what sample_lamp(L, P_k, u1[k], u2[k]) returns, per lane.
// (always inlined: a caller compiled per instruction set takes its lanes into its own vectors)
__attribute__((always_inline)) inline void sample_area_lanes(const LampRecord& L, const float* Px, const float* Py, const float* Pz,
                              const float* u1, const float* u2, LampLanes& s) {
    using namespace lampmath;
    constexpr int K = kLampLanes;
    const float* P[3] = {Px, Py, Pz};
    const bool rect = int(L.shape) == AREA_RECT, ellipse = int(L.shape) == AREA_ELLIPSE;
    // the draw by area (sample_lamp's tail): the lamp point's offsets x, y from its centre
    float x[K], y[K];
    if (ellipse) {  // concentric_disk: libm's cos and sin, one lane at a time
        for (int k = 0; k < K; ++k) {
            concentric_disk(u1[k], u2[k], x[k], y[k]);
            x[k] *= 0.5f;
            y[k] *= 0.5f;
        }
    } else {
        for (int k = 0; k < K; ++k) x[k] = u1[k] - 0.5f, y[k] = u2[k] - 0.5f;
    }
    float wi[3][K];
    LampLanes by_area;
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < K; ++k) {
            float q = L.axis_x[a] * x[k];
            q += L.axis_y[a] * y[k];
            wi[a][k] = q + (L.pos[a] - P[a][k]);
        }
    // (every division is done in every lane and selected after: a division under a condition
    // keeps the loop scalar)
    LampLanes& area = rect ? by_area : s;  // a rectangle's draws by area, kept apart from s
    for (int k = 0; k < K; ++k) {
        const float len = std::sqrt(wi[0][k] * wi[0][k] + wi[1][k] * wi[1][k] + wi[2][k] * wi[2][k]);
        const float r = 1.0f / len, inv = len > 0 ? r : 0.0f;
        const float w0 = wi[0][k] * inv, w1 = wi[1][k] * inv, w2 = wi[2][k] * inv;
        area.wi[0][k] = w0, area.wi[1][k] = w1, area.wi[2][k] = w2;
        area.dist[k] = len;
        const float cos_l = -(w0 * L.normal[0] + w1 * L.normal[1] + w2 * L.normal[2]);
        const bool ok = (cos_l > 0) & (len > 0);
        const float p = len * len / (L.area * cos_l), q = 1.0f / p;
        area.pdf[k] = ok ? p : 0.0f;
        const float scale = ok ? q : 0.0f;
        for (int a = 0; a < 3; ++a) area.value[a][k] = L.emit[a] * scale;
    }
    if (!rect) return;

    // a rectangle by solid angle where sph_rect says so (box: the whole square); first its
    // test for a lamp that looks small from P (most points of a room lit by a ceiling lamp)
    const float lx = std::sqrt(dot3(L.axis_x, L.axis_x)), ly = std::sqrt(dot3(L.axis_y, L.axis_y));
    float x0[K], x1[K], y0[K], y1[K], h[K], S[K], d23[K], b0[K], b1[K];
    int use[K];  // (int, not bool: bool lanes keep the loops below scalar)
    int big = 0;
    for (int k = 0; k < K; ++k) {
        const float rel[3] = {P[0][k] - L.pos[0], P[1][k] - L.pos[1], P[2][k] - L.pos[2]};
        const float fx = dot3(rel, L.inv_x), fy = dot3(rel, L.inv_y);
        h[k] = dot3(rel, L.normal);
        x0[k] = (-0.5f - fx) * lx;
        x1[k] = (0.5f - fx) * lx;
        y0[k] = (-0.5f - fy) * ly;
        y1[k] = (0.5f - fy) * ly;
        const float cx = 0.5f * (x0[k] + x1[k]), cy = 0.5f * (y0[k] + y1[k]), ex = x1[k] - x0[k], ey = y1[k] - y0[k];
        const bool small = 0.25f * (ex * ex + ey * ey) < (SA_SMALL * SA_SMALL) * (cx * cx + cy * cy + h[k] * h[k]);
        use[k] = !small;
        big |= use[k];
    }
    if (!big) {
        s = by_area;
        return;
    }
    for (int k = 0; k < K; ++k) {
        const float hk = h[k], h2 = hk * hk;
        // per edge (y0, x1, y1, x0): sph_rect's n = (-y0, x1, y1, -x0) / |(h, edge)| and a = h / |...|
        const float i0 = 1.0f / std::sqrt(h2 + y0[k] * y0[k]), i1 = 1.0f / std::sqrt(h2 + x1[k] * x1[k]);
        const float i2 = 1.0f / std::sqrt(h2 + y1[k] * y1[k]), i3 = 1.0f / std::sqrt(h2 + x0[k] * x0[k]);
        const float n0 = -y0[k] * i0, n1 = x1[k] * i1, n2 = y1[k] * i2, n3 = -x0[k] * i3;
        const float a0 = hk * i0, a1 = hk * i1, a2 = hk * i2, a3 = hk * i3;
        // per corner (edge c and the next, d): sin g and cos m
        auto sin_g = [](float nc, float ac, float nd, float ad) {
            const float aa = ac * ac;
            return std::sqrt(aa * nd * nd + nc * nc * ad * ad + aa * ad * ad);
        };
        const float s0 = sin_g(n0, a0, n1, a1), s1 = sin_g(n1, a1, n2, a2), s2 = sin_g(n2, a2, n3, a3),
                    s3 = sin_g(n3, a3, n0, a0);
        const float c0 = n0 * n1, c1 = n1 * n2, c2 = n2 * n3, c3 = n3 * n0;
        // atan2_4's lanes 0 and 1: corners 0 + 1 and 2 + 3
        d23[k] = lanes::atan2(s2 * c3 + c2 * s3, s2 * s3 - c2 * c3);
        S[k] = lanes::atan2(s0 * c1 + c0 * s1, s0 * s1 - c0 * c1) + d23[k];
        b0[k] = n0;
        b1[k] = n2;
        const float dx = lanes::vmax(0.0f, lanes::vmax(x0[k], -x1[k]));
        const float dy = lanes::vmax(0.0f, lanes::vmax(y0[k], -y1[k]));
        const float t2 = SA_MIN_TAN_ELEVATION * SA_MIN_TAN_ELEVATION;
        const float far2 = lanes::vmax(x0[k] * x0[k], x1[k] * x1[k]) + lanes::vmax(y0[k] * y0[k], y1[k] * y1[k]) + h2;
        use[k] = use[k] & (hk > 0) & (h2 >= std::numeric_limits<float>::min()) & (s0 > 0.0f) & (s1 > 0.0f) &
                 (s2 > 0.0f) & (s3 > 0.0f) & (far2 <= std::numeric_limits<float>::max()) &
                 (h2 >= t2 * (dx * dx + dy * dy)) & (S[k] >= SA_MIN_SOLID_ANGLE);
    }
    int any = 0;
    for (int k = 0; k < K; ++k) any |= use[k];
    if (!any) {
        s = by_area;
        return;
    }
    float c_phi[K], s_phi[K];
    for (int k = 0; k < K; ++k) {  // libm's cos and sin, only where a lane needs them
        const float phi = u1[k] * S[k] - d23[k];
        c_phi[k] = use[k] ? std::cos(phi) : 1.0f;
        s_phi[k] = use[k] ? std::sin(phi) : 1.0f;
    }
    for (int k = 0; k < K; ++k) {  // every lane computed, the by-solid-angle ones kept
        const float hk = h[k], X0 = x0[k], X1 = x1[k], Y0 = y0[k], Y1 = y1[k], Sk = S[k], B0 = b0[k];
        const float fu = (c_phi[k] * B0 + b1[k]) / s_phi[k];
        const float cu0 = 1.0f / std::sqrt(fu * fu + B0 * B0);
        const float cu = lanes::max_sel(-1.0f, lanes::min_sel(1.0f, fu > 0 ? cu0 : -cu0));
        const float xu = cu * hk / lanes::vmax(std::sqrt(1.0f - cu * cu), 1e-7f);
        const float xs = lanes::max_sel(X0, lanes::min_sel(X1, xu));
        const float d2 = xs * xs + hk * hk;
        const float h0 = Y0 / std::sqrt(d2 + Y0 * Y0), h1 = Y1 / std::sqrt(d2 + Y1 * Y1);
        const float hv = h0 + u2[k] * (h1 - h0);
        const float yv = hv * std::sqrt(d2) / std::sqrt(lanes::max_sel(0.0f, 1.0f - hv * hv));
        const float ys = lanes::max_sel(Y0, lanes::min_sel(Y1, yv));
        const float sx = xs / lx, sy = ys / ly;
        float w[3];
        for (int a = 0; a < 3; ++a) {
            float q = L.axis_x[a] * sx;
            q += L.axis_y[a] * sy;
            w[a] = q - L.normal[a] * hk;
        }
        const float len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        const float r = 1.0f / len, inv = len > 0 ? r : 0.0f, pdf = 1.0f / Sk;
        const bool on = use[k];
        for (int a = 0; a < 3; ++a) s.wi[a][k] = on ? w[a] * inv : by_area.wi[a][k];
        s.dist[k] = on ? len : by_area.dist[k];
        s.pdf[k] = on ? pdf : by_area.pdf[k];
        for (int a = 0; a < 3; ++a) s.value[a][k] = on ? L.emit[a] * Sk : by_area.value[a][k];
    }
}

}  // namespace dacrt
