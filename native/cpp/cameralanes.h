// The lane loop of camera_rays (camera.cpp) for the common camera, a pinhole without depth of
// field, compiled per instruction set in cameralanes.cpp.
#pragma once

#include <cstddef>

#include "shading.h"

namespace dacrt {

// camera_rays' pinhole mapping of raster positions (rx, ry)[i], b <= i < e: origins O, unit
// directions D (3 rows, stride n) and tmax, the scalar loop's operations per lane.
void pinhole_lanes(const CameraFrame& c, const float* rx, const float* ry, size_t b, size_t e, size_t n, float* O,
                   float* D, float* tmax);

}  // namespace dacrt
