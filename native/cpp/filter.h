// Ray filtering (Afra 2012): partition the ray records in place into rays that hit the current
// triangle set's box within [0, tfar] (moved to the front) and the rest. Whole 32-byte records
// move, never an index array: later passes then read memory linearly. W rays per box test,
// AoS -> SoA by loads and shuffles. Included inside an ISA namespace.
#pragma once
#include "runpartition.h"

// Robust slab test. No reciprocal is stored: 1/d is computed in registers, with the hardware's
// approximate reciprocal on AVX (a division would dominate the filter); the interval is then
// widened by a relative 2^-10, far more than the approximation error (<= 1.5 * 2^-12) plus
// rounding (Ize 2013's 1 + 2*gamma(3)), so the test never culls a ray that hits the exact box.
// Culling may differ by ISA at that margin; hits cannot, since leaves decide them exactly.
// Zero direction components give 1/d = +-inf: a slab distance is then +-inf, the exact slab
// (orthographic camera rays need it to be culled at all), or NaN (0 * inf) where the origin
// lies exactly on the slab's plane. The ordered min/max turn such a NaN into a kept or a culled
// ray; either is exact, because the ray runs inside a plane of the padded node box, more than
// the leaf's hit-point padding (half this one, leaf.h) away from every triangle of the node,
// so no hit of it could be kept there (the DACRT_NONROBUST build, without that padding, may
// lose such rays: part of what it gives up).
// Odd: a nonzero component whose reciprocal is +-inf or 0 (a denormal, or on AVX2 |d| >=
// ~2^126: see rcp_unusable) would put a finite slab at infinity and cull rays that hit; its
// slab is marked NaN and ignored by the NaN-ordered max/min. Made on every batch, that check
// cost 14-20% of the trace throughput on AVX-512 and 3-7% on AVX2 (San Francisco rays, 1
// thread), so only a batch with such a component (found by the field check) pays for it.
// (Marking the NaN slabs of zero components on every batch as well cost 2-3.5%.)
// Precise: the widening is relative to t, so a box t = 10^4 away from the origin was kept by rays
// passing ~10 from it: rays from far origins (a 10 km dome, dispatch.cpp) were tested against
// every small triangle near their path. Their groups divide instead (correctly rounded 1/d;
// with the subtraction and product, t is within 3 * 2^-24 relative: widened by 2^-20) and take
// the odd check, as a division overflows for denormal d as the reciprocal does.
enum FilterKind { kFast, kOdd, kPrecise };

template <int W, int Kind>
__attribute__((always_inline)) inline vbool<W> box_test(const vfloat<W> r[8], const float lo[3], const float hi[3]) {
    constexpr bool Odd = Kind != kFast;
    constexpr float kWiden = Kind == kPrecise ? 0x1p-20f : 0x1p-10f;
    vfloat<W> tmin = splat<W>(0.0f), tmax = r[6];
    for (int a = 0; a < 3; ++a) {
        const vfloat<W> inv = Kind == kPrecise ? splat<W>(1.0f) / r[3 + a] : rcp(r[3 + a]);
        const vfloat<W> t0 = (splat<W>(lo[a]) - r[a]) * inv;
        const vfloat<W> t1 = (splat<W>(hi[a]) - r[a]) * inv;
        if (!Odd) {
            tmin = vmax(vmin(t0, t1), tmin);
            tmax = vmin(vmax(t0, t1), tmax);
            continue;
        }
        const vbool<W> nan = cmpunord(t0, t1) | rcp_unusable(r[3 + a], inv);
        tmin = vmax(nan_where(nan, vmin(t0, t1)), tmin);  // NaN first operand -> tmin kept
        tmax = vmin(nan_where(nan, vmax(t0, t1)), tmax);
    }
    return cmple(tmin * splat<W>(1.0f - kWiden), tmax * splat<W>(1.0f + kWiden));
}

template <int W, int Kind>
__attribute__((always_inline)) inline uint32_t block_active(const Ray* rays, const float lo[3], const float hi[3]) {
    vfloat<W> r[8];
    load_rays<W>(reinterpret_cast<const float*>(rays), r);
    return bits(box_test<W, Kind>(r, lo, hi));
}

// The box test of the 64 rays from `rays` on, one bit per ray.
template <int W, int Kind>
__attribute__((always_inline)) inline uint64_t run_active(const Ray* rays, const float lo[3], const float hi[3]) {
    static_assert(kRunRays % W == 0, "W-ray blocks must tile a run");
    uint64_t m = 0;
    for (size_t b = 0; b < kRunRays / W; ++b) m |= uint64_t(block_active<W, Kind>(rays + b * W, lo, hi)) << (b * W);
    return m;
}

// Lomuto partition, a run's mask at a time (one swap loop exit per run, not per block), the
// last run padded: the short range partition_runs leaves (< 3 runs), and whole sweeps of at
// least kForwardSweepRays (below). The mask is taken before the run's swaps: they exchange
// each active ray with the inactive one at w <= its position, never touching a later
// position of the run.
template <int W, int Kind>
__attribute__((always_inline)) inline uint64_t run_active_tail(const Ray* rays, size_t i, size_t n, const float lo[3],
                                                               const float hi[3]) {
    uint64_t m = 0;
    for (size_t b = 0; b < kRunRays / W && i + b * W < n; ++b) {
        vfloat<W> r[8];
        const uint32_t valid = load_block<W>(rays, i + b * W, n, kInactiveRay, r);
        m |= uint64_t(bits(box_test<W, Kind>(r, lo, hi)) & valid) << (b * W);
    }
    return m;
}

template <int W, int Kind>
size_t filter_small(Ray* rays, size_t n, const float lo[3], const float hi[3]) {
    size_t w = 0;
    uint64_t next = n ? run_active_tail<W, Kind>(rays, 0, n, lo, hi) : 0;
    for (size_t i = 0; i < n; i += kRunRays) {
        uint64_t m = next;
        // The next run's mask before this run's swaps (they move records within [w, i +
        // kRunRays) only): its box tests then overlap the swap loop instead of following its
        // mispredicted exit. In cache (16K-ray sweeps) 1.5 -> 1.25-1.3 ns a ray.
        if (i + kRunRays < n) next = run_active_tail<W, Kind>(rays, i + kRunRays, n, lo, hi);
        while (m) {
            swap_records(rays + i + size_t(__builtin_ctzll(m)), rays + w);
            m &= m - 1;
            ++w;
        }
    }
    return w;
}

// Sweeps of at least this many rays (1 MB of records, an L2 here) go one way, forward, as
// filter_small: reading the records from both ends cost the two-ended sweep (which moves only
// the p(1-p)n misplaced records, against pn) up to twice its in-cache time per ray out of
// cache. Standalone, San Francisco diffuse rays, a box keeping 59%, 2 threads each sweeping
// its own records, ns a ray: two-ended 1.1 up to 64K rays, 1.55 at 128K, 2.1-2.4 at 256K,
// 2.6 at 512K (cache flushed); forward 1.3 at every size, 1.6 at 512K flushed. In the tracer,
// where a node's records have left L2 sooner, from 2^15 rays beat from 2^17 (CPU 0.95-0.985x)
// and from 2^13 was no better (0.97-1.04x). Only the order of the rays changes, never which
// are kept.
constexpr size_t kForwardSweepRays = size_t(1) << 15;

// Returns the number of active rays, now rays[0, result): partition_runs (runpartition.h) by
// the box test, the unsettled middle by filter_small. Runs of 64 rays rather than blocks of W:
// each run pair's swap loop ends on a mispredicted branch, as does each test for an empty
// mask, and with W = 16 those cost about a tenth of the whole trace (San Francisco diffuse
// rays, 1 thread: runs of 64 +10%, of 32 +8%; of 128, with two mask words, -28%).
template <int W, int Kind>
size_t filter_rays(Ray* rays, size_t n, const float lo[3], const float hi[3], Stats& st) {
    st.box_tests += n;
    if (n >= kForwardSweepRays) return filter_small<W, Kind>(rays, n, lo, hi);
    size_t b, e;
    // always_inline: without it GCC called the box test once per run (no longer one loop with
    // the box in registers)
    partition_runs(rays, n, [&](const Ray* p) __attribute__((always_inline)) { return run_active<W, Kind>(p, lo, hi); },
                   b, e);
    return b + filter_small<W, Kind>(rays + b, e - b, lo, hi);
}
