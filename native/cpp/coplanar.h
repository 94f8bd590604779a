// Triangles in one plane: the groups of triangles whose quantised planes repeat, the candidates
// for faces overlapping in part (the add-on's overlappingfaces.py tests their pairs exactly).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dacrt {

// The plane key of a triangle with corner v0 and unit normal (x, y, z) (a triangle_table's rows 0-2
// and 9-11; triangle_table writes it in its own pass), exact and the same on every ISA (float32
// operations in this order): the normal up to sign (flipped where s . n < 0, s = kCoplanarSign)
// in steps of 1/normal_bins per component, 14 bits each, and the offset s(n) n . v0 times
// inv_step + 2^21 + 0.5, truncated to 22 bits. Never 0 for a unit normal (the x bin is 0 only for
// n_x < -1 + 2^-13, which flips).
constexpr float kCoplanarSign[3] = {0.5773502f, 0.6172134f, 0.5345225f};
constexpr float kCoplanarBins = 4096.0f;

inline uint64_t coplanar_key(const float v0[3], float x, float y, float z, float inv_step) {
    const float s = kCoplanarSign[0] * x + kCoplanarSign[1] * y + kCoplanarSign[2] * z;
    const float sign = s < 0.0f ? -1.0f : 1.0f;
    const float n[3] = {x * sign, y * sign, z * sign};
    const float d = v0[0] * n[0] + v0[1] * n[1] + v0[2] * n[2];
    const float half = kCoplanarBins + 0.5f;
    // (branch-free, int32 conversions; a value out of range, or a NaN, whose conversion is
    // undefined, keys as 0 bits)
    auto bin = [](float v, float top) { return uint64_t(uint32_t(int32_t(v >= 0.0f && v < top ? v : 0.0f))); };
    return bin(n[0] * kCoplanarBins + half, 16384.0f) << 50 | bin(n[1] * kCoplanarBins + half, 16384.0f) << 36 |
           bin(n[2] * kCoplanarBins + half, 16384.0f) << 22 |
           // (out of range only past 2^21 steps from 0: the caller's step keeps |d| / step below)
           bin(d * inv_step + 2097152.5f, 4194304.0f);  // 2^21 + 0.5
}

// The triangles (rows, ascending within a group) of every plane key (keys: coplanar_key of each
// of the M triangles, from triangle_table) repeated by candidates (M entries, nonzero: a
// candidate; the others count as keyless) among the M triangles (indices tri, M rows of 3; geo
// the table, its normal rows read for the quad test), grouped: group g is rows[start[g]:start[g +
// 1]] (start ends with rows.size()). A quad's two triangles listed one after the other (i, i + 1
// candidates of one key sharing an edge by index, run one way by one and the other way by the
// other, facing one way; the first of a chain of such pairs) count as one: a quad alone in its
// plane is no group, and its second triangle joins its first's group. Groups of more than
// max_group triangles are left out. Keys are hashed and partitioned by thread, each partition's
// repeats found in a table that fits in cache; results do not depend on the thread count.
void coplanar_groups(const uint64_t* keys, const float* geo, size_t M, const int32_t* tri, const uint8_t* candidates,
                     size_t max_group, std::vector<int64_t>& rows, std::vector<int64_t>& start);

// out[i] (M entries): for the candidates (nonzero), coplanar_key of the table's rows (geo, 15 x M)
// on the grid shifted by half a bin in every component (the normal's bins + 0.5, the offset's +
// 0.5), 0 where a component falls out of range or is NaN; 0 for the others (shiftedkeys.cpp).
void shifted_plane_keys(const float* geo, size_t M, const uint8_t* candidates, float inv_step, uint64_t* out);

}  // namespace dacrt
