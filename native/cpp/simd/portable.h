// Portable SIMD emulation: W lanes as plain arrays. Every operation is the same IEEE float
// operation the AVX kernels perform per lane (x86 min/max NaN semantics included), so this
// fallback produces bit-identical hits. Included inside namespace dacrt::portable.
#pragma once

template <int W> struct vbool { uint32_t m; };  // lane i = bit i
template <int W> struct vfloat { float v[W]; };
template <int W> struct vint { int32_t v[W]; };

#define DACRT_LANES for (int i = 0; i < W; ++i)

template <int W> inline uint32_t bits(vbool<W> a) { return a.m; }
template <int W> inline bool any(vbool<W> a) { return a.m != 0; }
template <int W> inline vbool<W> operator&(vbool<W> a, vbool<W> b) { return {a.m & b.m}; }
template <int W> inline vbool<W> operator|(vbool<W> a, vbool<W> b) { return {a.m | b.m}; }
template <int W> inline vbool<W> andnot(vbool<W> a, vbool<W> b) { return {~a.m & b.m}; }  // !a & b
template <int W> inline vbool<W> from_bits(uint32_t m) { return {m}; }

template <int W> inline vfloat<W> splat(float x) { vfloat<W> r; DACRT_LANES r.v[i] = x; return r; }
template <int W> inline vfloat<W> loadu(const float* p) { vfloat<W> r; DACRT_LANES r.v[i] = p[i]; return r; }
template <int W> inline void storeu(float* p, vfloat<W> a) { DACRT_LANES p[i] = a.v[i]; }
#define DACRT_BIN(op) \
    template <int W> inline vfloat<W> operator op(vfloat<W> a, vfloat<W> b) { \
        vfloat<W> r; DACRT_LANES r.v[i] = a.v[i] op b.v[i]; return r; }
DACRT_BIN(+) DACRT_BIN(-) DACRT_BIN(*) DACRT_BIN(/)
#undef DACRT_BIN
// x86 semantics: the second operand is returned when either is NaN.
template <int W> inline vfloat<W> vmin(vfloat<W> a, vfloat<W> b) { vfloat<W> r; DACRT_LANES r.v[i] = a.v[i] < b.v[i] ? a.v[i] : b.v[i]; return r; }
template <int W> inline vfloat<W> vmax(vfloat<W> a, vfloat<W> b) { vfloat<W> r; DACRT_LANES r.v[i] = a.v[i] > b.v[i] ? a.v[i] : b.v[i]; return r; }
// Reciprocal for the box test; exact here, approximate on AVX (the box test widens for it).
template <int W> inline vfloat<W> rcp(vfloat<W> a) { vfloat<W> r; DACRT_LANES r.v[i] = 1.0f / a.v[i]; return r; }
// Lanes where inv = rcp(a) may be no reciprocal of a nonzero a: a denormal (1/a overflows to
// +-inf below ~2^-128), as on AVX-512.
template <int W> inline vbool<W> rcp_unusable(vfloat<W> a, vfloat<W>) {
    uint32_t m = 0; DACRT_LANES m |= uint32_t(std::fpclassify(a.v[i]) == FP_SUBNORMAL) << i; return {m};
}
template <int W> inline vfloat<W> vabs(vfloat<W> a) { vfloat<W> r; DACRT_LANES r.v[i] = std::fabs(a.v[i]); return r; }
#define DACRT_CMP(name, expr) \
    template <int W> inline vbool<W> name(vfloat<W> a, vfloat<W> b) { \
        uint32_t m = 0; DACRT_LANES m |= uint32_t(expr) << i; return {m}; }
DACRT_CMP(cmplt, a.v[i] < b.v[i]) DACRT_CMP(cmple, a.v[i] <= b.v[i]) DACRT_CMP(cmpeq, a.v[i] == b.v[i])
DACRT_CMP(cmpunord, a.v[i] != a.v[i] || b.v[i] != b.v[i])
#undef DACRT_CMP
template <int W> inline vfloat<W> select(vbool<W> m, vfloat<W> a, vfloat<W> b) { vfloat<W> r; DACRT_LANES r.v[i] = (m.m >> i & 1) ? a.v[i] : b.v[i]; return r; }
template <int W> inline vfloat<W> nan_where(vbool<W> m, vfloat<W> a) { return select(m, splat<W>(NAN), a); }
// a with the sign of s flipped where s is negative (xor of sign bits).
template <int W> inline vfloat<W> xorsign(vfloat<W> a, vfloat<W> s) { vfloat<W> r; DACRT_LANES r.v[i] = std::signbit(s.v[i]) ? -a.v[i] : a.v[i]; return r; }

template <int W> inline vint<W> splati(int32_t x) { vint<W> r; DACRT_LANES r.v[i] = x; return r; }
template <int W> inline vbool<W> cmpeqi(vint<W> a, vint<W> b) { uint32_t m = 0; DACRT_LANES m |= uint32_t(a.v[i] == b.v[i]) << i; return {m}; }
template <int W> inline vint<W> selecti(vbool<W> m, vint<W> a, vint<W> b) { vint<W> r; DACRT_LANES r.v[i] = (m.m >> i & 1) ? a.v[i] : b.v[i]; return r; }
template <int W> inline void storei(int32_t* p, vint<W> a) { DACRT_LANES p[i] = a.v[i]; }
template <int W> inline vint<W> loadi(const int32_t* p) { vint<W> r; DACRT_LANES r.v[i] = p[i]; return r; }
// Per-lane element idx of a 4-float table (x, y, z, 0).
template <int W> inline vfloat<W> permute(const float* table4, vint<W> idx) { vfloat<W> r; DACRT_LANES r.v[i] = table4[idx.v[i]]; return r; }

// AoS -> SoA: W ray records (8 floats each) into 8 vectors (org xyz, dir xyz, tfar, id bits).
template <int W> inline void load_rays(const float* rec, vfloat<W> out[8]) {
    for (int f = 0; f < 8; ++f) DACRT_LANES out[f].v[i] = rec[8 * i + f];
}
template <int W> inline void load_rays_tail(const float* rec, size_t k, const float* pad, vfloat<W> out[8]) {
    for (int f = 0; f < 8; ++f) DACRT_LANES out[f].v[i] = size_t(i) < k ? rec[8 * i + f] : pad[f];
}
#undef DACRT_LANES
