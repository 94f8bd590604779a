// SIMD check of the ray fields (finite origin and direction, non-zero direction, tfar >= 0 or
// +inf), the largest |origin coordinate| and whether a direction component is one the box
// test's reciprocal cannot take (filter.h), W rays per step with the filter's transposed loads.
// Also whether the ids run first_id, first_id + 1, ... in order, as every batch the renderer
// and the benchmarks build does: then no id needs marking (ray.cpp). The exact message for a
// bad ray and the general id check are in ray.cpp (scalar, cold/cheap).
// Included inside an ISA namespace.
#pragma once

template <int W>
bool fields_valid_w(const Ray* rays, size_t n, BatchInfo& info) {
    const vfloat<W> zero = splat<W>(0.0f);
    const vbool<W> all = cmpeq(zero, zero);
    vbool<W> ok_all = all, odd = andnot(all, all);
    vfloat<W> oam = zero;
    const Ray pad{{0, 0, 0}, {1, 0, 0}, 0.0f, 0};  // a valid ray
    uint32_t id_diff = 0;  // OR of (id ^ expected id): 0 when the ids are in order
    for (size_t i = 0; i < n; i += W) {
        vfloat<W> r[8];
        load_block<W>(rays, i, n, pad, r);
        const size_t m = n - i < size_t(W) ? n - i : size_t(W);  // the records just loaded, in L1
        for (size_t l = 0; l < m; ++l) id_diff |= rays[i + l].id ^ uint32_t(info.first_id + i + l);
        // x - x is exactly 0 for finite x and NaN for inf/NaN: one compare for six fields.
        const vfloat<W> z = ((r[0] - r[0]) + (r[1] - r[1])) + ((r[2] - r[2]) + (r[3] - r[3])) +
                            ((r[4] - r[4]) + (r[5] - r[5]));
        const vbool<W> zero_dir = cmpeq(r[3], zero) & cmpeq(r[4], zero) & cmpeq(r[5], zero);
        ok_all = ok_all & cmpeq(z, zero) & cmple(zero, r[6]) & andnot(zero_dir, all);
        oam = vmax(oam, vmax(vabs(r[0]), vmax(vabs(r[1]), vabs(r[2]))));
        for (int a = 3; a < 6; ++a) {  // nonzero below 2^-126 (denormal), or above 2^125
            const vfloat<W> ad = vabs(r[a]);
            odd = odd | (cmplt(zero, ad) & cmplt(ad, splat<W>(0x1p-126f))) | cmplt(splat<W>(0x1p125f), ad);
        }
    }
    alignas(64) float m[W];
    storeu(m, oam);
    float best = 0.0f;
    for (int l = 0; l < W; ++l) best = m[l] > best ? m[l] : best;
    info.origin_abs_max = best;
    info.odd_dirs = bits(odd) != 0;
    info.ids_in_order = id_diff == 0 && info.first_id + n <= size_t(UINT32_MAX) + 1;
    return bits(ok_all) == bits(all);
}
