// The environment map's tables from an image's texels, threaded by rows (see envbuild.h).
#include "envbuild.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <vector>

#include "parallel.h"

namespace dacrt {

namespace {

constexpr double PI_D = 3.14159265358979323846;

// Cycles' color_srgb_to_linear (negative -> 0): environment.cpp's decode, the same expression so
// the same bits as the lookups'.
inline float srgb_to_linear(float c) {
    return c < 0.04045f ? std::max(c * (1.0f / 12.92f), 0.0f) : std::pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

// An 8-bit image's encoded texels are k x float(1/255) (export/images.py: its bytes as float32
// times 1/255): their decodes from a table of the 256, each taken only where the texel has
// exactly that value, so the bits are srgb_to_linear's. Three pow per texel had been most of
// an sRGB 4K map's build (0.24 s CPU).
struct ByteDecode {
    float value[256], linear[256];
    ByteDecode() {
        for (int k = 0; k < 256; ++k) value[k] = float(k) * float(1.0 / 255.0), linear[k] = srgb_to_linear(value[k]);
    }
    float operator()(float c) const {
        const float x = c * 255.0f + 0.5f;
        if (x >= 0.0f && x < 256.0f) {
            const int k = int(x);
            uint32_t a, b;  // bitwise: -0 decodes to -0
            std::memcpy(&a, &value[k], 4), std::memcpy(&b, &c, 4);
            if (a == b) return linear[k];
        }
        return srgb_to_linear(c);
    }
};

// Integral of sin(theta) dv over v in [v0, v1] within [0, 1], theta = pi (1 - v).
inline double sin_integral(double v0, double v1) {
    return (std::cos(PI_D * (1.0 - v1)) - std::cos(PI_D * (1.0 - v0))) / PI_D;
}

// The guide of one CDF c[0..count] (environment.cpp's find_guided reads it): g[b] = std::upper_bound's position of b / G, b = 0..G.
// For u in [b/G, (b+1)/G) (exact: G is a power of two) the position of u lies in [g[b], g[b+1]]
// (monotone), so searching c[g[b], g[b+1]) finds the same one: one or two cache lines of a row
// instead of ~11 dependent loads through a big map's rows (cutpoint method, Chen and Asau 1974),
// and, for the rows' CDF, one or two mispredicted branches instead of ~log2(height) / 2 (the
// search over the rows was a quarter of a small map's sampling). Built in one walk along the
// sorted CDF, not a search per bucket: the same positions in count + G steps, not G log2(count).
template <class T>
void build_guide(const T* c, size_t count, uint32_t G, uint32_t* g) {
    size_t k = 0;
    for (uint32_t b = 0; b <= G; ++b) {
        const T u = T(b) / T(G);
        while (k <= count && !(u < c[k])) ++k;  // std::upper_bound's test: the first c[k] > u
        g[b] = uint32_t(k);
    }
}

// G for a CDF of count entries: a bucket per entry (at most 1024 buckets), so a sample's search
// meets ~1 entry, not ~8, and its branches rarely mispredict (1M samples of the benchmark's
// 96 x 48 sky 62 -> 46 ms, a 4K x 2K sky ~325 -> ~280 ms, one thread; the same samples). The
// table costs 4 bytes a bucket: up to ~8 bytes a texel on maps up to 1024 wide, 1 on a 4K map.
uint32_t guide_size(size_t count) {
    uint32_t G = 1;
    while (G < 1024 && size_t(G) < count) G *= 2;
    return G;
}

// Rows per thread: at least ~64K texels each (smaller maps build on the calling thread).
size_t min_rows(uint32_t width) { return std::max<size_t>(1, (size_t(1) << 16) / width); }

}  // namespace

namespace {

// texel_stats over texels [b, e) (C channels, or `channels` where C is 0), on the floats' bits so
// that it vectorises: a value is not finite where its exponent is all ones, finite and negative
// where its sign is set and its magnitude in (0, inf), above 0 where its sign is clear and its
// magnitude in (0, inf] (std::isfinite, t < 0 && t > -inf and t > 0 had compiled to a branch
// per value: a 4K RGBA map's scan ~2.7x slower on one thread).
template <size_t C>
TexelStats stats_range(const float* texels, size_t channels, size_t b, size_t e) {
    const size_t ch = C ? C : channels;
    uint64_t bad = 0;
    uint32_t neg = 0, pos = 0;
    for (size_t k = b; k < e; ++k) {
        uint32_t f = 0, n = 0, p = 0;
        for (size_t a = 0; a < 3; ++a) {
            uint32_t x;
            std::memcpy(&x, texels + k * ch + a, 4);
            const uint32_t m = x & 0x7fffffffu, s = x >> 31;
            f |= uint32_t(m >= 0x7f800000u);
            n |= s & uint32_t(m - 1u < 0x7f7fffffu);           // m in [1, 0x7f7fffff]
            p |= (s ^ 1u) & uint32_t(m - 1u < 0x7f800000u);    // m in [1, 0x7f800000]
        }
        bad += f, neg |= n, pos |= p;
    }
    return {size_t(bad), neg != 0, pos != 0};
}

}  // namespace

TexelStats texel_stats(const float* texels, size_t n, size_t channels) {
    std::atomic<size_t> non_finite{0};
    std::atomic<bool> negative{false}, positive{false};
    parallel_for(n, [&](size_t b, size_t e) {
        const TexelStats s = channels == 4   ? stats_range<4>(texels, channels, b, e)
                             : channels == 3 ? stats_range<3>(texels, channels, b, e)
                                             : stats_range<0>(texels, channels, b, e);
        non_finite += s.non_finite;
        if (s.negative) negative = true;
        if (s.positive) positive = true;
    }, size_t(1) << 16);
    return {non_finite.load(), negative.load(), positive.load()};
}

namespace {

// A texel's value: a float as it is, a byte k as export/images.py makes it (float32 k x 1/255).
inline float texel_value(float x) { return x; }
inline float texel_value(uint8_t k) { return float(k) * float(1.0 / 255.0); }

// What is wrong with texel k, the first one refused: a channel's finite value negative, or one
// the scale (null: none) takes past float's range (NaN and infinite values are kept, as NaN).
template <class T>
std::string texel_refusal(const T* texels, size_t channels, size_t k, const float* scale) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    int a = 0;
    float x = 0.0f;
    for (; a < 3; ++a) {
        x = texel_value(texels[k * channels + a]);
        const float y = scale ? x * scale[a] : x;
        if (std::fabs(x) < inf && !(y >= 0 && y < inf)) break;
    }
    char text[160];
    if (x < 0)
        std::snprintf(text, sizeof text, "pixel value %.9g at %zu (channel %d) is negative", double(x), k, a);
    else
        std::snprintf(text, sizeof text, "pixel value %.9g at %zu (channel %d) times scale %.9g is beyond float's range",
                      double(x), k, a, double(scale[a]));
    return text;
}

template <class T>
std::string build_tables(EnvironmentMap& env, const T* texels, size_t channels, uint32_t width, uint32_t height,
                         const float to_map[9], bool closest, bool srgb, const float* scale) {
    if (width == 0 || height == 0) return "the map has no pixels";
    if (channels < 3) return "texels need 3 channels or more";
    if (size_t(width) * height > (size_t(1) << 28)) return "the map has more than 2^28 pixels";
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            double dot = 0;
            for (int a = 0; a < 3; ++a) dot += double(to_map[3 * r + a]) * to_map[3 * c + a];
            if (!(std::fabs(dot - (r == c ? 1.0 : 0.0)) < 1e-4)) return "to_map is not an orthogonal 3x3 matrix";
        }
    for (int a = 0; scale && a < 3; ++a)
        if (!(scale[a] >= 0 && scale[a] < std::numeric_limits<float>::infinity()))
            return "scale " + std::to_string(scale[a]) + " is negative or not finite";
    env.width = width;
    env.height = height;
    env.closest = closest;
    env.srgb = srgb;
    for (int a = 0; a < 3; ++a) env.scale[a] = srgb && scale ? scale[a] : 1.0f;
    std::copy(to_map, to_map + 9, env.to_map);
    const size_t cells = size_t(width) * height;
    env.texel.resize(cells * 4);
    // The radiance texels (a linear map's RGB x scale, an sRGB map's encoded RGB) and each
    // one's luminance (an sRGB map's: of the decoded texel x scale, as the lookup decodes).
    std::mutex first_lock;
    size_t first_bad = cells;
    std::atomic<bool> steep{false};
    const ByteDecode byte_decode;
    const bool folds = !srgb && scale;
    parallel_for(height, [&](size_t b, size_t e) {
        size_t bad = cells;
        bool steep_rows = false;
        for (size_t k = b * width; k < e * width; ++k) {
            // an image's NaN or infinite channel is kept as NaN: every lookup blending it in
            // reads 0 in that channel (environment.cpp), as Cycles' blend is NaN there and its
            // film drops it; the importance reads it as 0. A finite value negative, or one the
            // scale makes infinite, is refused (selects, no branch per channel)
            constexpr float inf = std::numeric_limits<float>::infinity();
            float t[3];
            bool fault = false;
            for (int a = 0; a < 3; ++a) {
                const float x = texel_value(texels[k * channels + a]);
                const float y = folds ? x * scale[a] : x;
                const bool kept = std::fabs(x) < inf;
                fault |= kept & !(y >= 0 && y < inf);
                t[a] = kept ? y : std::numeric_limits<float>::quiet_NaN();
                env.texel[4 * k + a] = t[a];
            }
            if (fault && bad == cells) bad = k;
            for (int a = 0; a < 3; ++a) {
                if (srgb) t[a] = byte_decode(t[a]) * env.scale[a];
                t[a] = t[a] == t[a] ? t[a] : 0.0f;
            }
            // (a float sum past float's range, e.g. three texels of 3e38, is taken in double,
            // and a luminance still infinite, an sRGB decode past float's, as float's largest:
            // an infinite one made every CDF NaN and every sample's direction NaN)
            float lum = (t[0] + t[1] + t[2]) * (1.0f / 3.0f);
            if (!(lum < inf))
                lum = float(std::min((double(t[0]) + t[1] + t[2]) / 3.0, double(std::numeric_limits<float>::max())));
            if (lum > 0x1p60f)
                steep_rows = true;
            env.texel[4 * k + 3] = lum;
        }
        if (steep_rows) steep = true;
        if (bad < cells) {
            std::lock_guard<std::mutex> hold(first_lock);
            first_bad = std::min(first_bad, bad);
        }
    }, min_rows(width));
    if (first_bad < cells) return texel_refusal(texels, channels, first_bad, folds ? scale : nullptr);
    env.steep = steep.load();
    // Cell weights: their luminance integral, the mean of the corners ('Linear': the cell
    // between texel centres, whose bilinear blend is sampled exactly within it) or the texel
    // ('Closest'), times the mean of sin(theta) over the cell's rows (the last 'Linear' row
    // wraps over the pole: half at the top, half at the bottom).
    std::vector<double> row_sin(height);
    for (uint32_t i = 0; i < height; ++i) {
        if (closest)
            row_sin[i] = sin_integral(double(i) / height, double(i + 1) / height) * height;
        else if (i + 1 < height)
            row_sin[i] = sin_integral((i + 0.5) / height, (i + 1.5) / height) * height;
        else
            row_sin[i] = (sin_integral((i + 0.5) / height, 1.0) + sin_integral(0.0, 0.5 / height)) * height;
    }
    const float* L = env.texel.data() + 3;  // luminance, stride 4
    // The means of row i's cells, in double: their corners' ('Linear': with the next row and
    // column, wrapped) or the texel ('Closest')
    auto cell_means = [&](uint32_t i, double* m) {
        const float* r = L + size_t(i) * width * 4;
        if (closest) {
            for (uint32_t j = 0; j < width; ++j) m[j] = double(r[4 * j]);
            return;
        }
        const float* r1 = L + size_t(i + 1 == height ? 0 : i + 1) * width * 4;
        for (uint32_t j = 0; j < width; ++j) {
            const uint32_t j1 = j + 1 == width ? 0 : j + 1;
            m[j] = (double(r[4 * j]) + r[4 * j1] + r1[4 * j] + r1[4 * j1]) / 4.0;
        }
    };
    env.row_cdf.assign(size_t(height) + 1, 0.0);
    env.col_cdf.resize(size_t(height) * (width + 1));
    env.cell_pdf.resize(cells);
    env.guide_buckets = guide_size(width);
    env.col_guide.resize(size_t(height) * (env.guide_buckets + 1));
    std::vector<double> row_total(height);
    parallel_for(height, [&](size_t b, size_t e) {
        std::vector<double> row(width);
        for (size_t i = b; i < e; ++i) {
            cell_means(uint32_t(i), row.data());
            double acc = 0;
            for (uint32_t j = 0; j < width; ++j) acc += row[j] *= row_sin[i];
            float* c = env.col_cdf.data() + i * (width + 1);
            c[0] = 0.0f;
            double run = 0;
            for (uint32_t j = 0; j < width; ++j) {
                run += row[j];
                c[j + 1] = acc > 0 ? float(run / acc) : float(j + 1) / float(width);
            }
            c[width] = 1.0f;
            build_guide(c, width, env.guide_buckets, env.col_guide.data() + i * (env.guide_buckets + 1));
            row_total[i] = acc;
        }
    }, min_rows(width));
    double total = 0;  // in row order: the same sum whatever the threads
    for (uint32_t i = 0; i < height; ++i) env.row_cdf[i + 1] = total += row_total[i];
    env.total = total;
    if (!(total > 0)) {
        std::fill(env.cell_pdf.begin(), env.cell_pdf.end(), 0.0f);
        return {};
    }
    for (uint32_t i = 0; i <= height; ++i) env.row_cdf[i] /= total;
    env.row_cdf[height] = 1.0;
    env.row_buckets = guide_size(height);
    env.row_guide.assign(size_t(env.row_buckets) + 1, 0u);
    build_guide(env.row_cdf.data(), height, env.row_buckets, env.row_guide.data());
    // pdf over (u, v) = P(cell) w h x (the blend / its mean over the cell)
    const double pdf_scale = double(width) * height / total;
    parallel_for(height, [&](size_t b, size_t e) {
        std::vector<double> means(width);
        for (size_t i = b; i < e; ++i) {
            cell_means(uint32_t(i), means.data());
            for (uint32_t j = 0; j < width; ++j) {
                const double m = means[j];
                env.cell_pdf[i * width + j] = m > 0 ? float(m * row_sin[i] * pdf_scale / (closest ? 1.0 : m)) : 0.0f;
            }
        }
    }, min_rows(width));
    return {};
}

}  // namespace

std::string build_environment_texels(EnvironmentMap& env, const float* texels, size_t channels, uint32_t width,
                                     uint32_t height, const float to_map[9], bool closest, bool srgb,
                                     const float* scale) {
    return build_tables(env, texels, channels, width, height, to_map, closest, srgb, scale);
}

std::string build_environment_bytes(EnvironmentMap& env, const uint8_t* texels, size_t channels, uint32_t width,
                                    uint32_t height, const float to_map[9], bool closest, bool srgb,
                                    const float* scale) {
    return build_tables(env, texels, channels, width, height, to_map, closest, srgb, scale);
}

}  // namespace dacrt
