// The lane loop of cosine_scatter (scatter.cpp): cosine-weighted directions for a chunk of
// sample words, compiled per instruction set in scatterlanes.cpp.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dacrt {

// Malley directions around the unit shading normals (nx, ny, nz)[j] from the words wa[j],
// wb[j], j < m: wi (wx, wy, wz), their pdf (cos / pi) and ok: pdf > 0 and, with geometric
// normals (gx, gy, gz; null: none), above the geometric surface. malley()'s bits per lane.
void scatter_lanes(const uint32_t* wa, const uint32_t* wb, size_t m, const float* nx, const float* ny,
                   const float* nz, const float* gx, const float* gy, const float* gz, float* wx, float* wy,
                   float* wz, float* pdf, uint8_t* ok);

}  // namespace dacrt
