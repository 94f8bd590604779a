// A light-tree stop's eight lanes weighed at one point (lighttree.h, LightTree::Stop), in
// float, side by side: most of a many-light render's light sampling. Compiled once per
// instruction set (treelanes.cpp) with every lane's operations in the same order, so that each
// gives the same bits.
#pragma once

#include "lighttree.h"

namespace dacrt {

// The point a walk down the tree weighs its stops at, with what every stop would otherwise
// work out again from it: |N| (the box's spread toward the tangent plane) and max |P_k| (the
// back-face test's margin).
struct TreePoint {
    float P[3];
    const float* N;  // unit receiving normal, or null: none
    float abs_n[3];  // |N_k| (with N)
    float pm;        // max_k |P_k|
};
// Fills t in place, field by field: a TreePoint built aside and copied into a walk group's
// array was reloaded as 16-byte words over the 4- and 8-byte stores that had just built it,
// which the CPU cannot forward (those copies held ~19% of sample_group's perf samples; the
// walk's chain still waits as long, now in the lanes: README, manylights2).
void tree_point(TreePoint& t, const float P[3], const float* N);

// imp[k]: lane k's importance at the point (energy x incidence and emission cosines / squared
// distance, lighttree.cpp weigh(), 0 where culled), imin[k] its smallest (weigh()'s min). Returns, per four lanes (bit 0: lanes 0-3,
// bit 1: lanes 4-7), whether some lane's squared distance lies outside [1e-30, 1e30] or is NaN:
// those four must be weighed in float64 (their imp is left to the caller).
using StopWeighFn = int (*)(const LightTree::Stop& q, const TreePoint& at, double imp[8], double imin[8]);

// The widest kernel the CPU runs, or a narrower one DACRT_ISA names (portable, avx2).
StopWeighFn stop_weigh_fn();

// Points side by side, a row per coordinate (N[0] null: no normals), each row readable for a
// whole number of 16 past the points it holds. TreePoint's |N_k| and max |P_k| the lanes work
// out from these (exact: the same bits), so that a walk copies six rows per stop, not ten.
struct TreeRows {
    const float* P[3];
    const float* N[3];
};
// Lane k of stop q weighed at the rows' points [0, m), as StopWeighFn weighs it at each (the
// same bits): g[i] the weigh before the lane's energy (gmin[i] its smallest), ok[i] (-1 or 0) whether the lane's
// distances lie in float's range at point i (else its four go to float64). g and ok are
// written for a whole number of 16 past m.
using LaneRowsFn = void (*)(const LightTree::Stop& q, int k, const TreeRows& rows, size_t m, float* g, float* gmin,
                            int32_t* ok);
LaneRowsFn lane_rows_fn();

namespace avx512 {  // the AVX-512 copies (treelanes_avx512.cpp), for lane_copy
int tree_weigh(const LightTree::Stop& q, const TreePoint& at, double imp[8], double imin[8]);
void tree_rows(const LightTree::Stop& q, int k, const TreeRows& rows, size_t m, float* g, float* gmin, int32_t* ok);
}  // namespace avx512

}  // namespace dacrt
