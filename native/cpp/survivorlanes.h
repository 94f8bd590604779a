// survivor_range's common case in lanes: the survivors' throughputs and hit points (rows P,
// ng, P_off, ns) from their triangles' hit-point records (hitrecords.h), kSurvivorLanes
// survivors at a time (survivorlanes.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include "ray.h"

namespace dacrt {

constexpr size_t kSurvivorLanes = 16;

// survivor_range's survivors b, b + 1, ... in whole groups of kSurvivorLanes up to e, their hit
// points from records (smooth: with corner normals); returns the first survivor not done (the
// caller runs the rest one at a time). The same bits as survivor_range per survivor.
size_t survivor_lanes(const Hit* hits, size_t n, const float* albedo, size_t M, const float* thr, bool roulette,
                      const int64_t* idx, size_t k, float* thr_out, const float* records, bool smooth,
                      const float* D, float* surf_out, int32_t* prim_out, size_t b, size_t e);

}  // namespace dacrt
