// Validation of a caller's ray batch (see ray_check.h): every ray is checked before any is
// touched, so a rejected call leaves the array exactly as it was.
#include "ray_check.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace dacrt {

static std::string vec(const float* v) {
    std::ostringstream s;
    s << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
    return s.str();
}

static bool finite(float x) {
    uint32_t b;
    std::memcpy(&b, &x, 4);
    return (b & 0x7f800000u) != 0x7f800000u;
}

// The problem with ray k, or an empty string if its fields are fine and `repeated` is false.
__attribute__((noinline, cold)) static std::string describe(const Ray* rays, size_t n, size_t k, bool repeated) {
    const Ray& r = rays[k];
    const std::string at = "rays[" + std::to_string(k) + "]";
    for (int a = 0; a < 3; ++a)
        if (!finite(r.org[a])) return at + ".org is not finite: " + vec(r.org);
    for (int a = 0; a < 3; ++a)
        if (!finite(r.dir[a])) return at + ".dir is not finite: " + vec(r.dir);
    if (r.dir[0] == 0.0f && r.dir[1] == 0.0f && r.dir[2] == 0.0f) return at + ".dir is the zero vector";
    if (std::isnan(r.tfar)) return at + ".tfar is NaN";
    if (r.tfar < 0.0f) return at + ".tfar is negative (" + std::to_string(r.tfar) + ")";
    if (r.id >= n)
        return at + ".id = " + std::to_string(r.id) + " is out of range: ids must be 0.." + std::to_string(n - 1) +
               " (a permutation of the ray indices)";
    if (!repeated) return {};
    return at + ".id = " + std::to_string(r.id) + " is repeated: ids must be unique";
}

// Fields by the ISA's SIMD check, then ids against the marks; a message is built only after a
// failure (the scalar scan then names the first bad ray).
template <class Mark>
static std::string validate(const Ray* rays, size_t n, char* marks, size_t stride, Mark unseen, Mark seen,
                            FieldsFn fields, float& origin_abs_max) {
    if (!fields(rays, n, origin_abs_max))
        for (size_t k = 0; k < n; ++k) {
            std::string msg = describe(rays, n, k, false);
            if (!msg.empty()) return msg;
        }
    for (size_t k = 0; k < n; ++k) {
        const uint32_t id = rays[k].id;
        if (id >= n) return describe(rays, n, k, false);
        Mark& m = *reinterpret_cast<Mark*>(marks + size_t(id) * stride);
        if (m != unseen) return describe(rays, n, k, true);
        m = seen;
    }
    return {};
}

std::string validate_rays(const Ray* rays, size_t n, Hit* hits, FieldsFn fields, float& origin_abs_max) {
    for (size_t k = 0; k < n; ++k) hits[k] = Hit{INFINITY, -2, 0.0f, 0.0f};
    return validate<int32_t>(rays, n, reinterpret_cast<char*>(&hits[0].prim), sizeof(Hit), -2, -1, fields,
                             origin_abs_max);
}

std::string validate_rays(const Ray* rays, size_t n, uint8_t* occluded, FieldsFn fields, float& origin_abs_max) {
    std::memset(occluded, 2, n);
    return validate<uint8_t>(rays, n, reinterpret_cast<char*>(occluded), 1, 2, 0, fields, origin_abs_max);
}

}  // namespace dacrt
