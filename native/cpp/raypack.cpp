// Ray records from structure-of-arrays origins and directions (see shading.h).
#include "parallel.h"
#include "pathvertex.h"
#include "shading.h"

namespace dacrt {

void pack_rays(const float* O, const float* D, const float* tfar, size_t n, Ray* out) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) ray_record(O, D, n, i, tfar[i], out[i]);
    }, size_t(1) << 17);
}

}  // namespace dacrt
