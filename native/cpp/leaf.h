// Leaf intersection: every active ray against every triangle of the leaf, W rays x 1 triangle
// per SIMD step, with the watertight test of Woop, Benthin and Wald (JCGT 2013).
//
// Watertightness: each ray is sheared so it becomes the +z axis of a per-ray frame (kz = largest
// |dir| component); a shared vertex then gets bit-identical 2D coordinates in both triangles
// that use it (same operations, no FMA contraction), so the edge function of a shared edge has
// exactly opposite values in the two triangles. Where an edge function is exactly 0 it is
// recomputed in double (exact for these float products) so its sign is exact too. A ray can
// therefore never slip between two triangles that share an edge or a vertex.
// Ties (equal t) go to the lowest triangle index, so results do not depend on traversal order,
// thread count or ISA. Included inside an ISA namespace.
#pragma once

struct LeafTri {
    float v[3][4];
    int32_t prim;
};

template <int W>
struct RayGroup {
    vfloat<W> ok[3];     // origin in the ray's permuted axes (kx, ky, kz)
    vint<W> k[3];        // kx, ky, kz
    vfloat<W> S[3];      // shear: Sx, Sy, Sz
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
inline void load_group(const Ray* rays, size_t i, size_t na, const int32_t* skip, RayGroup<W>& g) {
    vfloat<W> r[8];
    g.valid = load_block<W>(rays, i, na, kInactiveRay, r);
    storeu(reinterpret_cast<float*>(g.id), r[7]);
    g.tfar = r[6];
    if (skip) {  // gathered once per group, then one compare per triangle
        alignas(64) int32_t sk[W];
        for (int l = 0; l < W; ++l) sk[l] = (g.valid >> l & 1u) ? skip[g.id[l]] : -1;
        g.skip = loadi<W>(sk);
    }
    const vfloat<W> org[3] = {r[0], r[1], r[2]};
    const vfloat<W> dir[3] = {r[3], r[4], r[5]};
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
    g.S[2] = splat<W>(1.0f) / dz;
    for (int a = 0; a < 3; ++a) g.ok[a] = pick(g.k[a], org);
}

// Edge functions exactly 0 in float: recompute in double from the same sheared coordinates.
template <int W>
inline void exact_edges(vfloat<W>& U, vfloat<W>& V, vfloat<W>& Wf, const vfloat<W>& Ax, const vfloat<W>& Ay,
                        const vfloat<W>& Bx, const vfloat<W>& By, const vfloat<W>& Cx, const vfloat<W>& Cy,
                        uint32_t lanes) {
    alignas(64) float u[W], v[W], w[W], ax[W], ay[W], bx[W], by[W], cx[W], cy[W];
    storeu(u, U); storeu(v, V); storeu(w, Wf);
    storeu(ax, Ax); storeu(ay, Ay); storeu(bx, Bx); storeu(by, By); storeu(cx, Cx); storeu(cy, Cy);
    while (lanes) {
        const int j = __builtin_ctz(lanes);
        lanes &= lanes - 1;
        u[j] = float(double(cx[j]) * double(by[j]) - double(cy[j]) * double(bx[j]));
        v[j] = float(double(ax[j]) * double(cy[j]) - double(ay[j]) * double(cx[j]));
        w[j] = float(double(bx[j]) * double(ay[j]) - double(by[j]) * double(ax[j]));
    }
    U = loadu<W>(u); V = loadu<W>(v); Wf = loadu<W>(w);
}

template <int W, Query Q>
void intersect_leaf(Ray* rays, size_t na, const uint32_t* ids, size_t nt, const Box* boxes,
                    const CompactTri* tris, Hit* hits, uint8_t* occluded, const int32_t* skip, Stats& st) {
    constexpr size_t kChunk = 32;
    alignas(64) LeafTri lt[kChunk];
    st.leaves += 1;
    st.tri_tests += uint64_t(na) * nt;
    const vfloat<W> zero = splat<W>(0.0f);
    for (size_t c0 = 0; c0 < nt; c0 += kChunk) {
        const size_t cn = std::min(kChunk, nt - c0);
        for (size_t j = 0; j < cn; ++j) {
            const uint32_t p = ids[c0 + j];
            reconstruct(boxes[p], tris[p], lt[j].v);
            lt[j].prim = int32_t(p);
        }
        for (size_t i = 0; i < na; i += W) {
            RayGroup<W> g;
            load_group<W>(rays, i, na, skip, g);
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
                vfloat<W> U = P[2][0] * P[1][1] - P[2][1] * P[1][0];
                vfloat<W> V = P[0][0] * P[2][1] - P[0][1] * P[2][0];
                vfloat<W> Wf = P[1][0] * P[0][1] - P[1][1] * P[0][0];
#ifndef DACRT_NONROBUST
                const uint32_t zeros = bits((cmpeq(U, zero) | cmpeq(V, zero) | cmpeq(Wf, zero)) & valid);
                if (zeros) {
                    st.double_fallbacks += __builtin_popcount(zeros);
                    exact_edges<W>(U, V, Wf, P[0][0], P[0][1], P[1][0], P[1][1], P[2][0], P[2][1], zeros);
                }
#endif
                const vbool<W> neg = cmplt(vmin(U, vmin(V, Wf)), zero);
                const vbool<W> pos = cmplt(zero, vmax(U, vmax(V, Wf)));
                const vbool<W> inside = andnot(neg & pos, valid);
                if (!any(inside)) continue;
                const vfloat<W> det = U + V + Wf;
                const vfloat<W> Tn = U * (g.S[2] * Pz[0]) + V * (g.S[2] * Pz[1]) + Wf * (g.S[2] * Pz[2]);
                const vfloat<W> inv = splat<W>(1.0f) / det;
                const vfloat<W> t = Tn * inv;
                vbool<W> ok = andnot(cmpeq(det, zero), inside) & cmplt(zero, t);
                if (skip) ok = andnot(cmpeqi(g.skip, splati<W>(T.prim)), ok);  // never the triangle it leaves
                if (Q == Query::Any) {
                    const uint32_t hit = bits(ok & cmplt(t, g.tfar)) & ~done;
                    done |= hit;
                    if (done == g.valid) break;
                    continue;
                }
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
                        if (bp[l] == -2) bp[l] = hits[g.id[l]].prim;
                        if (bp[l] == -1 || T.prim < bp[l]) win |= 1u << l;
                    }
                    take = take | from_bits<W>(win);
                }
                const uint32_t tk = bits(take);
                if (!tk) continue;
                changed |= tk;
                const vfloat<W> u = V * inv, v = Wf * inv;
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
                    occluded[g.id[l]] = 1;
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
                hits[g.id[l]] = Hit{bt[l], bp[l], bu[l], bv[l]};
            }
        }
    }
}
