// Cycles' rough diffuse (closure/bsdf_oren_nayar.h: Fujii's improved Oren-Nayar with OpenPBR's
// energy-preserving multiple scattering, "EON") as a factor on a Lambertian sample. Cycles
// samples it cosine-weighted, so pdfs and MIS weights are Lambert's and only the value changes;
// the material's albedo is already its view-averaged albedo D (addon/roughdiffuse.py), so a
// sample takes F / D, F = f_EON / f_Lambert. What depends on the point alone (the view and the
// colour) is a table per point (rough_rows); per direction only the light's part is left.
#pragma once

#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace dacrt {

// Rows of a rough point table (stride n): wo (0-2, toward the viewer), a (3), b (4; 0: Lambert,
// no factor), k = pi Ems (1 - E(nv)) per channel (5-7), 1 / D per channel (8-10).
constexpr int kRoughRows = 11;

// Cycles' bsdf_oren_nayar_G(cos theta), in double: what the table holds.
inline double oren_nayar_G_exact(double c) {
    if (c < 1e-6) return (1.5707963267948966 - 2.0 / 3.0) - c;  // (Cycles' Taylor branch)
    const double s = std::sqrt(std::fmax(1.0 - c * c, 0.0)), th = std::acos(std::fmin(c, 1.0));
    return s * (th - 2.0 / 3.0 - s * c) + 2.0 / 3.0 * (s / c) * (1.0 - s * s * s);
}

// G read off a table over cos in [0, 1], linearly between entries: acos, sqrt and a division
// per call (three per path vertex and sample) had made a rough scene's shading 1.5x Lambert's;
// within 1e-6 of the formula (G runs as (1 - cos)^1.5 at 1, so the steps there matter most).
constexpr int kGSteps = 4096;
struct OrenNayarGTable {
    float v[kGSteps + 2];
    OrenNayarGTable() {
        for (int i = 0; i <= kGSteps; ++i) v[i] = float(oren_nayar_G_exact(double(i) / kGSteps));
        v[kGSteps + 1] = v[kGSteps];
    }
};
inline float oren_nayar_G(float c) {
    static const OrenNayarGTable table;
    const float x = std::fmin(std::fmax(c, 0.0f), 1.0f) * float(kGSteps);
    const int i = int(x);
    const float f = x - float(i);
    return table.v[i] + f * (table.v[i + 1] - table.v[i]);
}

// value (3) times F / D of point i of the table for light direction wi at shading normal ns.
inline void rough_diffuse_scale(const float* rough, size_t n, size_t i, const float ns[3], const float wi[3],
                                float value[3]) {
    const float b = rough[4 * n + i];
    if (!(b > 0.0f)) return;
    const float a = rough[3 * n + i];
    const float wo[3] = {rough[i], rough[n + i], rough[2 * n + i]};
    const float nl = std::fmax(ns[0] * wi[0] + ns[1] * wi[1] + ns[2] * wi[2], 0.0f);
    const float nv = std::fmax(ns[0] * wo[0] + ns[1] * wo[1] + ns[2] * wo[2], 0.0f);
    float t = wi[0] * wo[0] + wi[1] * wo[1] + wi[2] * wo[2] - nl * nv;
    if (t > 0.0f) t /= std::fmax(nl, nv) + FLT_MIN;
    const float pi = 3.14159265358979f;
    const float single = pi * (a + b * t), El = a * pi + b * oren_nayar_G(nl);
    for (int c = 0; c < 3; ++c)
        value[c] *= (single + rough[(5 + c) * n + i] * (1.0f - El)) * rough[(8 + c) * n + i];
}

// Column i of the table (stride n) of a point of material m (params: 4 rows of M, as rough_rows
// takes them), colour rho, ray direction D (wo = -D), shading normal ns.
inline void rough_row(const float* params, size_t M, size_t m, const float rho[3], const float D[3], const float ns[3],
                      float* out, size_t n, size_t i) {
    const float a = params[m], b = params[M + m], ebar = params[2 * M + m], eavg = params[3 * M + m];
    float nv = 0.0f;
    for (int c = 0; c < 3; ++c) {
        out[size_t(c) * n + i] = -D[c];
        nv -= ns[c] * D[c];
    }
    out[3 * n + i] = a;
    out[4 * n + i] = b;
    const float ev = a * 3.14159265358979f + b * oren_nayar_G(std::fmax(nv, 0.0f));
    for (int c = 0; c < 3; ++c) {
        float k = 0.0f, inv_d = 0.0f;
        if (b > 0.0f) {
            // pi Ems of Cycles' multiple scattering, for the saturated colour
            const float r = std::fmin(std::fmax(rho[c], 0.0f), 1.0f);
            const float ms = r * r * eavg / (1.0f - eavg) / (1.0f - r * (1.0f - eavg));
            k = ms * (1.0f - ev);
            inv_d = 1.0f / (ebar + ms * (1.0f - ebar) * (1.0f - ebar));
        }
        out[size_t(5 + c) * n + i] = k;
        out[size_t(8 + c) * n + i] = inv_d;
    }
}

// The table (kRoughRows x n) of n points: material m = mat[i] has params (4 rows of M: a, b,
// Ebar the cos-weighted average of E, Eavg Cycles' fit of it; b 0: not rough, a zero column),
// rho (3 x n) its colour (saturated here, as Cycles' multiple-scattering term takes it), D
// (3 x n) the rays' directions (wo = -D), ns (3 x n) the shading normals.
void rough_rows(const float* params, size_t M, const int32_t* mat, const float* rho, const float* D, const float* ns,
                size_t n, float* out);

// thr (3 x n) times F / D of each point of the table for directions wi (3 x n) at ns, in place
// (a bounce's throughput after its cosine-weighted direction).
void rough_scale(const float* rows, const float* wi, const float* ns, size_t n, float* thr);

}  // namespace dacrt
