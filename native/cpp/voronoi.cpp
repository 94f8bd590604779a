// Cycles' Voronoi Texture (see voronoi.h): every operation in Cycles' order, in float32.
#include "voronoi.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "lookup3.h"
#include "parallel.h"
#include "svmmath.h"

namespace dacrt {

namespace {

// Cycles' PCG hashes (util/hash.h hash_pcg3d_i / hash_pcg2d_i: signed, wrapping; done in
// unsigned arithmetic, the same bits; >> on the signed value is arithmetic).
inline int32_t sra16(uint32_t v) { return int32_t(v) >> 16; }

inline void pcg3d(const int32_t k[3], float out[3]) {
    uint32_t x = uint32_t(k[0]) * 1664525u + 1013904223u;
    uint32_t y = uint32_t(k[1]) * 1664525u + 1013904223u;
    uint32_t z = uint32_t(k[2]) * 1664525u + 1013904223u;
    x += y * z;
    y += z * x;
    z += x * y;
    x ^= uint32_t(sra16(x));
    y ^= uint32_t(sra16(y));
    z ^= uint32_t(sra16(z));
    x += y * z;
    y += z * x;
    z += x * y;
    const float s = 1.0f / float(0x7FFFFFFFu);
    out[0] = float(int32_t(x & 0x7FFFFFFFu)) * s;
    out[1] = float(int32_t(y & 0x7FFFFFFFu)) * s;
    out[2] = float(int32_t(z & 0x7FFFFFFFu)) * s;
}

inline void pcg2d(const int32_t k[2], float out[2]) {
    uint32_t x = uint32_t(k[0]) * 1664525u + 1013904223u;
    uint32_t y = uint32_t(k[1]) * 1664525u + 1013904223u;
    x += y * 1664525u;
    y += x * 1664525u;
    x ^= uint32_t(sra16(x));
    y ^= uint32_t(sra16(y));
    x += y * 1664525u;
    y += x * 1664525u;
    const float s = 1.0f / float(0x7FFFFFFFu);
    out[0] = float(int32_t(x & 0x7FFFFFFFu)) * s;
    out[1] = float(int32_t(y & 0x7FFFFFFFu)) * s;
}

// An integer cell the way Cycles' make_int3(floor(x)) converts on the CPU (SSE's truncating
// conversion): beyond int's range, inf and NaN give INT_MIN, its 'integer indefinite' (a Scale
// typed 'inf', 3.4e38, puts every point there: Cycles' distance 0.6309, 0 had given 0.3521).
inline int32_t cell_of(float f) {
    return f >= -2147483648.0f && f < 2147483648.0f ? int32_t(f) : INT32_MIN;
}


// --- the whole node (svm_node_tex_voronoi) -------------------------------------------------

inline void pcg4d(const int32_t k[4], float out[4]) {
    uint32_t v[4];
    for (int a = 0; a < 4; ++a) v[a] = uint32_t(k[a]) * 1664525u + 1013904223u;
    v[0] += v[1] * v[3];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    v[3] += v[1] * v[2];
    for (int a = 0; a < 4; ++a) v[a] ^= uint32_t(sra16(v[a]));
    v[0] += v[1] * v[3];
    v[1] += v[2] * v[0];
    v[2] += v[0] * v[1];
    v[3] += v[1] * v[2];
    const float s = 1.0f / float(0x7FFFFFFFu);
    for (int a = 0; a < 4; ++a) out[a] = float(int32_t(v[a] & 0x7FFFFFFFu)) * s;
}

// 1D cells hash their float position with Bob Jenkins' lookup3 (util/hash.h hash_float_to_float,
// hash_float_to_float3).
using lookup3::float_bits;

inline float hash_float_to_float(float k) {
    uint32_t a = 0xdeadbeefu + (1u << 2) + 13u, b = a, c = a;
    a += float_bits(k);
    return float(lookup3::final_mix(a, b, c)) / float(0xFFFFFFFFu);
}

inline float hash_float2_to_float(float kx, float ky) {
    uint32_t a = 0xdeadbeefu + (2u << 2) + 13u, b = a, c = a;
    b += float_bits(ky);
    a += float_bits(kx);
    return float(lookup3::final_mix(a, b, c)) / float(0xFFFFFFFFu);
}

struct Settings {
    float randomness, smoothness, exponent;
    int metric;
};

// A cell's jitter (hash_int{2,3,4}_to_float{2,3,4}, 1D hash_float_to_float of the cell's float)
// and colour (hash_int2_to_float3 = hash_int3_to_float3 with z 0, hash_int4_to_float3 = the
// first three of the 4D hash).
template <int D>
inline void cell_hash(const int32_t cell[4], const float cellf[4], const int off[4], float h[4]) {
    if (D == 1) {
        h[0] = hash_float_to_float(cellf[0] + float(off[0]));
        return;
    }
    int32_t c[4];
    for (int a = 0; a < D; ++a) c[a] = int32_t(uint32_t(cell[a]) + uint32_t(off[a]));
    if (D == 2) pcg2d(c, h); else if (D == 3) pcg3d(c, h); else pcg4d(c, h);
}

template <int D>
inline void cell_color(const int32_t cell[4], const float cellf[4], const int off[4], float col[3]) {
    if (D == 1) {
        const float k = cellf[0] + float(off[0]);
        col[0] = hash_float_to_float(k);
        col[1] = hash_float2_to_float(k, 1.0f);
        col[2] = hash_float2_to_float(k, 2.0f);
        return;
    }
    int32_t c[4] = {0, 0, 0, 0};
    for (int a = 0; a < D; ++a) c[a] = int32_t(uint32_t(cell[a]) + uint32_t(off[a]));
    if (D == 4) {
        float h[4];
        pcg4d(c, h);
        for (int a = 0; a < 3; ++a) col[a] = h[a];
    } else {
        pcg3d(c, col);
    }
}

// reduce_add of D components: float4's SSE sum pairs (x + y) + (z + w).
template <int D>
inline float sum(const float v[4]) {
    if (D == 4) return (v[0] + v[1]) + (v[2] + v[3]);
    float s = v[0];
    for (int c = 1; c < D; ++c) s = s + v[c];
    return s;
}

template <int D>
inline float dot(const float a[4], const float b[4]) {
    float v[4];
    for (int c = 0; c < D; ++c) v[c] = a[c] * b[c];
    return sum<D>(v);
}

// voronoi_distance (pass bound: voronoi_distance_bound, which orders points the same).
template <int D>
inline float metric_distance(const float a[4], const float b[4], const Settings& s, bool bound) {
    float d[4];
    for (int c = 0; c < D; ++c) d[c] = a[c] - b[c];
    if (D == 1) return std::fabs(b[0] - a[0]);
    if (s.metric == VORONOI_EUCLIDEAN) {
        const float q = dot<D>(d, d);
        return bound ? q : std::sqrt(q);
    }
    for (int c = 0; c < D; ++c) d[c] = std::fabs(d[c]);
    if (s.metric == VORONOI_MANHATTAN) return sum<D>(d);
    if (s.metric == VORONOI_CHEBYCHEV) {
        float m = d[0];
        for (int c = 1; c < D; ++c) m = std::max(m, d[c]);
        return m;
    }
    if (s.metric == VORONOI_MINKOWSKI) {
        for (int c = 0; c < D; ++c) d[c] = std::pow(d[c], s.exponent);
        const float q = sum<D>(d);
        return bound ? q : std::pow(q, 1.0f / s.exponent);
    }
    return 0.0f;
}

// Euclidean distance (distance(), which N-Sphere Radius reads whatever the metric).
template <int D>
inline float euclid(const float a[4], const float b[4]) {
    if (D == 1) return std::fabs(a[0] - b[0]);
    float d[4];
    for (int c = 0; c < D; ++c) d[c] = a[c] - b[c];
    return std::sqrt(dot<D>(d, d));
}

inline float mixf(float a, float b, float t) { return a + t * (b - a); }

inline float smoothstep(float e0, float e1, float x) {
    if (x < e0) return 0.0f;
    if (x >= e1) return 1.0f;
    const float t = (x - e0) / (e1 - e0);
    return (3.0f - 2.0f * t) * (t * t);
}

struct Octave {
    float distance = 0.0f;
    float color[3] = {0, 0, 0};
    float position[4] = {0, 0, 0, 0};       // voronoi_position: 1D's coordinate in w
};

// Offsets (i, j, k, u) of the (2r + 1)^D cells, i fastest, as Cycles' nested loops.
template <int D>
inline void offset_of(int idx, int r, int off[4]) {
    const int w = 2 * r + 1;
    for (int a = 0; a < 4; ++a) {
        off[a] = a < D ? idx % w - r : 0;
        idx /= w;
    }
}

template <int D>
constexpr int cells(int r) {
    int n = 1;
    for (int a = 0; a < D; ++a) n *= 2 * r + 1;
    return n;
}

template <int D>
struct Cell {
    float cellf[4] = {0, 0, 0, 0}, local[4] = {0, 0, 0, 0};
    int32_t cell[4] = {0, 0, 0, 0};
    explicit Cell(const float* coord) {
        for (int c = 0; c < D; ++c) {
            cellf[c] = std::floor(coord[c]);
            local[c] = coord[c] - cellf[c];
            cell[c] = cell_of(cellf[c]);
        }
    }
    // the jittered point of the cell at offset off, relative to this cell
    void point(const int off[4], float randomness, float out[4]) const {
        float h[4];
        cell_hash<D>(cell, cellf, off, h);
        for (int c = 0; c < D; ++c) out[c] = float(off[c]) + h[c] * randomness;
    }
};

template <int D>
Octave voronoi_f1_octave(const float* coord, const Settings& s) {
    const Cell<D> C(coord);
    float best = FLT_MAX, target[4] = {0, 0, 0, 0};
    int target_off[4] = {0, 0, 0, 0};
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        float point[4];
        C.point(off, s.randomness, point);
        const float d = metric_distance<D>(point, C.local, s, true);
        if (d < best) {
            best = d;
            for (int a = 0; a < 4; ++a) target_off[a] = off[a];
            for (int a = 0; a < D; ++a) target[a] = point[a];
        }
    }
    Octave o;
    o.distance = metric_distance<D>(target, C.local, s, false);
    cell_color<D>(C.cell, C.cellf, target_off, o.color);
    float pos[4];
    for (int a = 0; a < D; ++a) pos[a] = target[a] + C.cellf[a];
    for (int a = 0; a < D; ++a) o.position[D == 1 ? 3 : a] = pos[a];
    return o;
}

template <int D>
Octave voronoi_smooth_f1_octave(const float* coord, const Settings& s) {
    const Cell<D> C(coord);
    float sd = 0.0f, scol[3] = {0, 0, 0}, spos[4] = {0, 0, 0, 0}, h = -1.0f;
    for (int idx = 0; idx < cells<D>(2); ++idx) {
        int off[4];
        offset_of<D>(idx, 2, off);
        float point[4];
        C.point(off, s.randomness, point);
        const float d = metric_distance<D>(point, C.local, s, false);
        h = h == -1.0f ? 1.0f : smoothstep(0.0f, 1.0f, 0.5f + 0.5f * (sd - d) / s.smoothness);
        float correction = s.smoothness * h * (1.0f - h);
        sd = mixf(sd, d, h) - correction;
        correction /= 1.0f + 3.0f * s.smoothness;
        float col[3];
        cell_color<D>(C.cell, C.cellf, off, col);
        for (int a = 0; a < 3; ++a) scol[a] = mixf(scol[a], col[a], h) - correction;
        for (int a = 0; a < D; ++a) spos[a] = mixf(spos[a], point[a], h) - correction;
    }
    Octave o;
    o.distance = sd;
    for (int a = 0; a < 3; ++a) o.color[a] = scol[a];
    for (int a = 0; a < D; ++a) o.position[D == 1 ? 3 : a] = C.cellf[a] + spos[a];
    return o;
}

template <int D>
Octave voronoi_f2_octave(const float* coord, const Settings& s) {
    const Cell<D> C(coord);
    float d1 = FLT_MAX, d2 = FLT_MAX, p1[4] = {0, 0, 0, 0}, p2[4] = {0, 0, 0, 0};
    int o1[4] = {0, 0, 0, 0}, o2[4] = {0, 0, 0, 0};
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        float point[4];
        C.point(off, s.randomness, point);
        const float d = metric_distance<D>(point, C.local, s, false);
        if (d < d1) {
            d2 = d1;
            d1 = d;
            std::memcpy(o2, o1, sizeof o1);
            std::memcpy(o1, off, sizeof o1);
            std::memcpy(p2, p1, sizeof p1);
            std::memcpy(p1, point, sizeof p1);
        } else if (d < d2) {
            d2 = d;
            std::memcpy(o2, off, sizeof o2);
            std::memcpy(p2, point, sizeof p2);
        }
    }
    Octave o;
    o.distance = d2;
    cell_color<D>(C.cell, C.cellf, o2, o.color);
    for (int a = 0; a < D; ++a) o.position[D == 1 ? 3 : a] = p2[a] + C.cellf[a];
    return o;
}

template <int D>
float voronoi_distance_to_edge(const float* coord, float randomness) {
    const Cell<D> C(coord);
    if (D == 1) {
        const int mid[4] = {0, 0, 0, 0}, left[4] = {-1, 0, 0, 0}, right[4] = {1, 0, 0, 0};
        float h[4];
        cell_hash<1>(C.cell, C.cellf, mid, h);
        const float m = h[0] * randomness;
        // (Cycles: hash_float_to_float(cellPosition - 1.0f), the same float as cellPosition + -1)
        cell_hash<1>(C.cell, C.cellf, left, h);
        const float l = -1.0f + h[0] * randomness;
        cell_hash<1>(C.cell, C.cellf, right, h);
        const float r = 1.0f + h[0] * randomness;
        const float dl = std::fabs((m + l) / 2.0f - C.local[0]);
        const float dr = std::fabs((m + r) / 2.0f - C.local[0]);
        return std::min(dl, dr);
    }
    float closest[4] = {0, 0, 0, 0}, best = FLT_MAX;
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        float v[4];
        C.point(off, randomness, v);
        for (int a = 0; a < D; ++a) v[a] = v[a] - C.local[a];
        const float d = dot<D>(v, v);
        if (d < best) {
            best = d;
            std::memcpy(closest, v, sizeof v);
        }
    }
    best = FLT_MAX;
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        float v[4], perp[4] = {0, 0, 0, 0}, mid[4] = {0, 0, 0, 0};
        C.point(off, randomness, v);
        for (int a = 0; a < D; ++a) v[a] = v[a] - C.local[a];
        for (int a = 0; a < D; ++a) perp[a] = v[a] - closest[a];
        const float q = dot<D>(perp, perp);
        if (q > 0.0001f) {
            const float len = std::sqrt(q);
            for (int a = 0; a < D; ++a) {
                mid[a] = (closest[a] + v[a]) / 2.0f;
                perp[a] = perp[a] / len;
            }
            best = std::min(best, dot<D>(mid, perp));
        }
    }
    return best;
}

template <int D>
float voronoi_n_sphere_radius(const float* coord, float randomness) {
    const Cell<D> C(coord);
    float closest[4] = {0, 0, 0, 0}, best = FLT_MAX;
    int closest_off[4] = {0, 0, 0, 0};
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        float point[4];
        C.point(off, randomness, point);
        const float d = euclid<D>(point, C.local);
        if (d < best) {
            best = d;
            std::memcpy(closest, point, sizeof point);
            std::memcpy(closest_off, off, sizeof off);
        }
    }
    best = FLT_MAX;
    float other[4] = {0, 0, 0, 0};
    for (int idx = 0; idx < cells<D>(1); ++idx) {
        int off[4];
        offset_of<D>(idx, 1, off);
        bool centre = true;
        for (int a = 0; a < D; ++a) centre = centre && off[a] == 0;
        if (centre) continue;
        for (int a = 0; a < D; ++a) off[a] += closest_off[a];
        float point[4];
        C.point(off, randomness, point);
        const float d = euclid<D>(closest, point);
        if (d < best) {
            best = d;
            std::memcpy(other, point, sizeof point);
        }
    }
    return euclid<D>(other, closest) / 2.0f;
}

struct Fractal {
    float detail, roughness, lacunarity, scale, max_distance;
    int feature;
    bool normalize;
};

// fractal_voronoi_x_fx: octaves of F1, Smooth F1 or F2 summed (distance, colour) and lerped
// (position) as Cycles' fBM, Detail's fraction mixing in the last.
template <int D>
Octave fractal_voronoi_x_fx(const float* coord, const Settings& s, const Fractal& f) {
    float amplitude = 1.0f, max_amplitude = 0.0f, scale = 1.0f;
    Octave out;
    const bool zero_input = f.detail == 0.0f || f.roughness == 0.0f;
    for (int i = 0; i <= std::ceil(f.detail); ++i) {
        float c[4];
        for (int a = 0; a < D; ++a) c[a] = coord[a] * scale;
        const Octave o = f.feature == VORONOI_F2 ? voronoi_f2_octave<D>(c, s)
                         : (f.feature == VORONOI_SMOOTH_F1 && s.smoothness != 0.0f) ? voronoi_smooth_f1_octave<D>(c, s)
                                                                                     : voronoi_f1_octave<D>(c, s);
        if (zero_input) {
            max_amplitude = 1.0f;
            out = o;
            break;
        }
        const float inv = 1.0f / scale;
        if (i <= f.detail) {
            max_amplitude += amplitude;
            out.distance += o.distance * amplitude;
            for (int a = 0; a < 3; ++a) out.color[a] += o.color[a] * amplitude;
            for (int a = 0; a < 4; ++a) out.position[a] = mixf(out.position[a], o.position[a] * inv, amplitude);
            scale *= f.lacunarity;
            amplitude *= f.roughness;
        } else {
            const float remainder = f.detail - std::floor(f.detail);
            if (remainder != 0.0f) {
                max_amplitude = mixf(max_amplitude, max_amplitude + amplitude, remainder);
                out.distance = mixf(out.distance, out.distance + o.distance * amplitude, remainder);
                for (int a = 0; a < 3; ++a)
                    out.color[a] = mixf(out.color[a], out.color[a] + o.color[a] * amplitude, remainder);
                for (int a = 0; a < 4; ++a)
                    out.position[a] = mixf(out.position[a], mixf(out.position[a], o.position[a] * inv, amplitude),
                                           remainder);
            }
        }
    }
    if (f.normalize) {
        out.distance /= max_amplitude * f.max_distance;
        const float inv = 1.0f / max_amplitude;
        for (int a = 0; a < 3; ++a) out.color[a] = out.color[a] * inv;
    }
    const float inv = f.scale != 0.0f ? 1.0f / f.scale : 0.0f;
    for (int a = 0; a < 4; ++a) out.position[a] = f.scale != 0.0f ? out.position[a] * inv : 0.0f;
    return out;
}

template <int D>
float fractal_voronoi_distance_to_edge(const float* coord, float randomness, const Fractal& f) {
    float amplitude = 1.0f, max_amplitude = f.max_distance, scale = 1.0f, distance = 8.0f;
    const bool zero_input = f.detail == 0.0f || f.roughness == 0.0f;
    for (int i = 0; i <= std::ceil(f.detail); ++i) {
        float c[4];
        for (int a = 0; a < D; ++a) c[a] = coord[a] * scale;
        const float od = voronoi_distance_to_edge<D>(c, randomness);
        if (zero_input) {
            distance = od;
            break;
        }
        if (i <= f.detail) {
            max_amplitude = mixf(max_amplitude, f.max_distance / scale, amplitude);
            distance = mixf(distance, std::min(distance, od / scale), amplitude);
            scale *= f.lacunarity;
            amplitude *= f.roughness;
        } else {
            const float remainder = f.detail - std::floor(f.detail);
            if (remainder != 0.0f) {
                const float lerp_amplitude = mixf(max_amplitude, f.max_distance / scale, amplitude);
                max_amplitude = mixf(max_amplitude, lerp_amplitude, remainder);
                const float lerp_distance = mixf(distance, std::min(distance, od / scale), amplitude);
                distance = mixf(distance, std::min(distance, lerp_distance), remainder);
            }
        }
    }
    if (f.normalize) distance /= max_amplitude;
    return distance;
}

using svm::clamp;

template <int D>
void texture_point(const float* p, const VoronoiTextureParams& k, size_t i, float* dist, float* col, float* pos,
                   float* radius) {
    auto at = [i](const float* a, size_t n) { return a[n == 1 ? 0 : i]; };
    const float scale = at(k.scale, k.scale_n);
    Settings s;
    s.randomness = clamp(at(k.randomness, k.randomness_n), 0.0f, 1.0f);
    s.smoothness = clamp(at(k.smoothness, k.smoothness_n) / 2.0f, 0.0f, 0.5f);
    s.exponent = at(k.exponent, k.exponent_n);
    s.metric = k.metric;
    Fractal f;
    f.detail = clamp(at(k.detail, k.detail_n), 0.0f, 15.0f);
    f.roughness = clamp(at(k.roughness, k.roughness_n), 0.0f, 1.0f);
    f.lacunarity = at(k.lacunarity, k.lacunarity_n);
    f.scale = scale;
    f.feature = k.feature;
    f.normalize = k.normalize;
    float coord[4] = {0, 0, 0, 0};
    for (int a = 0; a < D; ++a) coord[a] = p[a] * scale;
    *dist = 0.0f;
    *radius = 0.0f;
    for (int a = 0; a < 3; ++a) col[a] = 0.0f;
    for (int a = 0; a < 4; ++a) pos[a] = 0.0f;
    if (k.feature == VORONOI_DISTANCE_TO_EDGE) {
        f.max_distance = 0.5f + 0.5f * s.randomness;
        *dist = fractal_voronoi_distance_to_edge<D>(coord, s.randomness, f);
        return;
    }
    if (k.feature == VORONOI_N_SPHERE_RADIUS) {
        *radius = voronoi_n_sphere_radius<D>(coord, s.randomness);
        return;
    }
    const float factor = k.feature == VORONOI_F2 ? 2.0f : 1.0f;
    if (D == 1) {
        f.max_distance = (0.5f + 0.5f * s.randomness) * factor;
    } else {
        const float zero[4] = {0, 0, 0, 0};
        float h[4];
        for (int a = 0; a < 4; ++a) h[a] = 0.5f + 0.5f * s.randomness;
        f.max_distance = metric_distance<D>(zero, h, s, false) * factor;
    }
    const Octave o = fractal_voronoi_x_fx<D>(coord, s, f);
    *dist = o.distance;
    for (int a = 0; a < 3; ++a) col[a] = o.color[a];
    for (int a = 0; a < 4; ++a) pos[a] = o.position[a];
}

}  // namespace

void voronoi_texture(const float* p, size_t n, int dims, const VoronoiTextureParams& params, float* distance,
                     float* color, float* position, float* radius) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float* pi = p + size_t(dims) * i;
            float* c = color + 3 * i;
            float* q = position + 4 * i;
            switch (dims) {
                case 1: texture_point<1>(pi, params, i, distance + i, c, q, radius + i); break;
                case 2: texture_point<2>(pi, params, i, distance + i, c, q, radius + i); break;
                case 3: texture_point<3>(pi, params, i, distance + i, c, q, radius + i); break;
                default: texture_point<4>(pi, params, i, distance + i, c, q, radius + i); break;
            }
        }
    }, size_t(1) << 10);
}

}  // namespace dacrt
