// The rays of a batch reordered so that each of its chunks (dispatch.cpp) holds the rays whose
// origins lie in one region of space (the paper's pre-sorting, coarsely).
#pragma once
#include <cstddef>

#include "ray.h"

namespace dacrt {

// Reorders rays[0, n) into `parts` groups of nearly equal size, each the rays whose origins
// fall in one cell of a recursive median bisection of the origins (widest axis each time,
// judged on sampled rays). Leaves the rays as they are when the sampled origins coincide.
// True if it cut the rays at least once.
bool order_by_origin(Ray* rays, size_t n, size_t parts);

}  // namespace dacrt
