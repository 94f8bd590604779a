// Building the per-triangle hit-point records (see hitrecords.h).
#include "hitrecords.h"

#include "parallel.h"

namespace dacrt {

void hit_records(const float* geo, size_t M, const float* normals, float* out) {
    parallel_for(M, [&](size_t b, size_t e) {
        for (size_t p = b; p < e; ++p) hit_record(geo, M, normals, p, out + kHitRecord * p);
    });
}

}  // namespace dacrt
