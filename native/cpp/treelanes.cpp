// A light-tree stop's lanes weighed side by side (treelanes.h), as named copies per instruction
// set (as noise.cpp) so that DACRT_ISA can pick a narrower one and tests compare them on one
// machine. The portable copy holds the eight lanes as two SSE vectors of four; the AVX2 and
// AVX-512 copies as one 256-bit vector, half the instructions (target_probs was 14.5% of a
// many-light render). Per lane the operations and their order are the same in every copy, and
// -ffp-contract=off: every copy gives the same bits.
#include "treelanes.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "dispatch.h"

#pragma GCC diagnostic ignored "-Wpsabi"  // 32-byte vectors only ever inlined into AVX code

namespace dacrt {

namespace {

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
template <class V>
LANES V load(const float* p) {
    V v;
    std::memcpy(&v, p, sizeof v);  // (F8: lo then hi, 8 floats either way)
    return v;
}
// Of x >= 0 lanes: a lane loop the compiler turns into one sqrtps (vsqrtps).
LANES F4 root(F4 x) {
    F4 r;
    for (int k = 0; k < 4; ++k) r[k] = std::sqrt(x[k]);
    return r;
}
LANES F8 root(F8 x) { return {root(x.lo), root(x.hi)}; }
LANES W8 root(const W8& x) {
    W8 r;
    for (int k = 0; k < 8; ++k) r[k] = std::sqrt(x[k]);
    return r;
}
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

// The eight lanes of stop q weighed at the point, as lighttree.cpp's weigh() does, in float:
// enough for a sampling estimate once distances are in range: the culling tests keep a margin
// of float's rounding, so no lane weighs 0 that weigh() would not, and a lane not culled weighs
// more than 0. V: eight floats, M: their lane masks.
template <class V, class M, bool kNormal>
LANES int weigh_lanes(const LightTree::Stop& q, const TreePoint& at, double imp[8]) {
    const float* P = at.P;
    const float* N = at.N;
    const V zero = splat<V>(0.0f), one = splat<V>(1.0f);
    const V margin = splat<V>(1e-5f);  // ~100 float ULPs of a cosine
    const V v0 = load<V>(q.center[0]) - P[0], v1 = load<V>(q.center[1]) - P[1], v2 = load<V>(q.center[2]) - P[2];
    const V dd = v0 * v0 + v1 * v1 + v2 * v2, r = load<V>(q.radius), r2 = r * r;
    const M inside = !(dd > r2);
    const V denom = sel(inside, max_(dd, r2 * 0.25f), dd);
    const M ok = (denom >= 1e-30f) & (dd <= 1e30f) & (r2 <= 1e30f);
    const int bad = not_all(ok);
    if (bad == 3) return bad;
    // Every sine and cosine from dd and one product each (cos_u = sqrt(dd - r^2) / d, sin_i =
    // sqrt(dd - (N.v)^2) / d, ...) rather than from one another: the roots and the two
    // divisions then run side by side instead of one after another.
    const V av = -(load<V>(q.axis[0]) * v0 + load<V>(q.axis[1]) * v1 + load<V>(q.axis[2]) * v2);
    const V nv = kNormal ? N[0] * v0 + N[1] * v1 + N[2] * v2 : zero;
    const V inv_d = one / root(dd), inv_denom = one / denom;
    const V root_u = root(max_(dd - r2, zero)), root_i = root(max_(dd - nv * nv, zero)),
            root_t = root(max_(dd - av * av, zero));
    const V sin_u = min_(r * inv_d, one), cos_u = min_(root_u * inv_d, one);
    M culled = {}, out_culled = {};  // out_culled: outside the bounds only
    V f = one;
    if (kNormal) {
        const V spread = at.abs_n[0] * load<V>(q.half[0]) + at.abs_n[1] * load<V>(q.half[1]) +
                         at.abs_n[2] * load<V>(q.half[2]);
        const V reach = nv + spread, nv_abs = sel(nv < zero, -nv, nv);
        culled = !(reach > -(margin * (nv_abs + spread)));
        const V ci = clamp1(nv * inv_d), sin_i = min_(root_i * inv_d, one);
        const V c = ci * cos_u + sin_i * sin_u;
        const M below = ci < cos_u;
        out_culled = below & !(c > -margin);
        f = sel(below, max_(c, margin), one);
    }
    const V co = load<V>(q.cos_o), so = load<V>(q.sin_o);
    const V cos_p = co * cos_u - so * sin_u, sin_p = so * cos_u + co * sin_u;
    const V ct = clamp1(av * inv_d), sin_t = min_(root_t * inv_d, one);
    const V cos_r = ct * cos_p + sin_t * sin_p;
    const M beyond = (co > -one) & (sin_p >= zero) & (ct < cos_p);
    out_culled = out_culled | (beyond & (cos_r <= load<V>(q.cos_e) - margin));
    f = sel(beyond, f * max_(cos_r, margin), f);
    culled = culled | (~inside & out_culled);
    {  // behind every light of a node that emits within a hemisphere, inside its sphere too
        const V sl = load<V>(q.slab);
        const V d = dd * inv_d;  // (NaN at dd = 0: not culled, as the centre is in the box)
        const V tol = kBackMargin * (2.0f * (d + splat<V>(at.pm)) + sl);
        culled = culled | ((sl >= zero) & (av + sl <= -tol));
    }
    const V g = sel(culled, zero, sel(inside, one, f) * inv_denom);
    for (int k = 0; k < 8; ++k) imp[k] = q.energy[k] * double(lane(g, k));
    return bad;
}

#define DACRT_TREE_ISA(NAME, TARGET, V, M)                                                       \
    TARGET int NAME##_weigh(const LightTree::Stop& q, const TreePoint& at, double imp[8]) {      \
        return at.N ? weigh_lanes<V, M, true>(q, at, imp) : weigh_lanes<V, M, false>(q, at, imp); \
    }

DACRT_TREE_ISA(portable, , F8, M8)
DACRT_TREE_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))), W8, WM8)
DACRT_TREE_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))), W8,
               WM8)

}  // namespace

void tree_point(TreePoint& t, const float P[3], const float* N) {
    for (int k = 0; k < 3; ++k) t.P[k] = P[k], t.abs_n[k] = N ? std::fabs(N[k]) : 0.0f;
    t.N = N;
    t.pm = std::max({std::fabs(P[0]), std::fabs(P[1]), std::fabs(P[2])});
}

StopWeighFn stop_weigh_fn() { return lane_copy<StopWeighFn>(portable_weigh, avx2_weigh, avx512_weigh); }

}  // namespace dacrt
