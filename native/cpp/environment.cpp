// The environment map's tables, radiance, pdf and samples (see environment.h).
#include "environment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.h"

namespace dacrt {

namespace {

constexpr double PI_D = 3.14159265358979323846;
constexpr float PI = float(PI_D);
constexpr float INV_2PI = float(1.0 / (2.0 * PI_D));
constexpr float INV_PI = float(1.0 / PI_D);
constexpr float INV_2PI2 = float(1.0 / (2.0 * PI_D * PI_D));

inline uint32_t wrap(int64_t i, uint32_t size) {
    const int64_t m = i % int64_t(size);
    return uint32_t(m < 0 ? m + size : m);
}

// Radiance at (u, v) in texture space (REPEAT on both axes, as Cycles' environment lookup).
void lookup(const EnvironmentMap& env, float u, float v, float out[3]) {
    const uint32_t w = env.width, h = env.height;
    const float* px = env.rgb.data();
    if (env.closest) {
        const size_t k = (size_t(wrap(int64_t(std::floor(v * float(h))), h)) * w +
                          wrap(int64_t(std::floor(u * float(w))), w)) * 3;
        for (int a = 0; a < 3; ++a) out[a] = px[k + a];
        return;
    }
    const float x = u * float(w) - 0.5f, y = v * float(h) - 0.5f;
    const float x0f = std::floor(x), y0f = std::floor(y);
    const float fx = x - x0f, fy = y - y0f;
    const uint32_t xa = wrap(int64_t(x0f), w), xb = wrap(int64_t(x0f) + 1, w);
    const uint32_t ya = wrap(int64_t(y0f), h), yb = wrap(int64_t(y0f) + 1, h);
    const float* p00 = px + (size_t(ya) * w + xa) * 3;
    const float* p01 = px + (size_t(ya) * w + xb) * 3;
    const float* p10 = px + (size_t(yb) * w + xa) * 3;
    const float* p11 = px + (size_t(yb) * w + xb) * 3;
    for (int a = 0; a < 3; ++a)
        out[a] = (p00[a] * (1.0f - fx) + p01[a] * fx) * (1.0f - fy) + (p10[a] * (1.0f - fx) + p11[a] * fx) * fy;
}

// pdf over the sphere of a direction in texel (i, j) with sin(theta) = s.
inline float solid_angle_pdf(const EnvironmentMap& env, size_t i, size_t j, float s) {
    return s > 0 ? env.texel_pdf[i * env.width + j] * INV_2PI2 / s : 0.0f;
}

// The index k with cdf[k] <= u < cdf[k + 1] among cdf[0..count], at most count - 1.
template <class T>
inline size_t find_interval(const T* cdf, size_t count, T u) {
    const size_t k = size_t(std::upper_bound(cdf, cdf + count + 1, u) - cdf);
    return k == 0 ? 0 : std::min(k - 1, count - 1);
}

void gather_range(const EnvironmentMap* env, float prob, const float* D, const uint8_t* miss, const float* thr,
                  const float* pdf_bsdf, const int64_t* pid, size_t n, float* L, size_t N, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
        if (!miss[i]) continue;
        const float d[3] = {D[i], D[n + i], D[2 * n + i]};
        float Le[3], pdf;
        environment_eval(*env, d, Le, pdf);
        float w = 1.0f;
        if (prob > 0) {  // power heuristic of this BSDF ray against sampling the map
            float r = prob * pdf / pdf_bsdf[i];
            r *= r;
            w = 1.0f / (1.0f + r);
        }
        float* out = L + size_t(pid[i]);
        for (int a = 0; a < 3; ++a) {
            float v = Le[a] * w;
            if (thr) v *= thr[size_t(a) * n + i];
            out[size_t(a) * N] += v;
        }
    }
}

}  // namespace

std::string build_environment(EnvironmentMap& env, const float* rgb, uint32_t width, uint32_t height,
                              const float to_map[9], bool closest) {
    if (width == 0 || height == 0) return "the map has no pixels";
    if (size_t(width) * height > (size_t(1) << 28)) return "the map has more than 2^28 pixels";
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            double dot = 0;
            for (int a = 0; a < 3; ++a) dot += double(to_map[3 * r + a]) * to_map[3 * c + a];
            if (!(std::fabs(dot - (r == c ? 1.0 : 0.0)) < 1e-4)) return "to_map is not an orthogonal 3x3 matrix";
        }
    const size_t count = size_t(width) * height * 3;
    for (size_t k = 0; k < count; ++k)
        if (!(rgb[k] >= 0 && rgb[k] < std::numeric_limits<float>::infinity()))
            return "pixel value " + std::to_string(rgb[k]) + " at " + std::to_string(k / 3) +
                   " is negative or not finite";
    env.width = width;
    env.height = height;
    env.closest = closest;
    std::copy(to_map, to_map + 9, env.to_map);
    env.rgb.assign(rgb, rgb + count);
    env.row_cdf.assign(size_t(height) + 1, 0.0);
    env.col_cdf.assign(size_t(height) * (width + 1), 0.0f);
    env.texel_pdf.assign(size_t(height) * width, 0.0f);
    // Each texel's mean radiance over its area: its mean RGB, and for bilinear lookup the
    // separable (1, 6, 1) / 8 blend with its neighbours (REPEAT), the exact average of the
    // interpolated image over the texel. Weighting by the texel alone would leave three
    // quarters of a one-texel sun, spread into its neighbours by the filter, to BSDF rays.
    std::vector<double> mean(size_t(width) * height), blur(closest ? 0 : mean.size());
    for (size_t k = 0; k < mean.size(); ++k) mean[k] = (double(rgb[3 * k]) + rgb[3 * k + 1] + rgb[3 * k + 2]) / 3.0;
    if (!closest) {
        for (uint32_t i = 0; i < height; ++i)
            for (uint32_t j = 0; j < width; ++j) {
                const double* r = mean.data() + size_t(i) * width;
                blur[size_t(i) * width + j] = (r[wrap(int64_t(j) - 1, width)] + 6.0 * r[j] + r[wrap(int64_t(j) + 1, width)]) / 8.0;
            }
        for (uint32_t i = 0; i < height; ++i) {
            const double* a = blur.data() + size_t(wrap(int64_t(i) - 1, height)) * width;
            const double* b = blur.data() + size_t(i) * width;
            const double* c = blur.data() + size_t(wrap(int64_t(i) + 1, height)) * width;
            for (uint32_t j = 0; j < width; ++j) mean[size_t(i) * width + j] = (a[j] + 6.0 * b[j] + c[j]) / 8.0;
        }
    }
    std::vector<double> row_w(width);
    double total = 0;
    for (uint32_t i = 0; i < height; ++i) {
        const double s = std::sin(PI_D * (1.0 - (i + 0.5) / height));
        double acc = 0;
        for (uint32_t j = 0; j < width; ++j) {
            row_w[j] = mean[size_t(i) * width + j] * s;
            acc += row_w[j];
        }
        float* c = env.col_cdf.data() + size_t(i) * (width + 1);
        double run = 0;
        for (uint32_t j = 0; j < width; ++j) {
            run += row_w[j];
            c[j + 1] = acc > 0 ? float(run / acc) : float(j + 1) / float(width);
            env.texel_pdf[size_t(i) * width + j] = float(row_w[j]);  // scaled below
        }
        c[width] = 1.0f;
        total += acc;
        env.row_cdf[i + 1] = total;
    }
    env.total = total;
    if (total > 0) {
        for (uint32_t i = 0; i <= height; ++i) env.row_cdf[i] /= total;
        env.row_cdf[height] = 1.0;
        const double scale = double(width) * height / total;
        for (float& p : env.texel_pdf) p = float(p * scale);
    }
    return {};
}

void environment_eval(const EnvironmentMap& env, const float d[3], float Le[3], float& pdf) {
    const float* M = env.to_map;
    float m[3];
    for (int r = 0; r < 3; ++r) m[r] = M[3 * r] * d[0] + M[3 * r + 1] * d[1] + M[3 * r + 2] * d[2];
    const float len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    if (!(len > 0)) {
        Le[0] = Le[1] = Le[2] = 0.0f;
        pdf = 0.0f;
        return;
    }
    const float z = std::min(1.0f, std::max(-1.0f, m[2] / len));
    const float u = 0.5f - std::atan2(m[1], m[0]) * INV_2PI;
    const float v = 1.0f - std::acos(z) * INV_PI;
    lookup(env, u, v, Le);
    const size_t j = std::min(size_t(std::max(0.0f, u * float(env.width))), size_t(env.width) - 1);
    const size_t i = std::min(size_t(std::max(0.0f, v * float(env.height))), size_t(env.height) - 1);
    const float s = std::sqrt(m[0] * m[0] + m[1] * m[1]) / len;
    pdf = env.total > 0 ? solid_angle_pdf(env, i, j, s) : 0.0f;
}

void environment_sample(const EnvironmentMap& env, float u1, float u2, float wi[3], float value[3], float& pdf) {
    if (!(env.total > 0)) {
        wi[0] = wi[1] = 0.0f, wi[2] = 1.0f;
        value[0] = value[1] = value[2] = 0.0f;
        pdf = 0.0f;
        return;
    }
    const uint32_t w = env.width, h = env.height;
    const size_t i = find_interval(env.row_cdf.data(), h, double(u1));
    const double r0 = env.row_cdf[i], r1 = env.row_cdf[i + 1];
    const float fv = std::min(float((double(u1) - r0) / (r1 - r0)), 0x1.fffffep-1f);
    const float* c = env.col_cdf.data() + i * (size_t(w) + 1);
    const size_t j = find_interval(c, w, u2);
    const float fu = std::min((u2 - c[j]) / (c[j + 1] - c[j]), 0x1.fffffep-1f);
    const float u = (float(j) + std::max(0.0f, fu)) / float(w);
    const float v = (float(i) + std::max(0.0f, fv)) / float(h);
    const float theta = PI * (1.0f - v), phi = PI * (1.0f - 2.0f * u);
    const float s = std::sin(theta);
    const float m[3] = {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
    const float* M = env.to_map;  // orthogonal: the inverse is the transpose
    for (int a = 0; a < 3; ++a) wi[a] = M[a] * m[0] + M[3 + a] * m[1] + M[6 + a] * m[2];
    pdf = solid_angle_pdf(env, i, j, s);
    float Le[3];
    lookup(env, u, v, Le);
    const float inv = pdf > 0 ? 1.0f / pdf : 0.0f;
    for (int a = 0; a < 3; ++a) value[a] = Le[a] * inv;
}

void environment_gather(const EnvironmentMap& env, float prob, const float* D, const uint8_t* miss,
                        const float* thr, const float* pdf_bsdf, const int64_t* pid, size_t n, float* L, size_t N) {
    const EnvironmentMap* e = &env;
    parallel_for(n, [&](size_t b, size_t end) { gather_range(e, prob, D, miss, thr, pdf_bsdf, pid, n, L, N, b, end); });
}

}  // namespace dacrt
