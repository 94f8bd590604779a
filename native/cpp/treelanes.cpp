// A light-tree stop's lanes weighed side by side (treelanes.h), as named copies per instruction
// set (as noise.cpp) so that DACRT_ISA can pick a narrower one and tests compare them on one
// machine. The portable copy holds the eight lanes as two SSE vectors of four; the AVX2 and
// AVX-512 copies as one 256-bit vector, half the instructions (target_probs was 14.5% of a
// many-light render); the AVX-512 rows sixteen points at a time (treelanes_avx512.cpp). Per lane
// the operations and their order are the same in every copy (treeweigh.h), and
// -ffp-contract=off: every copy gives the same bits.
#include "treelanes.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "dispatch.h"

#pragma GCC diagnostic ignored "-Wpsabi"  // 32-byte vectors only ever inlined into AVX code

namespace dacrt {

namespace {

#include "treeweigh.h"

DACRT_TREE_ISA(portable, , F8, M8, F8, M8)
DACRT_TREE_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))), W8, WM8, W8, WM8)

}  // namespace

void tree_point(TreePoint& t, const float P[3], const float* N) {
    for (int k = 0; k < 3; ++k) t.P[k] = P[k], t.abs_n[k] = N ? std::fabs(N[k]) : 0.0f;
    t.N = N;
    t.pm = std::max({std::fabs(P[0]), std::fabs(P[1]), std::fabs(P[2])});
}

StopWeighFn stop_weigh_fn() { return lane_copy<StopWeighFn>(portable_weigh, avx2_weigh, avx512::tree_weigh); }

LaneRowsFn lane_rows_fn() { return lane_copy<LaneRowsFn>(portable_rows, avx2_rows, avx512::tree_rows); }

}  // namespace dacrt
