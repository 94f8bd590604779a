// The tracer's ray records (ray.h) written from (3, n) origin and direction columns 8 rays a
// step: the columns' 8 floats of each field loaded as rows and transposed in registers into 8
// whole 32-byte records (raylanes.cpp).
#pragma once

#include <cstddef>

#include "ray.h"

namespace dacrt {

// rays[i] = (O[:, i], D[:, i], tfar ? tfar[i] : tfar_all, i) for b <= i < e: pathvertex.h's
// ray_record per ray, the same bits (the fields are moved, never computed).
void ray_records_lanes(const float* O, const float* D, size_t n, size_t b, size_t e, const float* tfar,
                       float tfar_all, Ray* rays);

}  // namespace dacrt
