// Validation of a caller's ray batch (see ray_check.h): every ray is checked before any is
// touched, so a rejected call leaves the array exactly as it was.
#include "ray_check.h"

#include <cmath>
#include <sstream>

namespace dacrt {

static std::string vec(const float* v) {
    std::ostringstream s;
    s << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
    return s.str();
}

// Mark: the slot type of the output array used to detect repeated ids.
template <class Mark>
static std::string validate(const Ray* rays, size_t n, char* marks, size_t stride, Mark unseen, Mark seen,
                            float& origin_abs_max) {
    origin_abs_max = 0.0f;
    for (size_t k = 0; k < n; ++k) *reinterpret_cast<Mark*>(marks + k * stride) = unseen;
    for (size_t k = 0; k < n; ++k) {
        const Ray& r = rays[k];
        for (int a = 0; a < 3; ++a) {
            if (!std::isfinite(r.org[a])) return "rays[" + std::to_string(k) + "].org is not finite: " + vec(r.org);
            if (!std::isfinite(r.dir[a])) return "rays[" + std::to_string(k) + "].dir is not finite: " + vec(r.dir);
            origin_abs_max = std::fmax(origin_abs_max, std::fabs(r.org[a]));
        }
        if (r.dir[0] == 0.0f && r.dir[1] == 0.0f && r.dir[2] == 0.0f)
            return "rays[" + std::to_string(k) + "].dir is the zero vector";
        if (std::isnan(r.tfar)) return "rays[" + std::to_string(k) + "].tfar is NaN";
        if (r.tfar < 0.0f) return "rays[" + std::to_string(k) + "].tfar is negative (" + std::to_string(r.tfar) + ")";
        if (r.id >= n)
            return "rays[" + std::to_string(k) + "].id = " + std::to_string(r.id) + " is out of range: ids must be 0.." +
                   std::to_string(n - 1) + " (a permutation of the ray indices)";
        Mark& m = *reinterpret_cast<Mark*>(marks + size_t(r.id) * stride);
        if (m != unseen) return "rays[" + std::to_string(k) + "].id = " + std::to_string(r.id) + " is repeated: ids must be unique";
        m = seen;
    }
    return {};
}

std::string validate_rays(const Ray* rays, size_t n, Hit* hits, float& origin_abs_max) {
    std::string err = validate<int32_t>(rays, n, reinterpret_cast<char*>(&hits[0].prim), sizeof(Hit), -2, -1, origin_abs_max);
    if (err.empty())
        for (size_t k = 0; k < n; ++k) hits[k] = Hit{INFINITY, -1, 0.0f, 0.0f};
    return err;
}

std::string validate_rays(const Ray* rays, size_t n, uint8_t* occluded, float& origin_abs_max) {
    return validate<uint8_t>(rays, n, reinterpret_cast<char*>(occluded), 1, 2, 0, origin_abs_max);
}

}  // namespace dacrt
