// AVX2 8-wide vectors (Afra's width). Included inside namespace dacrt::avx2.
#pragma once

template <int W> struct vbool;
template <int W> struct vfloat;
template <int W> struct vint;
template <> struct vbool<8> { __m256 m; };
template <> struct vfloat<8> { __m256 v; };
template <> struct vint<8> { __m256i v; };
using vb8 = vbool<8>; using vf8 = vfloat<8>; using vi8 = vint<8>;

inline uint32_t bits(vb8 a) { return uint32_t(_mm256_movemask_ps(a.m)); }
inline bool any(vb8 a) { return _mm256_movemask_ps(a.m) != 0; }
inline vb8 operator&(vb8 a, vb8 b) { return {_mm256_and_ps(a.m, b.m)}; }
inline vb8 operator|(vb8 a, vb8 b) { return {_mm256_or_ps(a.m, b.m)}; }
inline vb8 andnot(vb8 a, vb8 b) { return {_mm256_andnot_ps(a.m, b.m)}; }
template <int W> vbool<W> from_bits(uint32_t m);
template <> inline vb8 from_bits<8>(uint32_t m) {
    const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    const __m256i x = _mm256_and_si256(_mm256_set1_epi32(int(m)), bit);
    return {_mm256_castsi256_ps(_mm256_cmpeq_epi32(x, bit))};
}

template <int W> vfloat<W> splat(float x);
template <> inline vf8 splat<8>(float x) { return {_mm256_set1_ps(x)}; }
template <int W> vfloat<W> loadu(const float* p);
template <> inline vf8 loadu<8>(const float* p) { return {_mm256_loadu_ps(p)}; }
inline void storeu(float* p, vf8 a) { _mm256_storeu_ps(p, a.v); }
inline vf8 operator+(vf8 a, vf8 b) { return {_mm256_add_ps(a.v, b.v)}; }
inline vf8 operator-(vf8 a, vf8 b) { return {_mm256_sub_ps(a.v, b.v)}; }
inline vf8 operator*(vf8 a, vf8 b) { return {_mm256_mul_ps(a.v, b.v)}; }
inline vf8 operator/(vf8 a, vf8 b) { return {_mm256_div_ps(a.v, b.v)}; }
inline vf8 vmin(vf8 a, vf8 b) { return {_mm256_min_ps(a.v, b.v)}; }
inline vf8 vmax(vf8 a, vf8 b) { return {_mm256_max_ps(a.v, b.v)}; }
inline vf8 rcp(vf8 a) { return {_mm256_rcp_ps(a.v)}; }  // |rel err| <= 1.5 * 2^-12, +-0 -> +-inf
inline vf8 vabs(vf8 a) { return {_mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v)}; }
inline vb8 cmplt(vf8 a, vf8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)}; }
inline vb8 cmple(vf8 a, vf8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)}; }
inline vb8 cmpeq(vf8 a, vf8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_EQ_OQ)}; }
inline vb8 cmpunord(vf8 a, vf8 b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_UNORD_Q)}; }
// Lanes where inv = rcp(a) is no reciprocal of a nonzero a: a denormal (rcp_ps reads it as 0:
// +-inf) or |a| near 2^126 and above (its tiny result is flushed to 0). a * inv is then inf or
// 0, where it is ~1 for any other a and NaN for a = 0 (not flagged: ordered compare).
inline vb8 rcp_unusable(vf8 a, vf8 inv) {
    return {_mm256_cmp_ps(_mm256_set1_ps(0.5f), vabs(a * inv - vf8{_mm256_set1_ps(1.0f)}).v, _CMP_LE_OQ)};
}
inline vf8 select(vb8 m, vf8 a, vf8 b) { return {_mm256_blendv_ps(b.v, a.v, m.m)}; }
inline vf8 nan_where(vb8 m, vf8 a) { return {_mm256_or_ps(a.v, m.m)}; }  // all-ones bits are a NaN
inline vf8 xorsign(vf8 a, vf8 s) { return {_mm256_xor_ps(a.v, _mm256_and_ps(s.v, _mm256_set1_ps(-0.0f)))}; }

template <int W> vint<W> splati(int32_t x);
template <> inline vi8 splati<8>(int32_t x) { return {_mm256_set1_epi32(x)}; }
inline vb8 cmpeqi(vi8 a, vi8 b) { return {_mm256_castsi256_ps(_mm256_cmpeq_epi32(a.v, b.v))}; }
inline vi8 selecti(vb8 m, vi8 a, vi8 b) {
    return {_mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b.v), _mm256_castsi256_ps(a.v), m.m))};
}
inline void storei(int32_t* p, vi8 a) { _mm256_storeu_si256((__m256i*)p, a.v); }
template <int W> vint<W> loadi(const int32_t* p);
template <> inline vi8 loadi<8>(const int32_t* p) { return {_mm256_loadu_si256((const __m256i*)p)}; }
// table4[idx] per lane: the table in both 128-bit halves and an in-lane permute (vpermilps),
// not a cross-lane vpermps (3 uops with a throughput of one per 4 cycles on Zen 1, where the
// leaf test's nine per triangle outweighed its arithmetic; the same one uop on Intel).
inline vf8 permute(const float* table4, vi8 idx) {
    return {_mm256_permutevar_ps(_mm256_broadcast_ps(reinterpret_cast<const __m128*>(table4)), idx.v)};
}

// 8 records (rows[j]: record j's 8 floats) transposed into 8 field vectors, as the paper's
// shuffles: each record's halves are loaded into the 128-bit lanes where they end up (records
// j and j + 4 share a vector), so only in-lane unpacks and shuffles follow. Transposing whole
// rows took 8 cross-lane vperm2f128, 8 uops each on Zen 1.
inline void transpose_rows8(const float* const rows[8], vf8 out[8]) {
    for (int h = 0; h < 2; ++h) {  // fields 0-3, then 4-7
        __m256 r[4];
        for (int j = 0; j < 4; ++j)
            r[j] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(rows[j] + 4 * h)),
                                        _mm_loadu_ps(rows[j + 4] + 4 * h), 1);
        const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
        const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
        out[4 * h + 0].v = _mm256_shuffle_ps(t0, t2, 0x44); out[4 * h + 1].v = _mm256_shuffle_ps(t0, t2, 0xEE);
        out[4 * h + 2].v = _mm256_shuffle_ps(t1, t3, 0x44); out[4 * h + 3].v = _mm256_shuffle_ps(t1, t3, 0xEE);
    }
}

template <int W> void load_rays(const float* rec, vfloat<W> out[8]);
template <> inline void load_rays<8>(const float* rec, vf8 out[8]) {
    const float* rows[8];
    for (int j = 0; j < 8; ++j) rows[j] = rec + 8 * j;
    transpose_rows8(rows, out);
}
// Records rec[0, k) (k < W) as load_rays, the lanes from k holding the record `pad`: loaded
// where they are (copying a short tail into a padded buffer stalled its reload on store
// forwarding, a fixed cost that dominated nodes of a few rays).
template <int W> void load_rays_tail(const float* rec, size_t k, const float* pad, vfloat<W> out[8]);
template <> inline void load_rays_tail<8>(const float* rec, size_t k, const float* pad, vf8 out[8]) {
    const float* rows[8];
    for (size_t j = 0; j < 8; ++j) rows[j] = j < k ? rec + 8 * j : pad;
    transpose_rows8(rows, out);
}
