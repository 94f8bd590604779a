// A light-tree stop's lanes weighed side by side (treelanes.h), as named copies per instruction
// set (as noise.cpp) so that DACRT_ISA can pick a narrower one and tests compare them on one
// machine. The portable copy holds the eight lanes as two SSE vectors of four; the AVX2 and
// AVX-512 copies as one 256-bit vector, half the instructions (target_probs was 14.5% of a
// many-light render). Per lane the operations and their order are the same in every copy, and
// -ffp-contract=off: every copy gives the same bits.
#include "treelanes.h"

#include <strings.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
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

// The eight lanes of stop q[s] weighed at point at[s], for G walks s, as lighttree.cpp's
// weigh() does, in float: enough for a sampling estimate once distances are in range: the
// culling tests keep a margin of float's rounding, so no lane weighs 0 that weigh() would not,
// and a lane not culled weighs more than 0. V: eight floats, M: their lane masks. Each
// statement runs for all G walks before the next: one walk's stop is a chain of roots and
// divisions, and written one walk after another (G calls) the core's window did not reach the
// next walk's chain while waiting on this one's. bad[s] as StopWeighFn's return.
template <class V, class M, bool kNormal, int G>
LANES void weigh_lanes(const LightTree::Stop* const qs[], const TreePoint* const ats[], double (*imp)[8], int bad[]) {
#define EACH for (int s = 0; s < G; ++s)
    const V zero = splat<V>(0.0f), one = splat<V>(1.0f);
    const V margin = splat<V>(1e-5f);  // ~100 float ULPs of a cosine
    V v0[G], v1[G], v2[G], dd[G], r[G], r2[G], denom[G];
    M inside[G];
    EACH {
        const LightTree::Stop& q = *qs[s];
        const float* P = ats[s]->P;
        v0[s] = load<V>(q.center[0]) - P[0], v1[s] = load<V>(q.center[1]) - P[1], v2[s] = load<V>(q.center[2]) - P[2];
        dd[s] = v0[s] * v0[s] + v1[s] * v1[s] + v2[s] * v2[s], r[s] = load<V>(q.radius), r2[s] = r[s] * r[s];
        inside[s] = !(dd[s] > r2[s]);
        denom[s] = sel(inside[s], max_(dd[s], r2[s] * 0.25f), dd[s]);
        const M ok = (denom[s] >= 1e-30f) & (dd[s] <= 1e30f) & (r2[s] <= 1e30f);
        bad[s] = not_all(ok);
    }
    if (G == 1 && bad[0] == 3) return;
    // Every sine and cosine from dd and one product each (cos_u = sqrt(dd - r^2) / d, sin_i =
    // sqrt(dd - (N.v)^2) / d, ...) rather than from one another: the roots and the two
    // divisions then run side by side instead of one after another.
    V av[G], nv[G], inv_d[G], inv_denom[G], root_u[G], root_i[G], root_t[G];
    EACH {
        const LightTree::Stop& q = *qs[s];
        const float* N = ats[s]->N;
        av[s] = -(load<V>(q.axis[0]) * v0[s] + load<V>(q.axis[1]) * v1[s] + load<V>(q.axis[2]) * v2[s]);
        nv[s] = kNormal ? N[0] * v0[s] + N[1] * v1[s] + N[2] * v2[s] : zero;
    }
    EACH inv_d[s] = one / root(dd[s]), inv_denom[s] = one / denom[s];
    EACH root_u[s] = root(max_(dd[s] - r2[s], zero)), root_i[s] = root(max_(dd[s] - nv[s] * nv[s], zero)),
        root_t[s] = root(max_(dd[s] - av[s] * av[s], zero));
    EACH {
        const LightTree::Stop& q = *qs[s];
        const TreePoint& at = *ats[s];
        const V sin_u = min_(r[s] * inv_d[s], one), cos_u = min_(root_u[s] * inv_d[s], one);
        M culled = {}, out_culled = {};  // out_culled: outside the bounds only
        V f = one;
        if (kNormal) {
            const V spread = at.abs_n[0] * load<V>(q.half[0]) + at.abs_n[1] * load<V>(q.half[1]) +
                             at.abs_n[2] * load<V>(q.half[2]);
            const V reach = nv[s] + spread, nv_abs = sel(nv[s] < zero, -nv[s], nv[s]);
            culled = !(reach > -(margin * (nv_abs + spread)));
            const V ci = clamp1(nv[s] * inv_d[s]), sin_i = min_(root_i[s] * inv_d[s], one);
            const V c = ci * cos_u + sin_i * sin_u;
            const M below = ci < cos_u;
            out_culled = below & !(c > -margin);
            f = sel(below, max_(c, margin), one);
        }
        const V co = load<V>(q.cos_o), so = load<V>(q.sin_o);
        const V cos_p = co * cos_u - so * sin_u, sin_p = so * cos_u + co * sin_u;
        const V ct = clamp1(av[s] * inv_d[s]), sin_t = min_(root_t[s] * inv_d[s], one);
        const V cos_r = ct * cos_p + sin_t * sin_p;
        const M beyond = (co > -one) & (sin_p >= zero) & (ct < cos_p);
        out_culled = out_culled | (beyond & (cos_r <= load<V>(q.cos_e) - margin));
        f = sel(beyond, f * max_(cos_r, margin), f);
        culled = culled | (~inside[s] & out_culled);
        {  // behind every light of a node that emits within a hemisphere, inside its sphere too
            const V sl = load<V>(q.slab);
            const V d = dd[s] * inv_d[s];  // (NaN at dd = 0: not culled, as the centre is in the box)
            const V tol = kBackMargin * (2.0f * (d + splat<V>(at.pm)) + sl);
            culled = culled | ((sl >= zero) & (av[s] + sl <= -tol));
        }
        const V g = sel(culled, zero, sel(inside[s], one, f) * inv_denom[s]);
        for (int k = 0; k < 8; ++k) imp[s][k] = q.energy[k] * double(lane(g, k));
    }
#undef EACH
}

// One stop at one point (StopWeighFn), and up to LightTree::kGroup stops at their points
// (StopGroupWeighFn: the walks with a normal together, those without one each alone).
#define DACRT_TREE_ISA(NAME, TARGET, V, M)                                                                       \
    TARGET int NAME##_weigh(const LightTree::Stop& q, const TreePoint& at, double imp[8]) {                      \
        const LightTree::Stop* qs[1] = {&q};                                                                     \
        const TreePoint* ats[1] = {&at};                                                                         \
        int bad[1];                                                                                              \
        double(*out)[8] = reinterpret_cast<double(*)[8]>(imp);                                                   \
        if (at.N)                                                                                                \
            weigh_lanes<V, M, true, 1>(qs, ats, out, bad);                                                       \
        else                                                                                                     \
            weigh_lanes<V, M, false, 1>(qs, ats, out, bad);                                                      \
        return bad[0];                                                                                           \
    }                                                                                                            \
    TARGET void NAME##_weigh_group(size_t count, const LightTree::Stop* const q[], const TreePoint* const at[],   \
                                   double (*imp)[8], int bad[]) {                                                \
        constexpr int G = int(LightTree::kGroup);                                                                \
        const LightTree::Stop* qs[G];                                                                            \
        const TreePoint* ats[G];                                                                                 \
        size_t idx[G], m = 0;                                                                                    \
        for (size_t s = 0; s < count; ++s) {                                                                     \
            if (at[s]->N) {                                                                                      \
                qs[m] = q[s], ats[m] = at[s], idx[m++] = s;                                                      \
                continue;                                                                                        \
            }                                                                                                    \
            bad[s] = NAME##_weigh(*q[s], *at[s], imp[s]);                                                        \
        }                                                                                                        \
        double got[G][8];                                                                                        \
        int got_bad[G];                                                                                          \
        switch (m) {                                                                                             \
            case 0: return;                                                                                      \
            case 1: weigh_lanes<V, M, true, 1>(qs, ats, got, got_bad); break;                                    \
            case 2: weigh_lanes<V, M, true, 2>(qs, ats, got, got_bad); break;                                    \
            case 3: weigh_lanes<V, M, true, 3>(qs, ats, got, got_bad); break;                                    \
            default: weigh_lanes<V, M, true, G>(qs, ats, got, got_bad);                                          \
        }                                                                                                        \
        for (size_t s = 0; s < m; ++s) {                                                                         \
            std::memcpy(imp[idx[s]], got[s], sizeof got[s]);                                                     \
            bad[idx[s]] = got_bad[s];                                                                            \
        }                                                                                                        \
    }

DACRT_TREE_ISA(portable, , F8, M8)
DACRT_TREE_ISA(avx2, __attribute__((target("avx2,fma,bmi,bmi2"))), W8, WM8)
DACRT_TREE_ISA(avx512, __attribute__((target("avx2,fma,bmi,bmi2,avx512f,avx512vl,avx512dq,avx512bw,avx512cd"))), W8,
               WM8)

}  // namespace

TreePoint tree_point(const float P[3], const float* N) {
    TreePoint t{{P[0], P[1], P[2]}, N, {0.0f, 0.0f, 0.0f}, 0.0f};
    if (N)
        for (int k = 0; k < 3; ++k) t.abs_n[k] = std::fabs(N[k]);
    t.pm = std::max({std::fabs(P[0]), std::fabs(P[1]), std::fabs(P[2])});
    return t;
}

namespace {

// The widest instruction set the CPU runs, or a narrower one DACRT_ISA names.
Isa tree_isa() {
    const Isa best = resolve_isa("");
    const char* env = std::getenv("DACRT_ISA");
    if (env && strcasecmp(env, "portable") == 0) return Isa::Portable;
    if (env && strcasecmp(env, "avx2") == 0 && best != Isa::Portable) return Isa::Avx2;
    return best;
}

}  // namespace

StopWeighFn stop_weigh_fn() {
    const Isa isa = tree_isa();
    return isa == Isa::Avx512 ? avx512_weigh : (isa == Isa::Avx2 ? avx2_weigh : portable_weigh);
}

StopGroupWeighFn stop_group_weigh_fn() {
    const Isa isa = tree_isa();
    return isa == Isa::Avx512 ? avx512_weigh_group : (isa == Isa::Avx2 ? avx2_weigh_group : portable_weigh_group);
}

}  // namespace dacrt
