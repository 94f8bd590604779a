// Loading W consecutive ray records into SIMD registers (SoA), the one step every pass over
// the ray array starts with (filter, leaf, validation). Included inside an ISA namespace.
#pragma once

template <int W>
constexpr uint32_t all_lanes() { return W == 32 ? 0xFFFFFFFFu : ((1u << W) - 1u); }

// Rays rays[i, min(i + W, n)) transposed into r[8]; lanes past n hold `pad`. Returns the mask
// of lanes holding real rays.
template <int W>
inline uint32_t load_block(const Ray* rays, size_t i, size_t n, const Ray& pad, vfloat<W> r[8]) {
    if (i + W <= n) {
        load_rays<W>(reinterpret_cast<const float*>(rays + i), r);
        return all_lanes<W>();
    }
    const size_t k = n - i;
    load_rays_tail<W>(reinterpret_cast<const float*>(rays + i), k, reinterpret_cast<const float*>(&pad), r);
    return (1u << k) - 1u;
}

// A padding ray no box test keeps and no triangle test accepts.
constexpr Ray kInactiveRay{{0, 0, 0}, {1, 0, 0}, kOccludedTfar, 0};
