// camera_rays (shading.h) for a camera whose rotation is sheared: a camera under a rotated,
// non-uniformly scaled parent, whose matrix Cycles keeps with its columns normalised but not
// orthogonal. camera_rays' orthonormal mapping would put the clip on the sheared image of the
// clip planes and leave directions of other than unit length.
#pragma once

#include <cstddef>

#include "shading.h"

namespace dacrt {

// As camera_rays, with Cycles' mapping of a sheared matrix: each world direction normalised
// after the matrix; a perspective camera's clip start and range (camera-space depths, divided
// by the pinhole direction's d_cam.z) laid along it from the pinhole or lens point, an
// orthographic camera's origins the matrix's image of its camera-space points and its clip
// range measured along the unit direction.
void sheared_camera_rays(const CameraFrame& c, const float* rx, const float* ry, size_t n, float* O, float* D,
                         float* tmax, Ray* rays = nullptr, const float* lu = nullptr, const float* lv = nullptr);

}  // namespace dacrt
