// Analytic lamps (point, spot, distant, area, uniform background) as plain float32 records, and
// their per-ray arithmetic: a light sample toward a shading point, a ray meeting a finite lamp,
// a ray that left the scene seeing a lamp at infinity. lamps.cpp runs these over ray batches.
//
// The formulas and their float32 operation order are those of the readable Python definitions
// (the renderer's addon/lights/{point,sun,area,background}.py and the warps of addon/sampling.py,
// which say why each formula is what it is); tests/integrator/test_native_lamps.py compares the
// two. Agreement is to rounding (libm vs numpy sin/cos, summation order), not bit for bit.
//
// Record layout: LAMP_RECORD_WIDTH float32 per lamp, exactly the fields of LampRecord in order
// (a row of a (R, W) float32 array; the Python side builds them with Lamp.record()). Kind and
// shape are small integers stored as floats. Unused fields are 0.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include "ies.h"
#include "lighttree.h"
#include "missflags.h"
#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#endif

namespace dacrt {

enum LampKind : int { LAMP_POINT = 0, LAMP_SPOT = 1, LAMP_SUN = 2, LAMP_AREA = 3, LAMP_BACKGROUND = 4, LAMP_NUM_KINDS = 5 };
enum PointShape : int { POINT_DELTA = 0, POINT_SPHERE = 1, POINT_DISK = 2 };  // point and spot
enum SunShape : int { SUN_DELTA = 0, SUN_CONE = 1 };
// square = rectangle, disk = ellipse; a parallelogram is a rectangle under a sheared transform,
// sampled by area (the spherical-rectangle warp needs right angles)
enum AreaShape : int { AREA_RECT = 0, AREA_ELLIPSE = 1, AREA_PARALLELOGRAM = 2 };

struct LampRecord {
    float kind;             //  0 LampKind
    float shape;            //  1 PointShape / SunShape / AreaShape; 0 for the background
    float emit[3];          //  2 intensity (delta point/spot), irradiance (delta sun), else radiance
    float pos[3];           //  5 centre (point, spot, area) or unit direction toward the sun
    float radius;           //  8 point/spot
    float cos_half;         //  9 spot: cos(size/2); sun: cos(angle/2)
    float inv_smooth;       // 10 spot: 1 / ((1 - cos(size/2)) blend); 0 = hard edge (blend 0)
    float omc;              // 11 sun: 1 - cos(angle/2)
    float pdf;              // 12 solid-angle pdf of a sun cone or the background
    float area;             // 13 area light: world area
    float axis_x[3];        // 14 area light: world X extent (object X axis x size)
    float axis_y[3];        // 17 world Y extent
    float inv_x[3];         // 20 axis_x / |axis_x|^2: local coordinate = dot(q - centre, inv_x)
    float inv_y[3];         // 23
    float normal[3];        // 26 unit normal of the emitting side (object -Z)
    float tan_half_spread;  // 29 area spread: tan(spread/2)
    float spread_norm;      // 30 spread profile normalisation; 0 = no spread (spread = pi)
    float inv_m3[9];        // 31 spot: inverse of the object's 3x3 transform, row-major
    float ies;              // 40 point/spot/area/sun cone: IES profile id (ies.h), 0 = none
    float ies_m3[9];        // 41 its world -> object transform of directions (as a normal), row-major
    float falloff_power;    // 50 point/spot/area: a Light Falloff's output, 0 Quadratic, 1 Linear, 2 Constant
    float falloff_smooth;   // 51 its Smooth (0: none)
};
constexpr size_t LAMP_RECORD_WIDTH = 52;
static_assert(sizeof(LampRecord) == LAMP_RECORD_WIDTH * sizeof(float), "LampRecord must be packed floats");

// Whether a lamp is at infinity (a sun or the background): rays that missed everything see it.
inline bool at_infinity(const LampRecord& lamp) {
    const int kind = int(lamp.kind);
    return kind == LAMP_SUN || kind == LAMP_BACKGROUND;
}

// Empty if the record can be used, else what is wrong (kind/shape codes, non-finite fields).
std::string lamp_record_error(const LampRecord& r);

// Light samples: for i with 0 <= entry[i] < R, a sample of lamp rec[entry[i]] seen from P
// (3 rows, stride n) with uniforms u1, u2: unit direction wi, shadow-ray length dist (inf at
// infinity), value = radiance / pdf (RGB; 0 where the lamp cannot reach P) and the solid-angle
// pdf (inf: delta lamp). Other samples are left untouched (another sampler fills them).
void lamp_sample(const LampRecord* rec, size_t R, const int32_t* entry, const float* P, const float* u1,
                 const float* u2, size_t n, float* wi, float* dist, float* value, float* pdf);

// What rays (O, D: 3 rows, stride n) see of the lamps rec[lamps[0..nl)]: a finite lamp where
// it is met at t < t_surf[i * t_step], a lamp at infinity where miss(i) (missflags.h: flags or
// the hit records; read for those alone, it may be neither when no lamp is at infinity). L[:, pid[i]] (stride N) +=
// thr x radiance x w, lamp by lamp in list order, with thr null = 1 and w = 1 when lamp_prob
// is null (camera rays), else the power heuristic 1 / (1 + (lamp_prob[j] pdf_l / pdf_bsdf)^2).
// With a light tree, a record j with lamp_key[j] >= 0 is that member of it: its selection
// probability is lamp_prob[j] x the tree's pdf at the ray's origin with normal (3 rows, stride
// n; null: none), the normal the ray's vertex sampled its light with, and with light linking
// receivers (n; null: none) the receiver mask of that vertex's object (LightTree::pdf).
// pid must be distinct (threads split by ray).
void lamp_gather(const LampRecord* rec, const int32_t* lamps, size_t nl, const float* lamp_prob, const float* O,
                 const float* D, const float* t_surf, Missed miss, const float* thr, const float* pdf_bsdf,
                 const int64_t* pid, size_t n, float* L, size_t N, float clamp, const LightTree* tree = nullptr,
                 const int32_t* lamp_key = nullptr, const float* normal = nullptr,
                 const uint64_t* receivers = nullptr, size_t t_step = 1);

namespace lampmath {

constexpr float PI = float(3.14159265358979323846);
constexpr float PI_2 = float(3.14159265358979323846 / 2.0);
constexpr float PI_4 = float(3.14159265358979323846 / 4.0);
constexpr float TWO_PI = float(2.0 * 3.14159265358979323846);
constexpr float FOUR_OVER_PI = float(4.0 / 3.14159265358979323846);
constexpr float INV_2PI = float(1.0 / (2.0 * 3.14159265358979323846));
constexpr float INF = std::numeric_limits<float>::infinity();

inline float dot3(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// v /= |v| (zero stays zero); returns |v|.
inline float normalize(float v[3]) {
    const float len = std::sqrt(dot3(v, v));
    const float inv = len > 0 ? 1.0f / len : 0.0f;
    for (int a = 0; a < 3; ++a) v[a] *= inv;
    return len;
}

// Shirley-Chiu concentric map of the unit square to the unit disk.
inline void concentric_disk(float u1, float u2, float& x, float& y) {
    const float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f;
    const bool use_a = std::fabs(a) > std::fabs(b);
    const float r = use_a ? a : b, num = use_a ? b : a;
    const float q = r == 0 ? 0.0f : num / r;
    const float phi = use_a ? PI_4 * q : PI_2 - PI_4 * q;
    x = r * std::cos(phi);
    y = r * std::sin(phi);
}

// std::max(0.0f, x) and std::min(1.0f, x) (constant first) map NaN to the constant, as
// fmax/fmin do, but inline and vectorise where fmaxf is a libm call.
inline void uniform_sphere(float u1, float u2, float out[3]) {
    const float z = 1.0f - 2.0f * u1;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = TWO_PI * u2;
    out[0] = r * std::cos(phi);
    out[1] = r * std::sin(phi);
    out[2] = z;
}

// Uniform direction in the cone around +Z with 1 - cos(half angle) = omc_max; returns cos(theta).
inline float uniform_cone(float u1, float u2, float omc_max, float out[3]) {
    const float omc = u1 * omc_max;
    const float cos_t = 1.0f - omc;
    const float sin_t = std::sqrt(std::max(0.0f, omc * (2.0f - omc)));
    const float phi = TWO_PI * u2;
    out[0] = sin_t * std::cos(phi);
    out[1] = sin_t * std::sin(phi);
    out[2] = cos_t;
    return cos_t;
}

// max(c, x) and min(c, x) as std::max(c, x) and std::min(c, x) (NaN x gives c), and c ? a : b
// with both computed, but always maxss/minss/masks on x86: in this scalar code GCC turns the
// std:: forms into branches (to skip a division, say), which rays or points whose spread box is
// clipped, empty or not at random mispredict (lamp_gather, lamp_sample up to 1.5x slower).
#if defined(__SSE2__) || defined(_M_X64)
inline float max_sel(float c, float x) { return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(x), _mm_set_ss(c))); }
inline float min_sel(float c, float x) { return _mm_cvtss_f32(_mm_min_ss(_mm_set_ss(x), _mm_set_ss(c))); }
inline float select_f(bool c, float a, float b) {
    const __m128 m = _mm_castsi128_ps(_mm_set1_epi32(-int(c)));
    return _mm_cvtss_f32(_mm_or_ps(_mm_and_ps(m, _mm_set_ss(a)), _mm_andnot_ps(m, _mm_set_ss(b))));
}
#else
inline float max_sel(float c, float x) { return std::max(c, x); }
inline float min_sel(float c, float x) { return std::min(c, x); }
inline float select_f(bool c, float a, float b) { return c ? a : b; }
#endif

inline float one_minus_cos_from_sin2(float s) { return s / (1.0f + std::sqrt(std::max(0.0f, 1.0f - s))); }

// Branchless tangent frame of a unit normal (Duff et al. 2017).
inline void orthonormal_basis(const float n[3], float t[3], float b[3]) {
    const float sign = n[2] >= 0 ? 1.0f : -1.0f;
    const float a = -1.0f / (sign + n[2]);
    const float bb = n[0] * n[1] * a;
    const float sxa = sign * n[0] * a;
    t[0] = 1.0f + sxa * n[0];
    t[1] = sign * bb;
    t[2] = -sign * n[0];
    b[0] = bb;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

inline void to_world(const float local[3], const float n[3], float out[3]) {
    float t[3], b[3];
    orthonormal_basis(n, t, b);
    for (int a = 0; a < 3; ++a) {
        float v = t[a] * local[0];
        v += b[a] * local[1];
        out[a] = v + n[a] * local[2];
    }
}

// Spot cone factor for a unit light->point direction: smoothstep (or a hard edge) of the
// forward component of that direction in the light's own (unscaled) frame.
inline float spot_attenuation(const LampRecord& L, const float from_light[3]) {
    const float* m = L.inv_m3;
    float local[3];
    for (int r = 0; r < 3; ++r) local[r] = m[3 * r] * from_light[0] + m[3 * r + 1] * from_light[1] + m[3 * r + 2] * from_light[2];
    const float length = std::sqrt(dot3(local, local));
    const float z = length > 0 ? -local[2] / length : -1.0f;
    if (L.inv_smooth == 0) return z > L.cos_half ? 1.0f : 0.0f;
    float f = (z - L.cos_half) * L.inv_smooth;
    f = f < 0 ? 0.0f : (f > 1 ? 1.0f : f);  // NaN stays NaN, as np.clip
    return f * f * (3.0f - 2.0f * f);
}

// Area light spread profile at emission cosine cos_l = -w . normal (1 without spread), w the
// unit direction between the point and the lamp. tan of the emission angle as |w x normal| /
// cos_l: 1 - cos^2 in float32 loses the small angles a narrow spread (< ~0.2 degrees) is made
// of (a 0.001-radian spread came out 1.9x too bright).
inline float area_spread(const LampRecord& L, float cos_l, const float w[3]) {
    if (L.spread_norm == 0) return 1.0f;  // per lamp: predicted
    const float* n = L.normal;
    const float cx = w[1] * n[2] - w[2] * n[1], cy = w[2] * n[0] - w[0] * n[2], cz = w[0] * n[1] - w[1] * n[0];
    const float sin_t = std::sqrt(cx * cx + cy * cy + cz * cz);
    // behind the lamp (cos_l <= 0, or NaN): tan_t = inf and f = 0 without a branch on which
    // side a ray is (no pattern to predict)
    const float tan_t = select_f(cos_l > 0, sin_t / cos_l, INF);
    return max_sel(0.0f, L.tan_half_spread - tan_t) * L.spread_norm;
}

// Area spread (Cycles' area_light_spread_clamp_light): the profile is 0 beyond the disk of
// radius h tan(spread/2) about the foot of a point X at height h on the emitting side, so beyond
// the square around it. The part of the local square [-0.5, 0.5]^2 within it, its widths (0 if
// empty), their product (its share of the bounding rectangle) and whether it is all of it
// (AreaLight._spread_box). Only for lamps with spread.
struct AreaBox {
    float lo_x, hi_x, lo_y, hi_y, w_x, w_y, frac;
    bool full;
};

inline AreaBox area_spread_box(const LampRecord& L, const float X[3]) {
    AreaBox b;
    const float rel[3] = {X[0] - L.pos[0], X[1] - L.pos[1], X[2] - L.pos[2]};
    const float h = dot3(rel, L.normal);
    const float fx = dot3(rel, L.inv_x), fy = dot3(rel, L.inv_y);
    const float r = h * L.tan_half_spread;
    const float rx = r * std::sqrt(dot3(L.inv_x, L.inv_x)), ry = r * std::sqrt(dot3(L.inv_y, L.inv_y));
    const float x0 = fx - rx, x1 = fx + rx, y0 = fy - ry, y1 = fy + ry;
    // whether the box is clipped varies from ray to ray: selects and flags, no branches
    b.lo_x = max_sel(-0.5f, x0);
    b.hi_x = min_sel(0.5f, x1);
    b.lo_y = max_sel(-0.5f, y0);
    b.hi_y = min_sel(0.5f, y1);
    b.w_x = max_sel(0.0f, b.hi_x - b.lo_x);
    b.w_y = max_sel(0.0f, b.hi_y - b.lo_y);
    b.frac = b.w_x * b.w_y;
    b.full = (x0 <= -0.5f) & (x1 >= 0.5f) & (y0 <= -0.5f) & (y1 >= 0.5f);
    return b;
}

// The area the box's share refers to: the lamp's; for an ellipse its bounding rectangle's where
// the box is clamped (sampled uniformly there), its own where not (the concentric map).
inline float area_box_area(const LampRecord& L, int shape, bool full) {
    return (shape == AREA_ELLIPSE) & !full ? L.area * FOUR_OVER_PI : L.area;
}


// Rectangles are sampled by solid angle (Cycles' area_light_rect_sample, after Urena et al. 2013,
// "An Area-Preserving Parametrization for Spherical Rectangles"): pdf = 1 / S, S the solid angle
// of the rectangle (or of the part of it a spread lets reach P) seen from P, so a large lamp close
// to a surface no longer costs the variance of t^2 / cos_l across it. The lamp's unit axes ex, ey
// and its normal n frame P: the rectangle is [x0, x1] x [y0, y1] at depth h below P (world
// lengths, relative to P's foot). S is the area of the spherical quadrilateral: the sum of its
// inner angles g_i minus 2 pi. Cycles' acos(-n_i . n_j) of the planes' normals loses up to 2e-3
// of S near grazing (acos near +-1), and g0 + g1 + g2 + g3 - 2 pi cancels far away; here the
// d_i = g_i - pi/2 come from exact sines and cosines, summed as arguments of complex products,
// so S = sum d_i keeps ~3e-7 of itself above the lamp at any distance, and the warp works with
// phi = au - pi (Cycles' au near pi) from the same sums. Where float32 still cannot (measured
// with a float64 twin on 2 x 3000 random lamps and points: a 256^2 grid of warped samples'
// irradiance), the lamp is sampled by area instead: below SA_MIN_SOLID_ANGLE, or where the lamp
// is seen under less than ~3 degrees of elevation (tan < SA_MIN_TAN_ELEVATION; a sliver near
// P's horizon, where the warp's 1 - cu^2 and 1 - hv^2 cancel). Within both, the warped estimate
// of irradiance was within 7e-5 of S's; outside, area sampling loses little: a small or
// far-off-axis lamp's t^2 / cos_l hardly varies. sample_lamp and hit_area decide at the same
// point with the same float32 operations, so MIS sees one pdf.
struct SphRect {
    float x0, x1, y0, y1, h;  // the rectangle relative to P (world lengths), h > 0 above it
    float b0, b1, d23, S;     // n0.z, n2.z, d2 + d3, solid angle
    float lx, ly;             // world lengths of the lamp's axes
    bool use;                 // sampled by solid angle at this P (else by area)
};

constexpr float SA_MIN_SOLID_ANGLE = 1e-3f;
constexpr float SA_MIN_TAN_ELEVATION = 0.05f;
// A lamp that looks small from P (its half-diagonal below SA_SMALL x the distance to its
// centre) is sampled by area, which costs a seventh as much per sample and loses little there:
// t^2 / cos_l varies little over it. Measured (python -m tests.bench errortime --scenes cornell,
// 64 spp): on the Cornell box (a 0.5 m square under the ceiling) solid angle everywhere cut
// relMSE 8% for 40% more render time (efficiency 357 -> 277); at 0.25, 5% for 17% (341 ->
// 312); at 0.5 the box is all by area, as before, while a 4 m square 0.5 m above a cube keeps
// its gain (1.6x -> 1.02x Cycles' seed-to-seed error).
constexpr float SA_SMALL = 0.5f;

// Four float32 lanes for sph_rect, whose four corners and two angle sums are independent: SSE2
// where there is one, else loops, the same IEEE operations per lane either way (so the same
// bits, and the Python definition's numpy arrays compute them too). As scalar code (~550
// instructions, most of them selects and register moves) sph_rect took ~3x as long.
#if defined(__SSE2__) || defined(_M_X64)
struct F4 {
    __m128 v;
};
inline F4 f4(float a, float b, float c, float d) { return {_mm_setr_ps(a, b, c, d)}; }
inline F4 f4(float a) { return {_mm_set1_ps(a)}; }
inline F4 operator+(F4 a, F4 b) { return {_mm_add_ps(a.v, b.v)}; }
inline F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
inline F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
inline F4 operator/(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
inline F4 sqrt4(F4 a) { return {_mm_sqrt_ps(a.v)}; }
inline F4 abs4(F4 a) { return {_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)}; }
inline F4 neg4(F4 a) { return {_mm_xor_ps(_mm_set1_ps(-0.0f), a.v)}; }
inline F4 gt4(F4 a, F4 b) { return {_mm_cmpgt_ps(a.v, b.v)}; }  // masks: all bits set where true
inline F4 sel4(F4 m, F4 a, F4 b) { return {_mm_or_ps(_mm_and_ps(m.v, a.v), _mm_andnot_ps(m.v, b.v))}; }
inline F4 next4(F4 a) { return {_mm_shuffle_ps(a.v, a.v, _MM_SHUFFLE(0, 3, 2, 1))}; }  // a1 a2 a3 a0
inline F4 evens4(F4 a) { return {_mm_shuffle_ps(a.v, a.v, _MM_SHUFFLE(2, 0, 2, 0))}; }  // a0 a2 a0 a2
inline F4 odds4(F4 a) { return {_mm_shuffle_ps(a.v, a.v, _MM_SHUFFLE(3, 1, 3, 1))}; }   // a1 a3 a1 a3
inline bool all4(F4 m) { return _mm_movemask_ps(m.v) == 0xF; }
inline float lane4(F4 a, int k) {
    alignas(16) float out[4];
    _mm_store_ps(out, a.v);
    return out[k];
}
#else
struct F4 {
    float v[4];
};
inline F4 f4(float a, float b, float c, float d) { return {{a, b, c, d}}; }
inline F4 f4(float a) { return {{a, a, a, a}}; }
#define DACRT_F4_MAP(expr) \
    F4 r;                  \
    for (int k = 0; k < 4; ++k) r.v[k] = (expr); \
    return r
inline F4 operator+(F4 a, F4 b) { DACRT_F4_MAP(a.v[k] + b.v[k]); }
inline F4 operator-(F4 a, F4 b) { DACRT_F4_MAP(a.v[k] - b.v[k]); }
inline F4 operator*(F4 a, F4 b) { DACRT_F4_MAP(a.v[k] * b.v[k]); }
inline F4 operator/(F4 a, F4 b) { DACRT_F4_MAP(a.v[k] / b.v[k]); }
inline F4 sqrt4(F4 a) { DACRT_F4_MAP(std::sqrt(a.v[k])); }
inline F4 abs4(F4 a) { DACRT_F4_MAP(std::fabs(a.v[k])); }
inline F4 neg4(F4 a) { DACRT_F4_MAP(-a.v[k]); }
inline F4 gt4(F4 a, F4 b) { DACRT_F4_MAP(a.v[k] > b.v[k] ? 1.0f : 0.0f); }  // masks: 1 where true
inline F4 sel4(F4 m, F4 a, F4 b) { DACRT_F4_MAP(m.v[k] != 0 ? a.v[k] : b.v[k]); }
inline F4 next4(F4 a) { return f4(a.v[1], a.v[2], a.v[3], a.v[0]); }
inline F4 evens4(F4 a) { return f4(a.v[0], a.v[2], a.v[0], a.v[2]); }
inline F4 odds4(F4 a) { return f4(a.v[1], a.v[3], a.v[1], a.v[3]); }
inline bool all4(F4 m) { return (m.v[0] != 0) & (m.v[1] != 0) & (m.v[2] != 0) & (m.v[3] != 0); }
inline float lane4(F4 a, int k) { return a.v[k]; }
#undef DACRT_F4_MAP
#endif

// atan2(y, x) per lane: Cephes' atanf polynomial after reducing |y| / |x| to at most tan(pi/8),
// within 3 float32 ULPs (2.1e-7 relative), from basic operations and selects only (glibc's
// atan2f takes ~30 ns, and its bits are not numpy's).
inline F4 atan2_4(F4 y, F4 x) {
    const F4 ax = abs4(x), ay = abs4(y), zero = f4(0.0f);
    const F4 swap = gt4(ay, ax);  // beyond pi/4: pi/2 - atan(|x| / |y|)
    const F4 num = sel4(swap, ax, ay), den = sel4(swap, ay, ax);
    const F4 mid = gt4(num, f4(0.41421356f) * den);  // beyond pi/8: pi/4 + atan((t - 1) / (t + 1))
    const F4 r = sel4(mid, num - den, num) / sel4(mid, num + den, den);
    const F4 z = r * r;
    F4 p = f4(8.05374449538e-2f) * z - f4(1.38776856032e-1f);
    p = p * z + f4(1.99777106478e-1f);
    p = p * z - f4(3.33329491539e-1f);
    F4 a = p * z * r + r;
    a = a + sel4(mid, f4(PI_4), zero);
    a = sel4(swap, f4(PI_2) - a, a);
    a = sel4(gt4(zero, x), f4(PI) - a, a);
    return sel4(gt4(zero, y), neg4(a), a);
}

// The rectangle [lo_x, hi_x] x [lo_y, hi_y] of the lamp's local square seen from P.
inline SphRect sph_rect(const LampRecord& L, const float P[3], float lo_x, float hi_x, float lo_y, float hi_y) {
    SphRect r;
    const float rel[3] = {P[0] - L.pos[0], P[1] - L.pos[1], P[2] - L.pos[2]};
    r.lx = std::sqrt(dot3(L.axis_x, L.axis_x));
    r.ly = std::sqrt(dot3(L.axis_y, L.axis_y));
    const float fx = dot3(rel, L.inv_x), fy = dot3(rel, L.inv_y);
    r.h = dot3(rel, L.normal);
    r.x0 = (lo_x - fx) * r.lx;
    r.x1 = (hi_x - fx) * r.lx;
    r.y0 = (lo_y - fy) * r.ly;
    r.y1 = (hi_y - fy) * r.ly;
    const float h2 = r.h * r.h;
    {
        const float cx = 0.5f * (r.x0 + r.x1), cy = 0.5f * (r.y0 + r.y1), ex = r.x1 - r.x0, ey = r.y1 - r.y0;
        if (0.25f * (ex * ex + ey * ey) < (SA_SMALL * SA_SMALL) * (cx * cx + cy * cy + h2)) {  // (NaN: not small)
            r.b0 = r.b1 = r.d23 = r.S = 0.0f;
            r.use = false;
            return r;
        }
    }
    // per edge (y0, x1, y1, x0): 1 / the distance to its line, and the unit normal of the plane
    // through P and it, as its z component n (along the lamp's normal) and in-plane part a
    const F4 inv = f4(1.0f) / sqrt4(f4(h2) + f4(r.y0, r.x1, r.y1, r.x0) * f4(r.y0, r.x1, r.y1, r.x0));
    const F4 n = f4(-r.y0, r.x1, r.y1, -r.x0) * inv, a = f4(r.h) * inv;
    // per corner (edge and next edge) its inner angle g as e^(i (g - pi/2)) = (sin g, -cos g):
    // the sine |n_a x n_b| from the components (not 1 - cos^2, which loses g near 0 and pi)
    const F4 nb = next4(n), ab = next4(a), aa = a * a;
    const F4 sin_g = sqrt4(aa * nb * nb + n * n * ab * ab + aa * ab * ab), cos_m = n * nb;
    // d_i = g_i - pi/2 in (-pi/2, pi/2) while sin g_i > 0: d0 + d1 and d2 + d3 as the arguments
    // of products of two corners' turns (two atan2 instead of four)
    const F4 se = evens4(sin_g), so = odds4(sin_g), ce = evens4(cos_m), co = odds4(cos_m);
    const F4 d = atan2_4(se * co + ce * so, se * so - ce * co);
    r.d23 = lane4(d, 1);
    r.S = lane4(d, 0) + r.d23;
    r.b0 = lane4(n, 0);
    r.b1 = lane4(n, 2);
    // horizontal distance from P's foot to the rectangle, for its elevation
    const float dx = std::max(0.0f, std::max(r.x0, -r.x1)), dy = std::max(0.0f, std::max(r.y0, -r.y1));
    const float t2 = SA_MIN_TAN_ELEVATION * SA_MIN_TAN_ELEVATION;
    const float far2 = std::max(r.x0 * r.x0, r.x1 * r.x1) + std::max(r.y0 * r.y0, r.y1 * r.y1) + h2;
    // P in front (one-sided), h^2 normal, every square finite (else S is garbage, not small),
    // every corner's sine > 0 (the sums' arguments unambiguous); NaN fails each test
    r.use = (r.h > 0) & (h2 >= std::numeric_limits<float>::min()) & all4(gt4(sin_g, f4(0.0f))) &
            (far2 <= std::numeric_limits<float>::max()) & (h2 >= t2 * (dx * dx + dy * dy)) &
            (r.S >= SA_MIN_SOLID_ANGLE) & (hi_x > lo_x) & (hi_y > lo_y);
    return r;
}

// The point (x, y) relative to P's foot of the sample (u1, u2) (sph_rect's r.use true): u1 picks
// the sub-area S u1 from the x0 edge, u2 the height along that column uniformly in solid angle.
// Clamped, NaN-safe, to the rectangle (where the warp's divisions hit 0 at the very edges).
inline void sph_rect_sample(const SphRect& r, float u1, float u2, float& x, float& y) {
    const float phi = u1 * r.S - r.d23;
    const float fu = (std::cos(phi) * r.b0 + r.b1) / std::sin(phi);
    float cu = 1.0f / std::sqrt(fu * fu + r.b0 * r.b0);
    cu = fu > 0 ? cu : -cu;
    cu = max_sel(-1.0f, min_sel(1.0f, cu));
    const float xu = cu * r.h / std::max(std::sqrt(1.0f - cu * cu), 1e-7f);
    x = max_sel(r.x0, min_sel(r.x1, xu));
    const float d2 = x * x + r.h * r.h;
    const float h0 = r.y0 / std::sqrt(d2 + r.y0 * r.y0), h1 = r.y1 / std::sqrt(d2 + r.y1 * r.y1);
    const float hv = h0 + u2 * (h1 - h0);
    const float yv = hv * std::sqrt(d2) / std::sqrt(max_sel(0.0f, 1.0f - hv * hv));
    y = max_sel(r.y0, min_sel(r.y1, yv));
}

}  // namespace lampmath

struct LampSample {
    float wi[3], dist, value[3], pdf;
};

// Cycles' Light Falloff node feeding the lamp's emission (svm_node_light_falloff) at the ray
// length t to the lamp's point (the sample's distance, or where a ray meets the lamp): the
// Linear output x t, Constant x t^2, then Smooth s > 0 x t^2 / (s + t^2); 1 for Quadratic
// without Smooth (the lamp's own falloff is the inverse square already).
inline float falloff_factor(const LampRecord& L, float t) {
    float f = L.falloff_power >= 1.0f ? t : 1.0f;
    if (L.falloff_power >= 2.0f) f *= t;
    const float t2 = t * t;
    if ((L.falloff_smooth > 0.0f) & std::isfinite(t2)) f *= t2 / (L.falloff_smooth + t2);  // (as Cycles)
    return f;
}

inline bool has_falloff(const LampRecord& L) { return (L.falloff_power != 0.0f) | (L.falloff_smooth != 0.0f); }

// One light sample of lamp L toward the shading point P (Lamp.sample in the Python definitions).
inline LampSample sample_lamp(const LampRecord& L, const float P[3], float u1, float u2) {
    using namespace lampmath;
    LampSample s;
    const int kind = int(L.kind), shape = int(L.shape);
    float scale = 1.0f;      // multiplies emit
    bool per_pdf = false;    // sun cone, background: value = (radiance / constant pdf) x 1
    switch (kind) {
    case LAMP_POINT:
    case LAMP_SPOT: {
        float axis[3] = {L.pos[0] - P[0], L.pos[1] - P[1], L.pos[2] - P[2]};
        const float d = normalize(axis);
        const float r = L.radius;
        const bool outside = d > r;
        const bool apart = d > 0;  // P at the very centre has no direction to the light
        if (shape == POINT_DELTA) {
            for (int a = 0; a < 3; ++a) s.wi[a] = axis[a];
            s.dist = d;
            s.pdf = INF;
            scale = d > 0 ? 1.0f / (d * d) : 0.0f;
        } else if (shape == POINT_SPHERE) {
            // Outside: the cone the sphere subtends. Inside (as Cycles, the sphere is seen in
            // every direction): the whole sphere of directions, a cone with 1 - cos = 2.
            const float sin2 = std::min(1.0f, (r * r) / std::max(1e-30f, d * d));
            const float omc = outside ? one_minus_cos_from_sin2(sin2) : 2.0f;
            float local[3];
            const float cos_t = uniform_cone(u1, u2, omc, local);
            to_world(local, axis, s.wi);
            const float b = d * cos_t;  // the near surface from outside, the far one from inside
            const float h = std::sqrt(std::max(0.0f, r * r - std::max(0.0f, d * d - b * b)));
            s.dist = outside ? b - h : b + h;
            s.pdf = apart ? INV_2PI / omc : 0.0f;
            scale = apart ? TWO_PI * omc : 0.0f;
        } else {                         // disk of radius r through the centre, facing P (also from
                                         // within r: Cycles' soft-falloff point has no inside)
            float x, y, t1[3], t2[3];
            concentric_disk(u1, u2, x, y);
            orthonormal_basis(axis, t1, t2);
            const float rx = r * x, ry = r * y;
            for (int a = 0; a < 3; ++a) {
                float q = t1[a] * rx;
                q += t2[a] * ry;
                q += L.pos[a];
                s.wi[a] = q - P[a];
            }
            s.dist = normalize(s.wi);
            const float cos_l = dot3(s.wi, axis);
            const bool good = apart && cos_l > 0;
            const float p = s.dist * s.dist / (PI * r * r * cos_l);
            s.pdf = good ? p : 0.0f;
            scale = good ? 1.0f / p : 0.0f;
        }
        // Cycles (light/spot.h): a sphere spot's cone applies only to points outside the
        // sphere; inside it the light is seen all round, unshaped
        if (kind == LAMP_SPOT && (shape != POINT_SPHERE || outside)) {
            const float from_light[3] = {-s.wi[0], -s.wi[1], -s.wi[2]};
            scale *= spot_attenuation(L, from_light);
        }
        break;
    }
    case LAMP_SUN:
        s.dist = INF;
        if (shape == SUN_DELTA) {
            for (int a = 0; a < 3; ++a) s.wi[a] = L.pos[a];
            s.pdf = INF;
        } else {
            float local[3];
            uniform_cone(u1, u2, L.omc, local);
            to_world(local, L.pos, s.wi);
            s.pdf = L.pdf;
            per_pdf = true;
        }
        break;
    case LAMP_AREA: {
        if (shape == AREA_RECT) {
            // by solid angle over the rectangle, or the part of it the spread's box about P
            // keeps (where sph_rect finds that too small or too flat: by area, below)
            AreaBox box{-0.5f, 0.5f, -0.5f, 0.5f, 1.0f, 1.0f, 1.0f, true};
            if (L.spread_norm != 0) box = area_spread_box(L, P);  // per lamp: predicted
            const SphRect r = sph_rect(L, P, box.lo_x, box.hi_x, box.lo_y, box.hi_y);
            if (r.use) {  // per point, and coherent across neighbouring points
                float x, y;
                sph_rect_sample(r, u1, u2, x, y);
                const float sx = x / r.lx, sy = y / r.ly;  // along the unit axes
                for (int a = 0; a < 3; ++a) {
                    float w = L.axis_x[a] * sx;
                    w += L.axis_y[a] * sy;
                    s.wi[a] = w - L.normal[a] * r.h;
                }
                s.dist = normalize(s.wi);
                s.pdf = 1.0f / r.S;
                scale = r.S * area_spread(L, -dot3(s.wi, L.normal), s.wi);
                break;
            }
        }
        float x, y;
        if (shape == AREA_ELLIPSE) {
            concentric_disk(u1, u2, x, y);
            x *= 0.5f;
            y *= 0.5f;
        } else {
            x = u1 - 0.5f;
            y = u2 - 0.5f;
        }
        float area = L.area;  // of what x, y are uniform over
        bool drawn = true;    // x, y on the lamp and within the spread's reach
        if (L.spread_norm != 0) {  // per lamp: predicted
            // Uniform over the part of the bounding rectangle within the spread's box about P
            // (area_spread_box; a whole rectangle's box gives u1 - 0.5 again, bit for bit),
            // where box points off an ellipse give 0; an ellipse the box covers whole keeps the
            // concentric map. Selects: whether a box is clipped varies from point to point.
            const AreaBox box = area_spread_box(L, P);
            const bool ellipse = shape == AREA_ELLIPSE, use_box = !ellipse | !box.full;
            const float bx = box.lo_x + u1 * box.w_x, by = box.lo_y + u2 * box.w_y;
            x = use_box ? bx : x;
            y = use_box ? by : y;
            drawn = (box.frac > 0) & (!ellipse | box.full | (bx * bx + by * by <= 0.25f));
            area = area_box_area(L, shape, box.full) * box.frac;
        }
        for (int a = 0; a < 3; ++a) {
            float q = L.axis_x[a] * x;
            q += L.axis_y[a] * y;
            s.wi[a] = q + (L.pos[a] - P[a]);
        }
        s.dist = normalize(s.wi);
        const float cos_l = -dot3(s.wi, L.normal);
        const bool ok = (cos_l > 0) & (s.dist > 0) & drawn;
        const float p = s.dist * s.dist / (area * cos_l);
        s.pdf = select_f(ok, p, 0.0f);
        scale = select_f(ok, 1.0f / p, 0.0f);
        scale *= area_spread(L, cos_l, s.wi);
        break;
    }
    default:  // LAMP_BACKGROUND
        uniform_sphere(u1, u2, s.wi);
        s.dist = INF;
        s.pdf = L.pdf;
        per_pdf = true;
        break;
    }
    if (L.ies != 0) {  // per lamp: predicted; the profile along the sample's direction (point, spot, area, sun)
        const float from_light[3] = {-s.wi[0], -s.wi[1], -s.wi[2]};
        scale *= ies_lamp_factor(L.ies, L.ies_m3, from_light);
    }
    if (has_falloff(L)) scale *= falloff_factor(L, s.dist);  // per lamp: predicted (finite lamps only)
    for (int a = 0; a < 3; ++a) s.value[a] = (per_pdf ? L.emit[a] / L.pdf : L.emit[a]) * scale;
    return s;
}

// hit_lamp for an area lamp, without or with spread (AreaLight.intersect). Everything is computed
// and the answer returned without a branch per ray: whether a ray meets the lamp is a coin flip
// a branch mispredicts (lamp_gather ~1.5x slower).
template <bool SPREAD>
inline bool hit_area(const LampRecord& L, const float O[3], const float D[3], float tmax, float Le[3], float& pdf) {
    using namespace lampmath;
    const float denom = dot3(D, L.normal);  // < 0: travelling toward the emitting face
    const float t = (dot3(L.pos, L.normal) - dot3(O, L.normal)) / denom;
    float rel[3];
    for (int a = 0; a < 3; ++a) rel[a] = (D[a] * t + O[a]) - L.pos[a];
    const float lx = dot3(rel, L.inv_x), ly = dot3(rel, L.inv_y);
    const bool inside = int(L.shape) == AREA_ELLIPSE ? lx * lx + ly * ly <= 0.25f
                                                     : (std::fabs(lx) <= 0.5f) & (std::fabs(ly) <= 0.5f);
    const float cos_l = -denom;
    float area = L.area, scale = 1.0f;
    bool drawn = true;
    if (SPREAD) {
        // only the part sample_lamp draws from for a shading point at O (beyond the box the
        // profile is 0), with that draw's pdf
        const AreaBox box = area_spread_box(L, O);
        const bool in_box = (lx >= box.lo_x) & (lx <= box.hi_x) & (ly >= box.lo_y) & (ly <= box.hi_y);
        drawn = (box.full | in_box) & (box.frac > 0);
        area = area_box_area(L, int(L.shape), box.full) * box.frac;
        scale = area_spread(L, cos_l, D);
    }
    pdf = t * t / (area * cos_l);
    const bool hit = (denom < 0) & (t > 0) & (t < tmax) & inside & drawn;
    if ((L.ies != 0) & hit) {  // (area_lanes_apply leaves such lamps to this path) only where met:
        const float from_light[3] = {-D[0], -D[1], -D[2]};  // a lookup costs more than a mispredict
        scale *= ies_lamp_factor(L.ies, L.ies_m3, from_light);
    }
    if (has_falloff(L) & hit) scale *= falloff_factor(L, t);  // (also left to this path)
    for (int a = 0; a < 3; ++a) Le[a] = L.emit[a] * scale;
    if (hit & (int(L.shape) == AREA_RECT)) {  // sample_lamp's pdf at O: its sph_rect decides
        // (a branch: most rays miss, and sph_rect's four atan2 would cost every candidate)
        AreaBox box{-0.5f, 0.5f, -0.5f, 0.5f, 1.0f, 1.0f, 1.0f, true};
        if (SPREAD) box = area_spread_box(L, O);
        const SphRect r = sph_rect(L, O, box.lo_x, box.hi_x, box.lo_y, box.hi_y);
        pdf = r.use ? 1.0f / r.S : pdf;
    }
    return hit;
}

__attribute__((noinline)) inline bool hit_area_spread(const LampRecord& L, const float O[3], const float D[3], float tmax,
                                                      float Le[3], float& pdf) {
    return hit_area<true>(L, O, D, tmax, Le, pdf);
}

// A ray (O, D) meeting finite lamp L at t < tmax (Lamp.intersect): radiance Le and solid-angle
// pdf. False for lamps at infinity and delta lamps (no ray meets them). Le and pdf mean
// something only when it returns true (an area lamp writes them either way). Always inlined:
// lamp_gather's loop around it runs ~20% slower calling it (GCC stops inlining it at about
// this size).
__attribute__((always_inline)) inline bool hit_lamp(const LampRecord& L, const float O[3], const float D[3], float tmax, float Le[3], float& pdf) {
    using namespace lampmath;
    const int kind = int(L.kind), shape = int(L.shape);
    float scale = 1.0f;
    bool seen = true;
    if ((kind == LAMP_POINT || kind == LAMP_SPOT) && shape != POINT_DELTA) {
        const float r = L.radius;
        const float oc[3] = {L.pos[0] - O[0], L.pos[1] - O[1], L.pos[2] - O[2]};
        const float b = dot3(oc, D), d2 = dot3(oc, oc);
        if (!(d2 > 0)) return false;  // origin at the centre
        float t_hit;
        bool cone = true;             // a sphere spot shapes only what lies outside it
        if (shape == POINT_SPHERE) {
            // from outside the near intersection; from inside the far one (seen all round)
            const bool outside = d2 > r * r;
            cone = outside;
            const float perp[3] = {oc[0] - D[0] * b, oc[1] - D[1] * b, oc[2] - D[2] * b};
            const float h2 = r * r - dot3(perp, perp);
            const float h = std::sqrt(std::max(0.0f, h2));
            const float t = outside ? b - h : b + h;
            if (!(h2 >= 0 && t > 0 && t < tmax)) return false;
            t_hit = t;
            pdf = outside ? INV_2PI / one_minus_cos_from_sin2(std::min(1.0f, r * r / d2)) : INV_2PI / 2.0f;
        } else {                              // disk through the centre, facing the ray origin
            const float dist_c = std::sqrt(d2);
            const float cos_l = b / dist_c;   // cos between D and the disk axis
            const float t = dist_c / cos_l;
            const float rel[3] = {D[0] * t - oc[0], D[1] * t - oc[1], D[2] * t - oc[2]};
            if (!(cos_l > 0 && t < tmax && dot3(rel, rel) <= r * r)) return false;
            pdf = t * t / (PI * r * r * cos_l);
            t_hit = t;
        }
        if (kind == LAMP_SPOT && cone) {
            const float from_light[3] = {-D[0], -D[1], -D[2]};
            scale = spot_attenuation(L, from_light);
        }
        if (L.ies != 0) {  // as sample_lamp weighs its samples: MIS sees one emission
            const float from_light[3] = {-D[0], -D[1], -D[2]};
            scale *= ies_lamp_factor(L.ies, L.ies_m3, from_light);
        }
        if (has_falloff(L)) scale *= falloff_factor(L, t_hit);
    } else if (kind == LAMP_AREA) {
        // per lamp, predicted; with spread out of line, which keeps lamps without spread as fast
        return L.spread_norm != 0 ? hit_area_spread(L, O, D, tmax, Le, pdf) : hit_area<false>(L, O, D, tmax, Le, pdf);
    } else {
        return false;
    }
    for (int a = 0; a < 3; ++a) Le[a] = L.emit[a] * scale;
    return seen;
}

// Whether direction D falls in the disk of sun L with an angle (SUN_CONE): miss_lamp's test,
// which lamp_gather's lamps at infinity (lamps.cpp) also list their rays by.
inline bool in_sun_disk(const LampRecord& L, const float D[3]) { return lampmath::dot3(D, L.pos) >= L.cos_half; }

// The radiance and solid-angle pdf of lamp L at infinity (a sun with an angle, or the
// background) seen along D, D in its disk: miss_lamp once it has seen the lamp.
inline void infinite_radiance(const LampRecord& L, const float D[3], float Le[3], float& pdf) {
    float scale = 1.0f;
    if (L.ies != 0) {  // a sun's profile along the direction it travels (as sample_lamp weighs it)
        const float from_light[3] = {-D[0], -D[1], -D[2]};
        scale = ies_lamp_factor(L.ies, L.ies_m3, from_light);
    }
    for (int a = 0; a < 3; ++a) Le[a] = L.emit[a] * scale;
    pdf = L.pdf;
}

// A ray that left the scene along D seeing lamp L at infinity (Lamp.eval_miss): radiance and
// solid-angle pdf. False for finite lamps and the delta sun.
inline bool miss_lamp(const LampRecord& L, const float D[3], float Le[3], float& pdf) {
    const int kind = int(L.kind);
    if (kind == LAMP_SUN) {
        if (int(L.shape) == SUN_DELTA || !in_sun_disk(L, D)) return false;
    } else if (kind != LAMP_BACKGROUND) {
        return false;
    }
    infinite_radiance(L, D, Le, pdf);
    return true;
}

}  // namespace dacrt
