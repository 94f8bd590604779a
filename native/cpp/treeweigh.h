// A light-tree stop's lanes weighed side by side (treelanes.h): the lane types and the weigh as
// templates over them, included inside each instruction set's own namespace (treelanes.cpp: the
// portable and AVX2 copies, by target attributes; treelanes_avx512.cpp: the AVX-512 copies,
// compiled with its flags, as kernel.h's simd headers are), so that no copy's code is ever
// merged with another's. Per lane the operations and their order are the same in every copy,
// and -ffp-contract=off: every copy gives the same bits. No std:: inline functions here (an
// out-of-line copy LTO keeps could be the AVX-512 one): builtins only. The including file has
// <cstdint>, <cstddef> and treelanes.h.
// (no #pragma once: included once per namespace)

// A point counts as behind a node's lights (LightTreeNode::slab) only beyond this share of
// 2 (d + max |P_k|) + slab (lighttree.cpp's weigh() keeps the same margin).
constexpr float kBackMargin = 1e-5f;

#define LANES inline __attribute__((always_inline))

// Four floats side by side (GCC/Clang vector extensions); comparisons give lane masks,
// `mask ? a : b` selects per lane.
typedef float F4 __attribute__((vector_size(16)));
typedef int32_t M4 __attribute__((vector_size(16)));
// Eight, for the AVX copies: without AVX GCC turns a 32-byte type's comparisons and selects
// into scalar code, 3x slower, hence F8 there.
typedef float W8 __attribute__((vector_size(32)));
typedef int32_t WM8 __attribute__((vector_size(32)));
#ifdef __AVX512F__
// Sixteen, for the AVX-512 rows (treelanes_avx512.cpp, compiled with the AVX-512 flags: under a
// target attribute alone GCC 12 lowered these helpers' 64-byte vectors before inlining them,
// ~3480 instructions with ~340 stack references, 3x slower than eight lanes).
typedef float W16 __attribute__((vector_size(64)));
typedef int32_t WM16 __attribute__((vector_size(64)));
#endif

// Eight lanes as two of four, each operation written out for both halves: the two halves'
// chains of roots and divisions overlap (weighed as two passes of four, the second waited on
// the first).
struct F8 {
    F4 lo, hi;
};
struct M8 {
    M4 lo, hi;
};
LANES F8 operator+(F8 a, F8 b) { return {a.lo + b.lo, a.hi + b.hi}; }
LANES F8 operator-(F8 a, F8 b) { return {a.lo - b.lo, a.hi - b.hi}; }
LANES F8 operator*(F8 a, F8 b) { return {a.lo * b.lo, a.hi * b.hi}; }
LANES F8 operator/(F8 a, F8 b) { return {a.lo / b.lo, a.hi / b.hi}; }
LANES F8 operator-(F8 a) { return {-a.lo, -a.hi}; }
LANES F8 operator-(F8 a, float b) { return {a.lo - b, a.hi - b}; }
LANES F8 operator*(F8 a, float b) { return {a.lo * b, a.hi * b}; }
LANES F8 operator*(float a, F8 b) { return {a * b.lo, a * b.hi}; }
LANES M8 operator<(F8 a, F8 b) { return {a.lo < b.lo, a.hi < b.hi}; }
LANES M8 operator>(F8 a, F8 b) { return {a.lo > b.lo, a.hi > b.hi}; }
LANES M8 operator<=(F8 a, F8 b) { return {a.lo <= b.lo, a.hi <= b.hi}; }
LANES M8 operator>=(F8 a, F8 b) { return {a.lo >= b.lo, a.hi >= b.hi}; }
LANES M8 operator>=(F8 a, float b) { return {a.lo >= b, a.hi >= b}; }
LANES M8 operator<=(F8 a, float b) { return {a.lo <= b, a.hi <= b}; }
LANES M8 operator&(M8 a, M8 b) { return {a.lo & b.lo, a.hi & b.hi}; }
LANES M8 operator|(M8 a, M8 b) { return {a.lo | b.lo, a.hi | b.hi}; }
LANES M8 operator!(M8 a) { return {!a.lo, !a.hi}; }
LANES M8 operator~(M8 a) { return {~a.lo, ~a.hi}; }
LANES F8 sel(M8 m, F8 a, F8 b) { return {m.lo ? a.lo : b.lo, m.hi ? a.hi : b.hi}; }
LANES W8 sel(const WM8& m, const W8& a, const W8& b) { return m ? a : b; }
#ifdef __AVX512F__
LANES W16 sel(const WM16& m, const W16& a, const W16& b) { return m ? a : b; }
#endif

template <class V>
LANES V splat(float x);
template <>
LANES F8 splat<F8>(float x) {
    return {F4{x, x, x, x}, F4{x, x, x, x}};
}
template <>
LANES W8 splat<W8>(float x) {
    return W8{x, x, x, x, x, x, x, x};
}
#ifdef __AVX512F__
template <>
LANES W16 splat<W16>(float x) {
    return W16{} + x;
}
#endif
template <class V>
LANES V load(const float* p) {
    V v;
    __builtin_memcpy(&v, p, sizeof v);  // (F8: lo then hi, 8 floats either way)
    return v;
}
// Of x >= 0 lanes: a lane loop the compiler turns into one sqrtps (vsqrtps).
LANES F4 root(F4 x) {
    F4 r;
    for (int k = 0; k < 4; ++k) r[k] = __builtin_sqrtf(x[k]);
    return r;
}
LANES F8 root(F8 x) { return {root(x.lo), root(x.hi)}; }
LANES W8 root(const W8& x) {
    W8 r;
    for (int k = 0; k < 8; ++k) r[k] = __builtin_sqrtf(x[k]);
    return r;
}
// |x| lane by lane, as std::fabs (the sign bit cleared: -0 gives +0).
LANES F4 abs_(F4 x) { return (F4)((M4)x & M4{} + 0x7fffffff); }
LANES F8 abs_(F8 x) { return {abs_(x.lo), abs_(x.hi)}; }
LANES W8 abs_(const W8& x) { return (W8)((WM8)x & WM8{} + 0x7fffffff); }
#ifdef __AVX512F__
LANES W16 root(const W16& x) {
    W16 r;
    for (int k = 0; k < 16; ++k) r[k] = __builtin_sqrtf(x[k]);
    return r;
}
LANES W16 abs_(const W16& x) { return (W16)((WM16)x & WM16{} + 0x7fffffff); }
#endif
LANES float lane(F8 v, int k) { return k < 4 ? v.lo[k] : v.hi[k - 4]; }
LANES float lane(const W8& v, int k) { return v[k]; }
// Bit h: some lane of four h is clear.
LANES int not_all(M8 m) {
    return (m.lo[0] & m.lo[1] & m.lo[2] & m.lo[3] ? 0 : 1) | (m.hi[0] & m.hi[1] & m.hi[2] & m.hi[3] ? 0 : 2);
}
LANES int not_all(const WM8& m) { return (m[0] & m[1] & m[2] & m[3] ? 0 : 1) | (m[4] & m[5] & m[6] & m[7] ? 0 : 2); }

template <class V>
LANES V max_(const V& a, const V& b) {
    return sel(a > b, a, b);
}
template <class V>
LANES V min_(const V& a, const V& b) {
    return sel(a < b, a, b);
}
template <class V>
LANES V clamp1(const V& x) {  // (NaN stays NaN)
    const V y = sel(x < splat<V>(-1.0f), splat<V>(-1.0f), x);
    return sel(y > splat<V>(1.0f), splat<V>(1.0f), y);
}

// Where the weigh below reads its operands: a stop's eight lanes at one point (StopAt: the
// stop's bounds loaded, the point's coordinates splatted) or one lane of a stop at a row of
// points (LaneAt: the lane's bounds splatted, the points' loaded). Each (point, lane) pair meets
// the same operations in the same order either way, so both give the same bits.
template <class V>
struct StopAt {
    const LightTree::Stop& q;
    const TreePoint& at;
    LANES V center(int a) const { return load<V>(q.center[a]); }
    LANES V half(int a) const { return load<V>(q.half[a]); }
    LANES V axis(int a) const { return load<V>(q.axis[a]); }
    LANES V radius() const { return load<V>(q.radius); }
    LANES V cos_o() const { return load<V>(q.cos_o); }
    LANES V sin_o() const { return load<V>(q.sin_o); }
    LANES V cos_e() const { return load<V>(q.cos_e); }
    LANES V slab() const { return load<V>(q.slab); }
    LANES V cos_b() const { return load<V>(q.cos_b); }
    LANES V cos_s() const { return load<V>(q.cos_s); }
    LANES V sin_s() const { return load<V>(q.sin_s); }
    LANES V P(int a) const { return splat<V>(at.P[a]); }
    LANES V N(int a) const { return splat<V>(at.N[a]); }
    LANES V abs_n(int a) const { return splat<V>(at.abs_n[a]); }
    LANES V pm() const { return splat<V>(at.pm); }
};
template <class V>
struct LaneAt {
    const LightTree::Stop& q;
    int k;
    const TreeRows& rows;
    size_t i;
    LANES V center(int a) const { return splat<V>(q.center[a][k]); }
    LANES V half(int a) const { return splat<V>(q.half[a][k]); }
    LANES V axis(int a) const { return splat<V>(q.axis[a][k]); }
    LANES V radius() const { return splat<V>(q.radius[k]); }
    LANES V cos_o() const { return splat<V>(q.cos_o[k]); }
    LANES V sin_o() const { return splat<V>(q.sin_o[k]); }
    LANES V cos_e() const { return splat<V>(q.cos_e[k]); }
    LANES V slab() const { return splat<V>(q.slab[k]); }
    LANES V cos_b() const { return splat<V>(q.cos_b[k]); }
    LANES V cos_s() const { return splat<V>(q.cos_s[k]); }
    LANES V sin_s() const { return splat<V>(q.sin_s[k]); }
    LANES V P(int a) const { return load<V>(rows.P[a] + i); }
    LANES V N(int a) const { return load<V>(rows.N[a] + i); }
    // tree_point's: std::fabs, and std::max of the three (the first largest, NaN as it compares)
    LANES V abs_n(int a) const { return abs_(N(a)); }
    LANES V pm() const {
        const V a = abs_(P(0)), b = abs_(P(1)), c = abs_(P(2));
        const V ab = sel(a < b, b, a);
        return sel(ab < c, c, ab);
    }
};

// Lanes weighed as lighttree.cpp's weigh() does, in float: enough for a sampling estimate once
// distances are in range: the culling tests keep a margin of float's rounding, so no lane weighs
// 0 that weigh() would not, and a lane not culled weighs more than 0. V: the lanes, M: their
// masks. ok: the lanes whose distances lie in float's range (the others are weighed in float64
// by the caller); g: the weigh before the energy, gmin: the smallest (as Cycles' min_importance:
// the incidence and emission cosines at their worst over the node's sphere and cone, 0 inside the
// sphere, where a light may give nothing, and where g is). Returns false, g and gmin unset, where
// stop(ok) says so.
template <class V, class M, bool kNormal, class S, class Stop>
LANES bool weigh_body(const S& src, V& g, V& gmin, M& ok, Stop stop) {
    const V zero = splat<V>(0.0f), one = splat<V>(1.0f);
    const V margin = splat<V>(1e-5f);  // ~100 float ULPs of a cosine
    const V v0 = src.center(0) - src.P(0), v1 = src.center(1) - src.P(1), v2 = src.center(2) - src.P(2);
    const V dd = v0 * v0 + v1 * v1 + v2 * v2, r = src.radius(), r2 = r * r;
    const M inside = !(dd > r2);
    const V denom = sel(inside, max_(dd, r2 * 0.25f), dd);
    ok = (denom >= 1e-30f) & (dd <= 1e30f) & (r2 <= 1e30f);
    if (stop(ok)) return false;
    // Every sine and cosine from dd and one product each (cos_u = sqrt(dd - r^2) / d, sin_i =
    // sqrt(dd - (N.v)^2) / d, ...) rather than from one another: the roots and the two
    // divisions then run side by side instead of one after another.
    const V av = -(src.axis(0) * v0 + src.axis(1) * v1 + src.axis(2) * v2);
    const V nv = kNormal ? src.N(0) * v0 + src.N(1) * v1 + src.N(2) * v2 : zero;
    const V inv_d = one / root(dd), inv_denom = one / denom;
    const V root_u = root(max_(dd - r2, zero)), root_i = root(max_(dd - nv * nv, zero)),
            root_t = root(max_(dd - av * av, zero));
    const V sin_u = min_(r * inv_d, one), cos_u = min_(root_u * inv_d, one);
    M culled = {}, out_culled = {};  // out_culled: outside the bounds only
    V f = one, fmin = one;
    if (kNormal) {
        const V spread = src.abs_n(0) * src.half(0) + src.abs_n(1) * src.half(1) + src.abs_n(2) * src.half(2);
        const V reach = nv + spread, nv_abs = sel(nv < zero, -nv, nv);
        culled = !(reach > -(margin * (nv_abs + spread)));
        const V ci = clamp1(nv * inv_d), sin_i = min_(root_i * inv_d, one);
        const V c = ci * cos_u + sin_i * sin_u;
        const M below = ci < cos_u;
        out_culled = below & !(c > -margin);
        f = sel(below, max_(c, margin), one);
        fmin = max_(ci * cos_u - sin_i * sin_u, zero);  // cos(theta_i + theta_u), 0 past pi/2
    }
    const V co = src.cos_o(), so = src.sin_o();
    const V cos_p = co * cos_u - so * sin_u, sin_p = so * cos_u + co * sin_u;
    const V ct = clamp1(av * inv_d), sin_t = min_(root_t * inv_d, one);
    const V cos_r = ct * cos_p + sin_t * sin_p;
    const M beyond = (co > -one) & (sin_p >= zero) & (ct < cos_p);
    out_culled = out_culled | (beyond & (cos_r <= src.cos_e() - margin));
    f = sel(beyond, f * max_(cos_r, margin), f);
    culled = culled | (~inside & out_culled);
    {  // the emission cosine at the worst: theta + theta_u + theta_s within theta_b (ct >= 0)
        const V c1 = ct * cos_u - sin_t * sin_u, s1 = sin_t * cos_u + ct * sin_u;
        const V cw = c1 * src.cos_s() - s1 * src.sin_s(), cb = src.cos_b();
        const V fe = sel((ct >= zero) & (cw >= cb), cw, zero);
        fmin = fmin * sel(cb < -one, cos_u, fe);
    }
    {  // behind every light of a node that emits within a hemisphere, inside its sphere too
        const V sl = src.slab();
        const V d = dd * inv_d;  // (NaN at dd = 0: not culled, as the centre is in the box)
        const V tol = kBackMargin * (2.0f * (d + src.pm()) + sl);
        culled = culled | ((sl >= zero) & (av + sl <= -tol));
    }
    g = sel(culled, zero, sel(inside, one, f) * inv_denom);
    gmin = sel(culled | inside, zero, fmin * inv_denom);
    return true;
}

// The eight lanes of stop q weighed at the point (weigh_body), times their energies.
template <class V, class M, bool kNormal>
LANES int weigh_lanes(const LightTree::Stop& q, const TreePoint& at, double imp[8], double imin[8]) {
    V g, gmin;
    M ok;
    int bad = 0;
    if (!weigh_body<V, M, kNormal>(StopAt<V>{q, at}, g, gmin, ok,
                                   [&](const M& o) { return (bad = not_all(o)) == 3; }))
        return bad;
    for (int k = 0; k < 8; ++k) imp[k] = q.energy[k] * double(lane(g, k));
    for (int k = 0; k < 8; ++k) imin[k] = q.energy[k] * double(lane(gmin, k));
    return bad;
}

// Lane k of stop q weighed at points [0, m) of rows (weigh_body), V's width of them at a time
// (the rows hold a whole number of V past m).
template <class V, class M, bool kNormal>
LANES void weigh_rows(const LightTree::Stop& q, int k, const TreeRows& rows, size_t m, float* g, float* gmin,
                      int32_t* ok) {
    constexpr size_t W = sizeof(V) / sizeof(float);
    for (size_t i = 0; i < m; i += W) {
        V gi, gm;
        M oki;
        weigh_body<V, M, kNormal>(LaneAt<V>{q, k, rows, i}, gi, gm, oki, [](const M&) { return false; });
        __builtin_memcpy(g + i, &gi, sizeof gi);
        __builtin_memcpy(gmin + i, &gm, sizeof gm);
        __builtin_memcpy(ok + i, &oki, sizeof oki);
    }
}

#define DACRT_TREE_ISA(NAME, TARGET, V, M, VR, MR)                                                         \
    TARGET int NAME##_weigh(const LightTree::Stop& q, const TreePoint& at, double imp[8], double imin[8]) { \
        return at.N ? weigh_lanes<V, M, true>(q, at, imp, imin) : weigh_lanes<V, M, false>(q, at, imp, imin); \
    }                                                                                                      \
    TARGET void NAME##_rows(const LightTree::Stop& q, int k, const TreeRows& rows, size_t m, float* g,      \
                            float* gmin, int32_t* ok) {                                                    \
        if (rows.N[0])                                                                                     \
            weigh_rows<VR, MR, true>(q, k, rows, m, g, gmin, ok);                                          \
        else                                                                                               \
            weigh_rows<VR, MR, false>(q, k, rows, m, g, gmin, ok);                                         \
    }
