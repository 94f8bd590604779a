// The equirectangular mapping of many directions at once (equirect.h's to_uv per lane),
// compiled per instruction set in envlanes.cpp: environment_gather's rays that missed.
#pragma once

#include <cstddef>

namespace dacrt {

// For j < m: the world direction (dx, dy, dz)[j] turned by to_map (row-major 3x3), its (u, v)
// and sin(theta), or sin_theta -1 where the direction has no length (zero or not finite).
void equirect_uv_lanes(const float to_map[9], const float* dx, const float* dy, const float* dz, size_t m,
                       float* u, float* v, float* sin_theta);

}  // namespace dacrt
