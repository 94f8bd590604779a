// Per-triangle hit-point records: what surface_point (pathvertex.h) reads of one triangle,
// packed into 32 floats (two cache lines, 128-byte aligned) instead of 24 table rows that are
// each their own cache line: the table's 15 rows (v0, v1 - v0, v2 - v0, unit geometric normal,
// self-intersection step), the TriangleShape that inside_edges and the step derive from them
// per hit (edge margin, twice the area, edges' squared lengths, the step's squared length and
// length), the 9 corner-normal rows (smooth tables) and a flag saying whether they are there.
// Built once per scene from the table (after every change to it); a hit then reads two lines
// and skips the per-hit shape arithmetic, and gives the same bits as the rows (the shape is
// computed by the same expressions, in the same order).
#pragma once

#include <cstddef>
#include <cstring>

#include "pathvertex.h"

namespace dacrt {

constexpr size_t kHitRecord = 32;       // floats per record
constexpr size_t kRecordShape = 15;     // TriangleShape's 7 floats from here
constexpr size_t kRecordNormals = 22;   // the 9 corner-normal rows from here (smooth)
constexpr size_t kRecordSmooth = 31;    // 1 with corner normals, 0 flat
static_assert(sizeof(TriangleShape) == 7 * sizeof(float), "TriangleShape is 7 floats");

// Record of triangle p of geo (15 rows of M) and normals (9 rows of M, null: flat) to r.
inline void hit_record(const float* geo, size_t M, const float* normals, size_t p, float* r) {
    auto g = [&](int row) { return geo[size_t(row) * M + p]; };
    for (int row = 0; row < 15; ++row) r[row] = g(row);
    const TriangleShape sh = shape_of(g);
    std::memcpy(r + kRecordShape, &sh, sizeof sh);
    for (int row = 0; row < 9; ++row) r[kRecordNormals + size_t(row)] = normals ? normals[size_t(row) * M + p] : 0.0f;
    r[kRecordSmooth] = normals ? 1.0f : 0.0f;
}

// surface_point of a hit on the triangle whose record is r (smooth: interpolate its corner normals).
inline void surface_point_record(const float* r, bool smooth, const Hit& h, const float d[3], SurfacePoint& s) {
    TriangleShape sh;
    std::memcpy(&sh, r + kRecordShape, sizeof sh);
    surface_point_of([r](int row) { return r[row]; }, [r](int row) { return r[kRecordNormals + size_t(row)]; },
                     smooth, sh, h, d, s);
}

// surface_point of hit h (0 <= prim < M) from its record where records are given (the same
// bits, faster), else from the table's rows.
inline void surface_point_at(const float* geo, size_t M, const float* normals, const float* records, const Hit& h,
                             const float d[3], SurfacePoint& s) {
    if (records)
        surface_point_record(records + kHitRecord * prim_at(h, M), normals != nullptr, h, d, s);
    else
        surface_point(geo, M, normals, h, d, s);
}

// The records of all M triangles (out: M x kHitRecord floats), threaded.
void hit_records(const float* geo, size_t M, const float* normals, float* out);

}  // namespace dacrt
