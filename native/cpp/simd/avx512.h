// AVX-512 16-wide vectors with mask registers. Included inside namespace dacrt::avx512.
#pragma once
#include "simd/avx2.h"  // the 8-wide types and declarations

template <> struct vbool<16> { __mmask16 m; };
template <> struct vfloat<16> { __m512 v; };
template <> struct vint<16> { __m512i v; };
using vb16 = vbool<16>; using vf16 = vfloat<16>; using vi16 = vint<16>;

inline uint32_t bits(vb16 a) { return uint32_t(a.m); }
inline bool any(vb16 a) { return a.m != 0; }
inline vb16 operator&(vb16 a, vb16 b) { return {__mmask16(a.m & b.m)}; }
inline vb16 operator|(vb16 a, vb16 b) { return {__mmask16(a.m | b.m)}; }
inline vb16 andnot(vb16 a, vb16 b) { return {__mmask16(~a.m & b.m)}; }
template <> inline vb16 from_bits<16>(uint32_t m) { return {__mmask16(m)}; }

template <> inline vf16 splat<16>(float x) { return {_mm512_set1_ps(x)}; }
template <> inline vf16 loadu<16>(const float* p) { return {_mm512_loadu_ps(p)}; }
inline void storeu(float* p, vf16 a) { _mm512_storeu_ps(p, a.v); }
inline vf16 operator+(vf16 a, vf16 b) { return {_mm512_add_ps(a.v, b.v)}; }
inline vf16 operator-(vf16 a, vf16 b) { return {_mm512_sub_ps(a.v, b.v)}; }
inline vf16 operator*(vf16 a, vf16 b) { return {_mm512_mul_ps(a.v, b.v)}; }
inline vf16 operator/(vf16 a, vf16 b) { return {_mm512_div_ps(a.v, b.v)}; }
inline vf16 vmin(vf16 a, vf16 b) { return {_mm512_min_ps(a.v, b.v)}; }
inline vf16 vmax(vf16 a, vf16 b) { return {_mm512_max_ps(a.v, b.v)}; }
inline vf16 rcp(vf16 a) { return {_mm512_rcp14_ps(a.v)}; }  // |rel err| <= 2^-14, +-0 -> +-inf
// Lanes where inv = rcp(a) may be no reciprocal of a nonzero a: a denormal (rcp14 is +-inf
// below ~2^-128; for large |a| its denormal results keep ~2^-14 precision).
inline vb16 rcp_unusable(vf16 a, vf16) { return {_mm512_fpclass_ps_mask(a.v, 0x20)}; }
inline vf16 vabs(vf16 a) { return {_mm512_abs_ps(a.v)}; }
inline vb16 cmplt(vf16 a, vf16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ)}; }
inline vb16 cmple(vf16 a, vf16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ)}; }
inline vb16 cmpeq(vf16 a, vf16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ)}; }
inline vb16 cmpunord(vf16 a, vf16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_UNORD_Q)}; }
inline vf16 select(vb16 m, vf16 a, vf16 b) { return {_mm512_mask_blend_ps(m.m, b.v, a.v)}; }
inline vf16 nan_where(vb16 m, vf16 a) { return {_mm512_mask_mov_ps(a.v, m.m, _mm512_set1_ps(NAN))}; }
inline vf16 xorsign(vf16 a, vf16 s) {
    return {_mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a.v),
            _mm512_and_si512(_mm512_castps_si512(s.v), _mm512_set1_epi32(int(0x80000000u)))))};
}

template <> inline vi16 splati<16>(int32_t x) { return {_mm512_set1_epi32(x)}; }
inline vb16 cmpeqi(vi16 a, vi16 b) { return {_mm512_cmpeq_epi32_mask(a.v, b.v)}; }
inline vi16 selecti(vb16 m, vi16 a, vi16 b) { return {_mm512_mask_blend_epi32(m.m, b.v, a.v)}; }
inline void storei(int32_t* p, vi16 a) { _mm512_storeu_si512(p, a.v); }
template <> inline vi16 loadi<16>(const int32_t* p) { return {_mm512_loadu_si512(p)}; }
inline vf16 permute(const float* table4, vi16 idx) {
    return {_mm512_permutexvar_ps(idx.v, _mm512_castps128_ps512(_mm_loadu_ps(table4)))};
}

// 16 records -> 8 vectors in 24 shuffles: the AVX2 in-lane transpose stages applied to zmm
// rows that each hold two records, then one two-source permute per field restores ray order.
// z[k] holds records 2k and 2k + 1.
inline void transpose16(const __m512 z[8], vf16 out[8]) {
    __m512 t[8], s[8];
    for (int h = 0; h < 2; ++h) {
        const int b = 4 * h;
        t[b + 0] = _mm512_unpacklo_ps(z[b + 0], z[b + 1]); t[b + 1] = _mm512_unpackhi_ps(z[b + 0], z[b + 1]);
        t[b + 2] = _mm512_unpacklo_ps(z[b + 2], z[b + 3]); t[b + 3] = _mm512_unpackhi_ps(z[b + 2], z[b + 3]);
        s[b + 0] = _mm512_shuffle_ps(t[b + 0], t[b + 2], 0x44); s[b + 1] = _mm512_shuffle_ps(t[b + 0], t[b + 2], 0xEE);
        s[b + 2] = _mm512_shuffle_ps(t[b + 1], t[b + 3], 0x44); s[b + 3] = _mm512_shuffle_ps(t[b + 1], t[b + 3], 0xEE);
    }
    const __m512i lo = _mm512_setr_epi32(0, 8, 1, 9, 2, 10, 3, 11, 16, 24, 17, 25, 18, 26, 19, 27);
    const __m512i hi = _mm512_add_epi32(lo, _mm512_set1_epi32(4));
    for (int f = 0; f < 4; ++f) {
        out[f].v = _mm512_permutex2var_ps(s[f], lo, s[f + 4]);
        out[f + 4].v = _mm512_permutex2var_ps(s[f], hi, s[f + 4]);
    }
}
template <> inline void load_rays<16>(const float* rec, vf16 out[8]) {
    __m512 z[8];
    for (int k = 0; k < 8; ++k) z[k] = _mm512_loadu_ps(rec + 16 * k);
    transpose16(z, out);
}
// Masked loads: the tail is read in place (lanes past it never touch memory) over the pad.
template <> inline void load_rays_tail<16>(const float* rec, size_t k, const float* pad, vf16 out[8]) {
    const __m512 p = _mm512_broadcast_f32x8(_mm256_loadu_ps(pad));
    const size_t floats = 8 * k;
    __m512 z[8];
    for (size_t j = 0; j < 8; ++j) {
        const size_t f0 = 16 * j;
        const __mmask16 m = floats >= f0 + 16 ? __mmask16(0xFFFF)
                            : floats <= f0 ? __mmask16(0) : __mmask16((1u << (floats - f0)) - 1u);
        z[j] = _mm512_mask_loadu_ps(p, m, rec + f0);
    }
    transpose16(z, out);
}
