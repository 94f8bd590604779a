// Ray records from structure-of-arrays origins and directions (see shading.h).
#include "parallel.h"
#include "shading.h"

namespace dacrt {

void pack_rays(const float* O, const float* D, const float* tfar, size_t n, Ray* out) {
    parallel_for(n, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            Ray& r = out[i];
            for (int a = 0; a < 3; ++a) {
                r.org[a] = O[a * n + i];
                r.dir[a] = D[a * n + i];
            }
            r.tfar = tfar[i];
            r.id = uint32_t(i);
        }
    }, size_t(1) << 17);
}

}  // namespace dacrt
