// Ray records from structure-of-arrays origins and directions (see shading.h).
#include "parallel.h"
#include "raylanes.h"
#include "shading.h"

namespace dacrt {

void pack_rays(const float* O, const float* D, const float* tfar, size_t n, Ray* out) {
    parallel_for(n, [&](size_t b, size_t e) { ray_records_lanes(O, D, n, b, e, tfar, 0.0f, out); }, size_t(1) << 17);
}

}  // namespace dacrt
