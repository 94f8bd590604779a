// Validation of a caller's ray batch (see ray_check.h): every ray is checked before any is
// touched, so a rejected call leaves the array exactly as it was.
#include "ray_check.h"
#include "parallel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
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
    if (r.tfar < 0.0f) {  // shortest round-trip digits: std::to_string's %f showed -1e-7 as "-0.000000"
        std::ostringstream s;
        s.precision(9);
        s << r.tfar;
        return at + ".tfar is negative (" + s.str() + ")";
    }
    if (r.id >= n)
        return at + ".id = " + std::to_string(r.id) + " is out of range: ids must be 0.." + std::to_string(n - 1) +
               " (a permutation of the ray indices)";
    if (!repeated) return {};
    return at + ".id = " + std::to_string(r.id) + " is repeated: ids must be unique";
}

// Fields by the ISA's SIMD check, then ids against the marks; a message is built only after a
// failure (the scalar scan then names the first bad ray).
template <class Mark>
static std::string validate_serial(const Ray* rays, size_t n, char* marks, size_t stride, Mark unseen, Mark seen,
                                   FieldsFn fields, BatchInfo& info) {
    if (!fields(rays, n, info))
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

// The same check, in one pass when the ids are in order (ray k has id k, as in every batch
// the renderer and the benchmarks build): the output is initialised straight to its marked
// state while the fields are checked, and ids in order are trivially a permutation. Otherwise
// on several threads (a big batch's serial validation was ~7% of its trace call on 2
// threads): output initialisation, then every id marks its slot, then every slot must be
// marked. n ids below n are unique exactly when all n slots end up marked, so the marking
// needs no read-modify-write: concurrent (relaxed atomic) stores of the same value cannot
// hide a repeated id, which always leaves some slot unmarked. Any failure reruns the serial
// check for its exact message. init(b, e, mark) sets the outputs of [b, e) to mark.
template <class Mark, class Init>
static std::string validate(const Ray* rays, size_t n, char* marks, size_t stride, Mark unseen, Mark seen,
                            FieldsFn fields, BatchInfo& info, int threads, Init init) {
    constexpr size_t kMinPerThread = 1 << 15;
    auto slot = [&](size_t id) { return reinterpret_cast<Mark*>(marks + id * stride); };
    std::atomic<bool> fields_ok{true}, ids_ok{true};
    std::mutex m;
    BatchInfo all;
    parallel_for(n, [&](size_t b, size_t e) {
        init(b, e, seen);
        BatchInfo part;
        part.first_id = b;
        if (!fields(rays + b, e - b, part)) fields_ok.store(false, std::memory_order_relaxed);
        std::lock_guard<std::mutex> g(m);
        all.merge(part);
    }, kMinPerThread, threads);
    if (fields_ok.load() && all.ids_in_order) {
        info = all;
        return {};
    }
    parallel_for(n, [&](size_t b, size_t e) { init(b, e, unseen); }, kMinPerThread, threads);
    if (!fields_ok.load() || threads == 1 || threads_for(n, kMinPerThread) <= 1)
        return validate_serial(rays, n, marks, stride, unseen, seen, fields, info);
    parallel_for(n, [&](size_t b, size_t e) {
        bool ok = true;
        for (size_t k = b; k < e; ++k) {
            const uint32_t id = rays[k].id;
            if (id >= n) { ok = false; continue; }
            __atomic_store_n(slot(id), seen, __ATOMIC_RELAXED);
        }
        if (!ok) ids_ok.store(false, std::memory_order_relaxed);
    }, kMinPerThread, threads);
    if (ids_ok.load()) {
        parallel_for(n, [&](size_t b, size_t e) {
            bool ok = true;
            for (size_t k = b; k < e; ++k) ok &= *slot(k) == seen;
            if (!ok) ids_ok.store(false, std::memory_order_relaxed);
        }, kMinPerThread, threads);
    }
    if (ids_ok.load()) {
        info = all;
        return {};
    }
    parallel_for(n, [&](size_t b, size_t e) { init(b, e, unseen); }, kMinPerThread, threads);  // unmark
    return validate_serial(rays, n, marks, stride, unseen, seen, fields, info);
}

std::string validate_rays(const Ray* rays, size_t n, Hit* hits, FieldsFn fields, BatchInfo& info, int threads) {
    auto init = [hits](size_t b, size_t e, int32_t mark) {
        for (size_t k = b; k < e; ++k) hits[k] = Hit{INFINITY, mark, 0.0f, 0.0f};
    };
    return validate<int32_t>(rays, n, reinterpret_cast<char*>(&hits[0].prim), sizeof(Hit), -2, -1, fields,
                             info, threads, init);
}

std::string validate_rays(const Ray* rays, size_t n, uint8_t* occluded, FieldsFn fields, BatchInfo& info,
                          int threads) {
    auto init = [occluded](size_t b, size_t e, uint8_t mark) { std::memset(occluded + b, mark, e - b); };
    return validate<uint8_t>(rays, n, reinterpret_cast<char*>(occluded), 1, 2, 0, fields, info, threads,
                             init);
}

}  // namespace dacrt
