// Leaf intersection: every active ray against every triangle of the leaf, W rays x 1 triangle
// per SIMD step, with the watertight test of Woop, Benthin and Wald (JCGT 2013).
//
// Watertightness: each ray is sheared so it becomes the +z axis of a per-ray frame (kz = largest
// |dir| component); a shared vertex then gets bit-identical 2D coordinates in both triangles
// that use it (same operations, no FMA contraction), so the edge function of a shared edge has
// exactly opposite values in the two triangles. A nonzero float edge function already has the
// exact sign (rounding is monotonic); lanes where one is exactly 0 (on an edge or vertex, or
// products below the float range) are decided in double, as are lanes whose determinant lies
// outside [2^-64, 2^64] (tiny or huge triangles), where 1/det would lose precision or overflow,
// and lanes where det is small against its products (needles, slivers, grazing views: float
// cancellation would cost t its precision) -- see exact_lanes. A ray can therefore never slip
// between two triangles that share an edge or a vertex, at any scale. In float,
// t = (barycentrics . Pz) / dz cannot overflow before the division (|b| <= 1); a t beyond the
// float range is not a hit.
// Ties (equal t) go to the lowest triangle index, so results do not depend on traversal order,
// thread count or ISA.
//
// Hits on the filter's segment: a ray lying (within rounding) in a triangle's plane can pass
// the inside test -- its projection of the triangle is a sliver that rounding may move over the
// origin -- with t from the plane far from where the ray meets the triangle's box. Whether such
// a ray reached that leaf depended on how the filter's boxes fell (leaf size, partition mode,
// thread count, ISA), so its hit did too. So a hit is kept only where the segment [0, t] meets
// the triangle's box padded by tol = 2^-20 (largest |box coordinate| + largest |origin
// coordinate|), half the filter's padding of every node box that holds the triangle (trace.h):
// then every node on the way keeps the ray while its tfar >= t, and the hits are a function of
// the ray and the triangles alone. A t short of the padded box is raised to where the ray
// enters it, a ray that misses it is no hit. A ray that really meets the triangle passes within
// ~6 ulps of those magnitudes of it (the rounding of its sheared coordinates), inside tol, so
// it is never dropped; only a grazing ray's t can move. Dropping the hits whose point o + t d
// lies outside the padded box, or short of it, instead let rays out of closed meshes through
// the edges of faces they graze (tests/stress/test_watertight.py, grazing rays).
// Included inside an ISA namespace.
#pragma once

struct LeafTri {
    float v[3][4];
    int32_t prim;
};

// A leaf triangle's box and its largest |coordinate|, for the hit point check: computed where
// a hit needs it (a padded copy made with every leaf triangle was no faster).
struct TriBox {
    float lo[3], hi[3], abs_max = 0.0f;
    explicit TriBox(const LeafTri& T) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(T.v[0][a], std::min(T.v[1][a], T.v[2][a]));
            hi[a] = std::max(T.v[0][a], std::max(T.v[1][a], T.v[2][a]));
            abs_max = std::max(abs_max, std::max(std::fabs(lo[a]), std::fabs(hi[a])));
        }
    }
};

template <int W>
struct RayGroup {
    vfloat<W> ok[3];     // origin in the ray's permuted axes (kx, ky, kz)
    vint<W> k[3];        // kx, ky, kz
    vfloat<W> S[2];      // shear: Sx = dir[kx] / dz, Sy = dir[ky] / dz
    vfloat<W> dz;        // dir[kz] (t = sheared z / dz: no reciprocal, denormal dz still works)
    vfloat<W> org[3], dir[3];  // as loaded (the hit point check)
    vfloat<W> tfar;
    vint<W> skip;        // triangle each lane ignores (-1: none)
    uint32_t id[W];
    uint32_t valid;      // lanes holding real rays
};

template <int W>
inline vfloat<W> pick(vint<W> k, const vfloat<W> v[3]) {
    return select(cmpeqi(k, splati<W>(0)), v[0], select(cmpeqi(k, splati<W>(1)), v[1], v[2]));
}

template <int W>
inline void load_group(const Ray* rays, size_t i, size_t na, const int32_t* skip, size_t nids, RayGroup<W>& g) {
    vfloat<W> r[8];
    g.valid = load_block<W>(rays, i, na, kInactiveRay, r);
    storeu(reinterpret_cast<float*>(g.id), r[7]);
    g.tfar = r[6];
    if (skip) {  // gathered once per group, then one compare per triangle
        alignas(64) int32_t sk[W];
        for (int l = 0; l < W; ++l) sk[l] = (g.valid >> l & 1u) && g.id[l] < nids ? skip[g.id[l]] : -1;
        g.skip = loadi<W>(sk);
    }
    const vfloat<W> org[3] = {r[0], r[1], r[2]};
    const vfloat<W> dir[3] = {r[3], r[4], r[5]};
    for (int a = 0; a < 3; ++a) { g.org[a] = org[a]; g.dir[a] = dir[a]; }
    const vfloat<W> ax = vabs(dir[0]), ay = vabs(dir[1]), az = vabs(dir[2]);
    const vbool<W> x_max = cmple(ay, ax) & cmple(az, ax);
    const vbool<W> y_max = cmple(az, ay);
    const vint<W> kz = selecti(x_max, splati<W>(0), selecti(y_max, splati<W>(1), splati<W>(2)));
    vint<W> kx = selecti(cmpeqi(kz, splati<W>(0)), splati<W>(1), selecti(cmpeqi(kz, splati<W>(1)), splati<W>(2), splati<W>(0)));
    vint<W> ky = selecti(cmpeqi(kz, splati<W>(0)), splati<W>(2), selecti(cmpeqi(kz, splati<W>(1)), splati<W>(0), splati<W>(1)));
    const vfloat<W> dz = pick(kz, dir);
    const vbool<W> flip = cmplt(dz, splat<W>(0.0f));  // keep the winding of the sheared frame
    const vint<W> tx = kx;
    kx = selecti(flip, ky, kx);
    ky = selecti(flip, tx, ky);
    g.k[0] = kx; g.k[1] = ky; g.k[2] = kz;
    g.S[0] = pick(kx, dir) / dz;
    g.S[1] = pick(ky, dir) / dz;
    g.dz = dz;
    for (int a = 0; a < 3; ++a) g.ok[a] = pick(g.k[a], org);
}

// Lanes the float test cannot decide reliably (an edge function exactly 0, |det| outside
// [2^-64, 2^64], or det small against its products): the inside test in double from the same
// float sheared coordinates -- products of two floats are exact in double, so the signs are
// exact and agree with the neighbouring triangle's float signs -- and u, v from those; t from
// the triangle's plane in double on the unsheared inputs (exact differences of floats), which
// stays accurate for slivers whose sheared vertices float rounding has moved across their
// width. Returns the lanes that hit (t, u, v written).
template <int W>
__attribute__((noinline, cold)) uint32_t exact_lanes(const vfloat<W> P[3][2], const Ray* rays, const LeafTri& T,
                                                     uint32_t lanes, vfloat<W>& To, vfloat<W>& Uo, vfloat<W>& Vo) {
    alignas(64) float p[3][2][W], t[W], u[W], v[W];
    for (int q = 0; q < 3; ++q) { storeu(p[q][0], P[q][0]); storeu(p[q][1], P[q][1]); }
    storeu(t, To); storeu(u, Uo); storeu(v, Vo);
    double e1[3], e2[3], n[3];
    for (int a = 0; a < 3; ++a) {
        e1[a] = double(T.v[1][a]) - T.v[0][a];
        e2[a] = double(T.v[2][a]) - T.v[0][a];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    uint32_t hit = 0;
    while (lanes) {
        const int j = __builtin_ctz(lanes);
        lanes &= lanes - 1;
        const double ax = p[0][0][j], ay = p[0][1][j], bx = p[1][0][j], by = p[1][1][j];
        const double cx = p[2][0][j], cy = p[2][1][j];
        const double U = cx * by - cy * bx, V = ax * cy - ay * cx, Wd = bx * ay - by * ax;
        if ((U < 0.0 || V < 0.0 || Wd < 0.0) && (U > 0.0 || V > 0.0 || Wd > 0.0)) continue;
        const double det = U + V + Wd;
        if (!(det != 0.0)) continue;  // ray in the triangle's plane (or out of range: NaN)
        const Ray& r = rays[j];
        double num = 0.0, den = 0.0;
        for (int a = 0; a < 3; ++a) {
            num += n[a] * (double(T.v[0][a]) - r.org[a]);
            den += n[a] * double(r.dir[a]);
        }
        t[j] = float(num / den);
        u[j] = float(V / det);
        v[j] = float(Wd / det);
        hit |= 1u << j;
    }
    To = loadu<W>(t); Uo = loadu<W>(u); Vo = loadu<W>(v);
    return hit;
}

// The hit point check (see the top): t is kept, raised or the hit dropped by the segment
// [0, t] against the triangle's box padded by kHitBoxTol (largest |box coordinate| + largest
// |origin coordinate|), evaluated in double (differences and quotients of floats, exact to
// 2^-53). The float check in intersect_leaf passes only points well inside that box (padding
// kFastBoxTol of the box's magnitude, less than kHitBoxTol minus its own rounding), where this
// keeps t as it is, so which of the two decides a lane never changes its result.
constexpr double kHitBoxTol = 0x1p-20;
constexpr float kFastBoxTol = 0x1p-21f;

// The lanes of the check that the float test could not pass; returns those kept (t raised
// where the padded box lies beyond it).
template <int W>
__attribute__((noinline, cold)) uint32_t box_lanes(const Ray* rays, const TriBox& B, uint32_t lanes, vfloat<W>& To) {
    alignas(64) float t[W];
    storeu(t, To);
    uint32_t keep = 0;
    while (lanes) {
        const int j = __builtin_ctz(lanes);
        lanes &= lanes - 1;
        const Ray& r = rays[j];
        double oabs = 0.0;
        for (int a = 0; a < 3; ++a) oabs = std::max(oabs, std::fabs(double(r.org[a])));
        const double tol = kHitBoxTol * (double(B.abs_max) + oabs);
        double s0 = 0.0, s1 = INFINITY;  // where the ray from its origin on is in the padded box
        for (int a = 0; a < 3; ++a) {
            const double l = double(B.lo[a]) - tol - r.org[a], h = double(B.hi[a]) + tol - r.org[a];
            if (r.dir[a] == 0.0f) {
                if (l > 0.0 || h < 0.0) s1 = -INFINITY;
                continue;
            }
            const double e0 = l / r.dir[a], e1 = h / r.dir[a];
            s0 = std::max(s0, std::min(e0, e1));
            s1 = std::min(s1, std::max(e0, e1));
        }
        if (!(s0 <= s1)) continue;  // misses the padded box, or it lies behind the origin
        const float tn = double(t[j]) < s0 ? float(s0) : t[j];
        if (!(tn < INFINITY)) continue;
        t[j] = tn;
        keep |= 1u << j;
    }
    To = loadu<W>(t);
    return keep;
}

// The hit point check of the lanes `lanes` (see the top), t raised where needed; returns the
// lanes kept.
template <int W>
__attribute__((always_inline)) inline uint32_t hits_on_segment(const RayGroup<W>& g, const Ray* rays, const LeafTri& T,
                                                   uint32_t lanes, vfloat<W>& t) {
    const TriBox B(T);
    const float pad = kFastBoxTol * B.abs_max;
    vbool<W> in = from_bits<W>(lanes);
    for (int a = 0; a < 3; ++a) {
        const vfloat<W> p = g.org[a] + t * g.dir[a];
        in = in & cmple(splat<W>(B.lo[a] - pad), p) & cmple(p, splat<W>(B.hi[a] + pad));
    }
    const uint32_t out = lanes & ~bits(in);
    return out ? (lanes & ~out) | box_lanes<W>(rays, B, out, t) : lanes;
}

// Lanes whose hit cannot count: t <= 0 or t beyond limit (the best t so far, or tfar), judged
// without dividing. The leaf's t = ((U/det) Pz0 + (V/det) Pz1 + (W/det) Pz2) / dz takes two
// divisions per triangle and ray group, the latency the loop waited on (perf: ~15% of leaf
// samples); most triangles a group reaches are inside for some lane but behind its best hit.
// With s = num sign(den), num = U Pz0 + V Pz1 + W Pz2, den = det dz, t ~ s / |den|. For
// lanes the float test decides (U, V, W one sign, none zero, |det| in [2^-64, 2^64]) both
// formulas round a sum of terms bounded by max|Pz| |det| (scaled by |den|): they differ by
// under 16 eps max|Pz| |det| + 4 eps |s|, so the margins here (2^-16 = 256 eps, and 2^-80
// absolute for denormal products) only cull lanes the exact test rejects: results are bit for
// bit those of dividing everywhere, also where t is a denormal (its rounding is absolute
// there: the limit gets 2^-148 more). NaN (overflowed products) and tiny |den| (< 2^-60,
// where den loses precision) are never culled.
template <int W>
__attribute__((always_inline)) inline vbool<W> beyond_limit(vfloat<W> U, vfloat<W> V, vfloat<W> Wf, vfloat<W> det,
                                                            const vfloat<W> Pz[3], vfloat<W> dz, vfloat<W> limit) {
    constexpr float kRel = 0x1p-16f;
    const vfloat<W> num = (U * Pz[0] + V * Pz[1]) + Wf * Pz[2];
    const vfloat<W> den = det * dz;
    const vfloat<W> s = xorsign(num, den), aden = vabs(den);
    const vfloat<W> M = vmax(vabs(Pz[0]), vmax(vabs(Pz[1]), vabs(Pz[2])));
    const vfloat<W> E = splat<W>(kRel) * (M * vabs(det)) + splat<W>(0x1p-80f);
    const vfloat<W> zero = splat<W>(0.0f);
    const vbool<W> behind = cmplt(s, zero - E);
    // (limit + 2^-148: a t in float's denormal range rounds to a multiple of 2^-149, up to half
    // of t; one just beyond the limit can round onto it and must be divided and compared)
    const vbool<W> beyond = cmplt((limit + splat<W>(0x1p-148f)) * aden + E, s - splat<W>(kRel) * vabs(s));
    return (behind | beyond) & cmple(splat<W>(0x1p-60f), aden);
}

// Skip: whether skip is given. A template parameter, not a test in the triangle loop: GCC made
// the two loops itself until the hit point check grew the function, and the single loop it
// then made ran occlusion leaves ~30% slower on AVX2 (San Francisco shadow rays).
template <int W, Query Q, bool Skip>
void intersect_leaf_k(Ray* rays, size_t na, const uint32_t* ids, size_t nt, const Box* boxes,
                      const CompactTri* tris, const uint32_t* prims, Hit* hits, uint8_t* occluded,
                      const int32_t* skip, size_t nids, const uint8_t* mask, uint8_t visible, Stats& st) {
    constexpr size_t kChunk = 32;
    alignas(64) LeafTri lt[kChunk];
    st.leaves += 1;
    const vfloat<W> zero = splat<W>(0.0f);
    for (size_t c0 = 0; c0 < nt; c0 += kChunk) {
        const size_t cl = std::min(kChunk, nt - c0);
        size_t cn = 0;
        for (size_t j = 0; j < cl; ++j) {
            const uint32_t s = ids[c0 + j], p = prims[s];
            if (mask && !(mask[p] & visible)) continue;  // not seen by this call's rays
            reconstruct(boxes[s], tris[s], lt[cn].v);
            lt[cn++].prim = int32_t(p);
        }
        if (cn == 0) continue;
        st.tri_tests += uint64_t(na) * cn;
        for (size_t i = 0; i < na; i += W) {
            RayGroup<W> g;
            load_group<W>(rays, i, na, Skip ? skip : nullptr, nids, g);
            const vbool<W> valid = from_bits<W>(g.valid);
            vfloat<W> best_t = g.tfar, best_u = zero, best_v = zero;
            vint<W> best_p = splati<W>(-2);  // -2: unknown (earlier leaves' best is in hits[id])
            uint32_t changed = 0, done = 0;
            for (size_t j = 0; j < cn; ++j) {
                const LeafTri& T = lt[j];
                vfloat<W> P[3][2], Pz[3];
                for (int q = 0; q < 3; ++q) {
                    const vfloat<W> x = permute(T.v[q], g.k[0]) - g.ok[0];
                    const vfloat<W> y = permute(T.v[q], g.k[1]) - g.ok[1];
                    Pz[q] = permute(T.v[q], g.k[2]) - g.ok[2];
                    P[q][0] = x - g.S[0] * Pz[q];
                    P[q][1] = y - g.S[1] * Pz[q];
                }
                const vfloat<W> a0 = P[2][0] * P[1][1], b0 = P[2][1] * P[1][0];
                const vfloat<W> a1 = P[0][0] * P[2][1], b1 = P[0][1] * P[2][0];
                const vfloat<W> a2 = P[1][0] * P[0][1], b2 = P[1][1] * P[0][0];
                const vfloat<W> U = a0 - b0, V = a1 - b1, Wf = a2 - b2;
                const vbool<W> neg = cmplt(vmin(U, vmin(V, Wf)), zero);
                const vbool<W> pos = cmplt(zero, vmax(U, vmax(V, Wf)));
                vbool<W> inside = andnot(neg & pos, valid);  // nonzero signs are exact: mixed = outside
                if (!any(inside)) continue;
                const vfloat<W> det = U + V + Wf;
#ifndef DACRT_NONROBUST
                const vfloat<W> adet = vabs(det);
                const vbool<W> zeros = cmpeq(U, zero) | cmpeq(V, zero) | cmpeq(Wf, zero);
                const vbool<W> in_range = cmple(splat<W>(0x1p-64f), adet) & cmple(adet, splat<W>(0x1p64f));
                // cancellation: sum |products| > 64 |det| would cost t more than ~2^-18 relative
                const vfloat<W> mag = (vabs(a0) + vabs(b0)) + (vabs(a1) + vabs(b1)) + (vabs(a2) + vabs(b2));
                const vbool<W> well = cmple(mag, adet * splat<W>(64.0f));
                const uint32_t slow = bits(andnot(andnot(zeros, in_range & well), inside));
#else
                const uint32_t slow = 0;
#endif
                inside = andnot(from_bits<W>(slow), inside);
                // The two divisions below only where the hit could count (see beyond_limit).
                inside = andnot(beyond_limit<W>(U, V, Wf, det, Pz, g.dz, Q == Query::Any ? g.tfar : best_t), inside);
                if (!slow && !any(inside)) continue;
                const vfloat<W> inv = splat<W>(1.0f) / det;
                vfloat<W> u = V * inv, v = Wf * inv;
                vfloat<W> t = ((U * inv) * Pz[0] + u * Pz[1] + v * Pz[2]) / g.dz;
                if (slow) {
                    st.double_fallbacks += __builtin_popcount(slow);
                    inside = inside | from_bits<W>(exact_lanes<W>(P, rays + i, T, slow, t, u, v));
                }
                // t in (0, inf): NaN (det 0 in the non-robust build) and overflowed t never hit
                vbool<W> ok = inside & cmplt(zero, t) & cmplt(t, splat<W>(INFINITY));
                if (Skip) ok = andnot(cmpeqi(g.skip, splati<W>(T.prim)), ok);  // never the triangle it leaves
                // The hit point check (see the top) runs on the lanes where this hit could count:
                // it only ever raises t, so a lane already beyond its best hit cannot matter.
                if (Q == Query::Any) {
                    uint32_t hit = bits(ok & cmplt(t, g.tfar)) & ~done;
#ifndef DACRT_NONROBUST
                    if (hit) hit = hits_on_segment<W>(g, rays + i, T, hit, t) & bits(cmplt(t, g.tfar));
#endif
                    done |= hit;
                    if (done == g.valid) break;
                    continue;
                }
#ifndef DACRT_NONROBUST
                const uint32_t counts = bits(ok & cmple(t, best_t));
                if (counts) ok = andnot(from_bits<W>(counts & ~hits_on_segment<W>(g, rays + i, T, counts, t)), ok);
#endif
                const vbool<W> closer = ok & cmplt(t, best_t);
                const vbool<W> tie = ok & cmpeq(t, best_t);
                vbool<W> take = closer;
                if (any(tie)) {  // rare: equal distance, lowest triangle index wins
                    alignas(64) int32_t bp[W];
                    storei(bp, best_p);
                    uint32_t tl = bits(tie), win = 0;
                    while (tl) {
                        const int l = __builtin_ctz(tl);
                        tl &= tl - 1;
                        if (bp[l] == -2) bp[l] = g.id[l] < nids ? hits[g.id[l]].prim : -1;
                        if (bp[l] == -1 || T.prim < bp[l]) win |= 1u << l;
                    }
                    take = take | from_bits<W>(win);
                }
                const uint32_t tk = bits(take);
                if (!tk) continue;
                changed |= tk;
                best_t = select(take, t, best_t);
                best_u = select(take, u, best_u);
                best_v = select(take, v, best_v);
                best_p = selecti(take, splati<W>(T.prim), best_p);
            }
            if (Q == Query::Any) {
                while (done) {
                    const int l = __builtin_ctz(done);
                    done &= done - 1;
                    rays[i + l].tfar = kOccludedTfar;
                    if (g.id[l] < nids) occluded[g.id[l]] = 1;  // see TraceJob::num_ids
                }
                continue;
            }
            if (!changed) continue;
            alignas(64) float bt[W], bu[W], bv[W];
            alignas(64) int32_t bp[W];
            storeu(bt, best_t); storeu(bu, best_u); storeu(bv, best_v); storei(bp, best_p);
            while (changed) {
                const int l = __builtin_ctz(changed);
                changed &= changed - 1;
                rays[i + l].tfar = bt[l];
                if (g.id[l] < nids) hits[g.id[l]] = Hit{bt[l], bp[l], bu[l], bv[l]};  // see TraceJob::num_ids
            }
        }
    }
}

template <int W, Query Q>
void intersect_leaf(Ray* rays, size_t na, const uint32_t* ids, size_t nt, const Box* boxes,
                    const CompactTri* tris, const uint32_t* prims, Hit* hits, uint8_t* occluded, const int32_t* skip,
                    size_t nids, const uint8_t* mask, uint8_t visible, Stats& st) {
    if (skip) intersect_leaf_k<W, Q, true>(rays, na, ids, nt, boxes, tris, prims, hits, occluded, skip, nids, mask, visible, st);
    else intersect_leaf_k<W, Q, false>(rays, na, ids, nt, boxes, tris, prims, hits, occluded, skip, nids, mask, visible, st);
}
