// Per-ray helper kernels for the renderer's shading side: the arithmetic that sits between two
// traced batches (hit-point reconstruction, diffuse bounce directions, random numbers, ray
// packing). Fused and threaded here because numpy spends one memory pass per operation and one
// core on all of them, which made Python, not tracing, the bulk of a render.
//
// Vectors are structure-of-arrays: 3 rows of `stride` floats (numpy (3, n) C order).
#pragma once

#include <cmath>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "lighttree.h"
#include "ray.h"

namespace dacrt {

// The caller's arrays are read with the GIL released, and another Python thread may rewrite
// them after the binding checked them. So every index a kernel takes from one (a column of a
// path array, a film column, a triangle of a hit) is read once and clamped to the n >= 1 entries
// it indexes: a rewritten index selects a wrong entry, never memory outside the array (as
// vertex_of does for the tracer's triangles). Negative values clamp to n - 1 too.
template <class Index>
inline size_t index_at(const Index* idx, size_t j, size_t n) {
    const uint64_t k = uint64_t(int64_t(__atomic_load_n(idx + j, __ATOMIC_RELAXED)));
    return k < n ? size_t(k) : n - 1;
}
inline size_t prim_at(const Hit& h, size_t M) {
    const uint32_t p = uint32_t(__atomic_load_n(&h.prim, __ATOMIC_RELAXED));
    return p < M ? size_t(p) : M - 1;
}

// Cycles' sample clamp (film/light_passes.h film_clamp_light): a contribution whose channels'
// absolute values sum to more than limit is scaled down to that sum (limit: 3 x the Clamp
// Direct / Indirect setting, infinity for none).
inline void clamp_light(float v[3], float limit) {
    const float sum = std::fabs(v[0]) + std::fabs(v[1]) + std::fabs(v[2]);
    if (sum > limit) {
        const float s = limit / sum;
        for (int a = 0; a < 3; ++a) v[a] *= s;
    }
}

// ULP of a positive normal float: 2^(its exponent - 23) (self-intersection steps are counted
// in these, as the add-on documents).
inline float ulp_of(float x) {
    uint32_t b;
    std::memcpy(&b, &x, 4);
    b = (b & 0x7F800000u) - (23u << 23);
    float u;
    std::memcpy(&u, &b, 4);
    return u;
}

constexpr float kFloatMax = std::numeric_limits<float>::max();

// |d| in float32: sqrt(d . d), the same bits, where that sum is finite; beyond (|d| past
// ~1.8e19, a vast emitter's sampled point) scaled by the largest component, so the length and
// the unit direction stay finite; +inf where a component is. (An overflowing sum had left a
// shadow ray with a zero direction.)
inline float length3(const float d[3]) {
    const float s = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (s <= kFloatMax) return std::sqrt(s);
    const float m = std::fmax(std::fabs(d[0]), std::fmax(std::fabs(d[1]), std::fabs(d[2])));
    if (!(m < kFloatMax)) return m;   // inf (NaN stays NaN through fmax only if all are)
    const float e[3] = {d[0] / m, d[1] / m, d[2] / m};
    return m * std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
}

// out[r] = sum over j of values[r * samples + j] x weights[j] (weights null: 1), in double, j in
// order: the film's per-pixel sums of a block of samples (rows = channels x pixels).
void sample_sums(const float* values, size_t rows, size_t samples, const double* weights, double* out);

// Ray records from rows O, D (stride n) and tfar; ids 0..n-1.
void pack_rays(const float* O, const float* D, const float* tfar, size_t n, Ray* out);

// The per-triangle table surface() reads, for M triangles of float32 vertices: rows v0,
// v1 - v0, v2 - v0 (differences in double, rounded once), the unit geometric normal (double
// cross product; 0 for zero area) and the front-side self-intersection step along that normal:
// of offset_ulps ULPs of the triangle's largest |coordinate| (at least `tiny`) the share P's
// error along the normal needs, sum_a |n_a| ulp(largest |coordinate a|) / ulp(largest), at most
// 1 (a plane z = c a million units across: ULPs of c), or all of it where full[i] (null: none)
// is set: a triangle with a coincident twin, whose float test at a ray's origin errs by ULPs of
// its coordinates along the ray. The hit point's margin from the edges is always the whole
// (pathvertex.h edge_margin). geo: 15 rows of M; area: M doubles; keys (M, or null): an odd
// order-free hash of each triangle's corners' bits (-0 as 0): exact copies have equal keys;
// plane_keys (M, or null): each triangle's coplanar_key (coplanar.h) of its v0 and normal rows
// with plane_inv_step, written here where they are at hand (coplanar_groups' input: keyed in a
// pass of its own, it had read the six rows again). Triangles must index existing vertices
// (callers check).
void triangle_table(const float* vertices, size_t V, const int32_t* triangles, size_t M, float offset_ulps, float tiny,
                    const uint8_t* full, float* geo, double* area, uint64_t* keys = nullptr,
                    uint64_t* plane_keys = nullptr, float plane_inv_step = 0.0f);

// out[i] = 1 where keys[i] != 0 and another entry holds the same key, else 0 (n entries): the
// triangles whose triangle_table key repeats (a surface modelled twice). Keys partitioned by
// hash into buckets of ~4K, each searched in an open-addressing table that fits in cache (see
// surface.cpp); a sort of a million keys had cost ~60 ms a frame. n < 2^32.
void repeated_keys(const uint64_t* keys, size_t n, uint8_t* out);

// Unit geometric normals (M rows of 3, by the winding (v1 - v0) x (v2 - v0)) of triangles of
// float64 vertices (V rows of 3), in double, rounded once; good[i] = 0 (normal 0) for a
// zero-area or non-finite triangle. Triangles must index existing vertices (callers check).
void face_normals(const double* vertices, size_t V, const int32_t* triangles, size_t M, float* normals, uint8_t* good);

// Points through k affine maps (the export's object-to-world transform of a mesh's instances):
// out[i][p] (k x n rows of 3) = linear_i points[p] + offset_i, each component computed as
// ((l0 x + l1 y) + l2 z) + o in double and rounded once to T (float or double); linear: k
// row-major 3x3 doubles, offset: k x 3 doubles or null. Threaded over all k n points.
template <class T>
void transform_points(const float* points, size_t n, const double* linear, const double* offset, size_t k, T* out);

// Per-corner values (M triangles x 3 corners x c floats) as the rows barycentric interpolation
// reads: corner 0 (c rows of M), corner 1 - corner 0, corner 2 - corner 0 (3c rows in all).
void corner_rows(const float* per_corner, size_t M, size_t c, float* rows);

// Whether every corner normal (M x 3 corners x 3, C order) is within tol of its triangle's
// geometric normal (geo rows 9-11 of M): flat shading needs no interpolation.
bool normals_flat(const float* normals, const float* geo, size_t M, float tol);

// Hit points of rays idx[0..k) (all rays when idx is null): reads hits[i] and column i of D
// (stride n). geo: 15 rows of M (v0, v1 - v0, v2 - v0, unit geometric normal, front-side
// self-intersection step); normals: 9 rows of M (corner 0 normal, corner 1 - 0, corner 2 - 0)
// or null for flat shading. out: rows P, ng, P_off, then ns when normals are given (stride k);
// ng, ns face the incoming ray and P_off is P stepped off the surface toward the ray's side.
// Returns the number of selected rays whose prim is not a triangle of geo (out stays unwritten
// for them; callers raise). records: as survivor_throughput's (null: the rows).
size_t surface(const float* geo, size_t M, const float* normals, const Hit* hits, const int64_t* idx,
               size_t k, const float* D, size_t n, float* out, const float* records = nullptr);

// Two uniforms per path for keys (rows k0, k1; stride n) and dimension words ka, kb.
void uniform2_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, float* u1, float* u2);

// The same two words as uniform2_rows, as a double with 32-bit resolution (a choice among many
// lights) and a float with 24.
void uniform_pick_rows(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, double* pick, float* u);

// Cosine-weighted directions around the shading normals ns (3 rows, stride n), random numbers
// from keys/ka/kb; pdf = cos / pi. ok[i] = 0 for directions below the geometric normal ng
// (null: ns is ng) or at grazing cos = 0.
// With origins O (3 rows, stride n; else null) it also writes the bounce rays' records (org O,
// dir wi, tfar inf, id i), saving the tracer's packing pass.
// With a ShadingOffset, Cycles' shadow terminator shading offset dims the throughput of each
// kept direction leaving a triangle whose frequency multiplier exceeds 1 (shift_cos_in).
struct ShadingOffset {
    const float* freq = nullptr;   // per triangle, 1 / (1 - offset / 2)
    size_t M = 0;                  // triangles of freq
    const int32_t* prim = nullptr; // the triangle each direction leaves (n)
    float* thr = nullptr;          // throughputs (3 rows, stride n), scaled in place
};
void cosine_scatter(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                    float* wi, float* pdf, uint8_t* ok, const float* O = nullptr, Ray* rays = nullptr,
                    const ShadingOffset* offset = nullptr);
// cosine_scatter's directions [begin, end) on the calling thread.
void scatter_range(const uint32_t* keys, size_t n, uint32_t ka, uint32_t kb, const float* ns, const float* ng,
                   float* wi, float* pdf, uint8_t* ok, const float* O, Ray* rays, const ShadingOffset* offset,
                   size_t begin, size_t end);

}  // namespace dacrt

namespace dacrt {

// Points on triangles which[i] seen from points P (3 rows, stride n), random numbers u1, u2:
// uniform by solid angle where the triangle is large for its distance, else by area
// (trianglelight.h); geo as in surface(), area per triangle of geo. Writes the unit direction
// wi toward the point, its distance dist, the solid-angle pdf (0 where the point cannot be
// seen: edge-on or coincident) and target, the point stepped off the emitter toward P (where a
// shadow ray must end) by its offset row or, if longer, 8 ULPs of max(|P|, dist). Returns how
// many which[i] are not triangles of geo (nothing written).
size_t sample_triangles(const float* geo, const float* area, size_t M, const int64_t* which, const float* P,
                        const float* u1, const float* u2, size_t n, float* wi, float* dist, float* pdf,
                        float* target);

}  // namespace dacrt

namespace dacrt {

// Next-event estimation weights: for light samples (unit wi toward the light, solid-angle pdf,
// inf for delta lights; value = radiance / pdf) at points with shading normal ns (geometric ng,
// null: same), light-selection probability p_sel and path throughput thr (null: 1), multiplies
// value in place by thr x cos/pi x (power-heuristic MIS weight against the cosine BSDF) / p_sel.
// ok[i]: the sample can contribute (cos > 0 on both normals, some positive channel).
void nee_weight(const float* ns, const float* ng, const float* wi, const float* pdf, const float* p_sel,
                const float* thr, float* value, size_t n, uint8_t* ok);

// Shadow ray records for the samples idx[0..k): origin column idx[j] of O (stride n), and either
// direction wi / length dist or, where target is given and not NaN, the direction toward target
// and that distance times `shorten`. ids are 0..k-1. valid[j] = 0 for zero-length rays (their
// record gets tfar 0: never occluded; callers discard them).
void shadow_rays(const float* O, const float* wi, const float* dist, const float* target, size_t n,
                 const int64_t* idx, size_t k, float shorten, Ray* out, uint8_t* valid);

}  // namespace dacrt

namespace dacrt {

// Camera samples of (pixel, sample) pairs: the path keys (rows: the pixel's seed, see
// random.h pixel_seed, and the sample index; stride n) and the raster position
// of pixel (x = pixel % width, y = pixel / width) plus a pixel-filter offset per axis, drawn by
// table lookup (linear interpolation of an inverse CDF of `table_size` entries) from the
// uniforms of dimension words (ka, kb).
void pixel_samples(const int64_t* pixel, const int64_t* sample, size_t n, int64_t width, uint64_t k0, uint64_t k1,
                   uint32_t ka, uint32_t kb, const float* table, size_t table_size, uint32_t* keys, float* rx,
                   float* ry);

// pixel_samples of a pixel-major block: every one of the npix pixels for the samples s0 ..
// s0 + ns - 1 (path i: pixel pixels[i / ns], sample s0 + i % ns), without the pairs' arrays.
void block_samples(const int64_t* pixels, size_t npix, int64_t s0, size_t ns, int64_t width, uint64_t k0,
                   uint64_t k1, uint32_t ka, uint32_t kb, const float* table, size_t table_size, uint32_t* keys,
                   float* rx, float* ry);

}  // namespace dacrt

namespace dacrt {

// Which paths go on after a vertex: those whose ray hit (hit[i]; hit null: every record with
// prim >= 0, which the pass reads anyway, so the caller makes no flag array) a triangle with live[prim] set
// (not black) and, when u_rr is given, survive Russian roulette with probability
// q = min(sqrt(max channel of thr), 1) (thr null: 1). Writes their indices to idx (sized n) and
// returns how many; dead_black / dead_rr: paths ended by each reason.
size_t survivors(const Hit* hits, const uint8_t* hit, size_t n, const uint8_t* live, size_t M, const float* thr,
                 const float* u_rr, int64_t* idx, size_t* dead_black, size_t* dead_rr);

// Throughput after this reflection of the k survivors idx: albedo[prim] x thr / q (q as in
// survivors() when roulette, else 1); thr_out: 3 rows of stride k. With geo non-null, in the
// same pass, their surface points as surface() gives them (directions D: 3 rows, stride n;
// normals null = flat) to surf_out: rows P, ng, P_off (and ns with normals) of stride k, and
// their triangles to prim_out: one pass over the survivors instead of three calls and passes.
// records (null: read geo and normals' rows): the table's hit-point records (hitrecords.h,
// built from this geo and normals), the same bits from two cache lines a hit.
void survivor_throughput(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                         const int64_t* idx, size_t k, float* thr_out, const float* geo = nullptr,
                         const float* normals = nullptr, const float* D = nullptr, float* surf_out = nullptr,
                         int32_t* prim_out = nullptr, const float* records = nullptr);
// survivor_throughput's survivors [b, e) on the calling thread.
void survivor_range(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                    const int64_t* idx, size_t k, float* thr_out, const float* geo, const float* normals,
                    const float* D, float* surf_out, int32_t* prim_out, size_t b, size_t e,
                    const float* records = nullptr);

// Emission that rays (origins O, unit directions D: 3 rows, stride n) meet on emissive triangles
// (two-sided), added to L (3 rows, stride N) at column pid[i] (distinct per ray). Rays with
// hit[i] set (hit null: every ray; a miss, prim < 0, meets none) whose triangle has
// emissive[prim]: emission (3 rows of M, radiance per triangle)
// x thr (3 rows, stride n; null = 1) x, for BSDF rays (tri_prob non-null; triangles of
// tri_prob 0 are never light-sampled: weight 1), the power-heuristic weight against light
// sampling of that triangle, 1 / (1 + (tri_prob pdf_light / pdf)^2), pdf_light the solid-angle
// pdf sample_triangles has at O for that direction; a triangle with tri_key[q] >= 0 is that
// member of the light tree, its selection probability tri_prob x the tree's pdf at O with
// normal (3 rows, stride n; null: none), the normal the ray's vertex sampled its light with,
// and with light linking receivers (n; null: none) the receiver mask of that vertex's object.
// Returns the number of rays that met emission.
size_t gather_emission(const Hit* hits, const uint8_t* hit, size_t n, const float* emission, const uint8_t* emissive,
                       const float* tri_prob, const float* area, const float* geo, size_t M, const float* O,
                       const float* D, const float* thr, const float* pdf, const int64_t* pid, float* L, size_t N, float clamp,
                       const LightTree* tree = nullptr, const int32_t* tri_key = nullptr,
                       const float* normal = nullptr, const uint64_t* receivers = nullptr);

// A camera's frame in float32, as addon/camera.py CameraModel rounds it: orthonormal
// camera-to-world rotation (columns right, up, back), position, the raster -> viewplane map
// s = origin + r * scale per axis, tan(fov/2), clip start and range; ortho_base = pos -
// clip_start * back (ortho origins). Depth of field as Cycles' thin lens: aperture radius
// (0: pinhole), focus distance, blades (< 3: a round aperture), blade rotation and
// 1 / aperture ratio (anamorphic bokeh: the lens x scaled by it).
struct CameraFrame {
    bool ortho;
    float rot[3][3], pos[3], ortho_base[3];
    float sx0, sx_scale, sy0, sy_scale;
    float tan_half_fov, clip_start, clip_range;
    float aperture, focal_distance, blades, blade_rotation, inv_ratio;
};

// Rays through full-frame raster positions (rx, ry): origins O and unit directions D (3 rows,
// stride n) on the clip-start plane, tmax reaching the clip-end plane; with rays non-null also
// their records (ids 0..n-1) for the tracer. With an aperture and lens uniforms (lu, lv) each
// ray starts from its lens point and passes through the pinhole ray's point on the plane of
// focus (Cycles' camera_sample_perspective / _orthographic).
void camera_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D, float* tmax,
                 Ray* rays = nullptr, const float* lu = nullptr, const float* lv = nullptr);

// One (rows, n) array (C order, elements of itemsize 1, 2, 4 or 8 bytes) and the (rows, k)
// array its columns idx go to.
struct Columns {
    const void* src;
    void* dst;
    size_t rows, n, itemsize;
};

// dst[:, j] = src[:, idx[j]] for every array, j < k (idx checked by the caller).
void take_columns(const Columns* arrays, size_t count, const int64_t* idx, size_t k);

// In place, the columns j with keep[j] false dropped from every array (src == dst, rows x n)
// and from the records rays (n; null: none), the kept ones moved forward in order to (rows, m)
// at the start of each buffer and the moved records' ids renumbered to their positions: what
// take_columns of keep's indices and pack_rays would give, moving only the columns past the
// first drop (a bounce drops a few of 10^5 paths). Returns m.
size_t drop_columns(const uint8_t* keep, size_t n, const Columns* arrays, size_t count, Ray* rays);

}  // namespace dacrt

