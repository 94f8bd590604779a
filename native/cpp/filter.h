// Ray filtering (Afra 2012): partition the ray records in place into rays that hit the current
// triangle set's box within [0, tfar] (moved to the front) and the rest. Whole 32-byte records
// move, never an index array: later passes then read memory linearly. W rays per box test,
// AoS -> SoA by loads and shuffles. Included inside an ISA namespace.
#pragma once

// Robust slab test. No reciprocal is stored: 1/d is computed in registers (an IEEE division, so
// all ISAs agree). Zero direction components give +-inf, and 0 * inf = NaN when the origin lies
// on a slab plane; such a slab is marked NaN and ignored by the NaN-ordered max/min, so a ray
// that runs inside a plane of the box is kept. The exit distance is widened by 1 + 2*gamma(3)
// (Ize 2013) so rounding never culls a ray that hits the exact box.
template <int W>
inline vbool<W> box_test(const vfloat<W> r[8], const float lo[3], const float hi[3]) {
    constexpr float kGamma3x2 = 2.0f * (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);
    vfloat<W> tmin = splat<W>(0.0f), tmax = r[6];
    for (int a = 0; a < 3; ++a) {
        const vfloat<W> inv = splat<W>(1.0f) / r[3 + a];
        const vfloat<W> t0 = (splat<W>(lo[a]) - r[a]) * inv;
        const vfloat<W> t1 = (splat<W>(hi[a]) - r[a]) * inv;
        const vbool<W> nan = cmpunord(t0, t1);
        tmin = vmax(nan_where(nan, vmin(t0, t1)), tmin);  // NaN first operand -> tmin kept
        tmax = vmin(nan_where(nan, vmax(t0, t1)), tmax);
    }
    return cmple(tmin, tmax * splat<W>(1.0f + kGamma3x2));
}

inline void swap_records(Ray* a, Ray* b) {
    Ray t;
    std::memcpy(&t, a, sizeof(Ray));
    std::memcpy(a, b, sizeof(Ray));
    std::memcpy(b, &t, sizeof(Ray));
}

// Returns the number of active rays, now rays[0, result). dir_votes[a] counts active rays going
// +a minus those going -a: the majority decides which child is visited first.
template <int W>
size_t filter_rays(Ray* rays, size_t n, const float lo[3], const float hi[3], int64_t dir_votes[3],
                   Stats& st) {
    st.box_tests += n;
    dir_votes[0] = dir_votes[1] = dir_votes[2] = 0;
    size_t w = 0;  // next slot for an active ray
    const uint32_t full = W == 32 ? 0xFFFFFFFFu : ((1u << W) - 1u);
    alignas(64) Ray tail[W];
    for (size_t i = 0; i < n; i += W) {
        vfloat<W> r[8];
        uint32_t valid = full;
        if (i + W <= n) {
            load_rays<W>(reinterpret_cast<const float*>(rays + i), r);
        } else {  // last partial block: pad with rays that can never be active
            const size_t k = n - i;
            std::memcpy(tail, rays + i, k * sizeof(Ray));
            for (size_t j = k; j < size_t(W); ++j) tail[j] = Ray{{0, 0, 0}, {1, 0, 0}, kOccludedTfar, 0};
            load_rays<W>(reinterpret_cast<const float*>(tail), r);
            valid = (1u << k) - 1u;
        }
        const vbool<W> act = box_test<W>(r, lo, hi) & from_bits<W>(valid);
        uint32_t m = bits(act);
        for (int a = 0; a < 3; ++a) {
            const vfloat<W> zero = splat<W>(0.0f);
            dir_votes[a] += __builtin_popcount(bits(cmplt(zero, r[3 + a]) & act)) -
                            __builtin_popcount(bits(cmplt(r[3 + a], zero) & act));
        }
        if (m == full && w == i) {  // whole block active and already in place
            w += W;
            continue;
        }
        while (m) {
            const size_t src = i + size_t(__builtin_ctz(m));
            m &= m - 1;
            if (src != w) swap_records(rays + src, rays + w);
            ++w;
        }
    }
    return w;
}
