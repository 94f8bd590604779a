"""Agreement of DACRT's hits with Embree's on the benchmark rays, and a float64 brute-force
verdict on the rays where they differ.

Every differing ray (different primitive, or the same primitive at distances further apart than
float32 precision allows) is first screened cheaply: if both report the same distance (within a
tolerance of the scene's float32 precision) and each claimed triangle is confirmed in float64 to
lie there, it is a tie at a shared edge or between coincident triangles, and both are right. The
rest are traced again in float64 against every triangle (Moller-Trumbore, no epsilon) to tell
which tracer was right; a hit or miss within float32 precision of a triangle edge counts as right
either way. Rays where DACRT is wrong become reproducers in the report (scene, ray index, org,
dir, tfar). The headline agreement figure is `same_prim`: the share of rays where DACRT's
primitive equals Embree's (`same_answer` for occlusion).
"""

from __future__ import annotations

import numpy as np

MAX_CHECKED = 48   # brute-force verdicts per ray set (each costs one pass over all triangles)
MAX_REPRO = 5      # reproducers kept per ray set


def _scale(vertices: np.ndarray) -> float:
    return float(np.abs(vertices).max()) if len(vertices) else 1.0


def _brute_force(p0, e1, e2, o, d):
    """All (t, b1, b2) of one float64 ray against all triangles; t = nan where parallel."""
    pvec = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pvec)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tvec = o - p0
        b1 = np.einsum("ij,ij->i", tvec, pvec) * inv
        qvec = np.cross(tvec, e1)
        b2 = (qvec @ d) * inv
        t = np.einsum("ij,ij->i", e2, qvec) * inv
    t[det == 0] = np.nan
    return t, b1, b2


class Reference:
    """float64 copies of a scene's triangles for brute-force verdicts."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        v = vertices.astype(np.float64)
        self.p0 = v[triangles[:, 0]]
        self.e1 = v[triangles[:, 1]] - self.p0
        self.e2 = v[triangles[:, 2]] - self.p0
        # altitudes over each edge, to turn barycentric margins into distances
        area2 = np.linalg.norm(np.cross(self.e1, self.e2), axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.alt = np.stack([area2 / np.linalg.norm(self.e2 - self.e1, axis=1),
                                 area2 / np.linalg.norm(self.e2, axis=1),
                                 area2 / np.linalg.norm(self.e1, axis=1)], 1)
        self.tol = 1e-5 * _scale(vertices)      # ~ float32 precision of the coordinates, x100

    def candidates(self, o, d, tfar):
        """Triangles hit by the ray in (0, tfar] with their t and signed distance of the hit
        point to the nearest triangle edge (negative = just outside)."""
        o, d = np.asarray(o, np.float64), np.asarray(d, np.float64)
        t, b1, b2 = _brute_force(self.p0, self.e1, self.e2, o, d)
        edge = np.min(np.stack([1 - b1 - b2, b1, b2], 1) * self.alt, axis=1)
        # t > 0 strictly: the origin's own triangle lies just behind the offset origin.
        near = np.isfinite(t) & (t > 0) & (t <= tfar + self.tol) & (edge > -self.tol)
        idx = np.nonzero(near)[0]
        return idx, t[idx], edge[idx]

    def claims_hold(self, org, dirs, prim, t) -> np.ndarray:
        """Vectorised over rays: does triangle prim[i] really meet ray i (float64) at about
        t[i], inside the triangle up to float32 precision? False for prim < 0."""
        ok = prim >= 0
        k = np.nonzero(ok)[0]
        if len(k) == 0:
            return ok
        o, d, p = org[k].astype(np.float64), dirs[k].astype(np.float64), prim[k]
        e1, e2 = self.e1[p], self.e2[p]
        pvec = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, pvec)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tvec = o - self.p0[p]
            b1 = np.einsum("ij,ij->i", tvec, pvec) * inv
            qvec = np.cross(tvec, e1)
            b2 = np.einsum("ij,ij->i", qvec, d) * inv
            t64 = np.einsum("ij,ij->i", e2, qvec) * inv
        edge = np.min(np.stack([1 - b1 - b2, b1, b2], 1) * self.alt[p], axis=1)
        tk = t[k].astype(np.float64)
        good = (det != 0) & (t64 > 0) & (edge > -self.tol) & \
            (np.abs(t64 - tk) <= self.tol + 1e-5 * np.abs(t64))
        ok = ok.copy()
        ok[k] = good
        return ok

    def judge_intersect(self, o, d, tfar, prim, t):
        """Is (prim, t) an acceptable closest hit of the ray? Returns (ok, exact closest prim,
        its t) in float64."""
        idx, tt, edge = self.candidates(o, d, tfar)
        strict = (edge >= 0) & (tt > 0) & (tt <= tfar)
        ref_prim, ref_t = -1, np.inf
        if strict.any():
            k = np.argmin(np.where(strict, tt, np.inf))
            ref_prim, ref_t = int(idx[k]), float(tt[k])
        # Closest acceptable distance: hits that are in by float32 precision may count.
        firm = strict & (edge > self.tol)
        t_firm = float(tt[firm].min()) if firm.any() else np.inf
        if prim < 0:
            return bool(t_firm == np.inf), ref_prim, ref_t
        at = np.nonzero(idx == prim)[0]
        if len(at) == 0:
            return False, ref_prim, ref_t
        tp = float(tt[at[0]])
        ok = abs(tp - t) <= self.tol + 1e-5 * abs(tp) and tp <= t_firm + self.tol + 1e-5 * tp
        return bool(ok), ref_prim, ref_t

    def judge_occluded(self, o, d, tfar, occluded):
        """Is the occlusion answer acceptable? Returns (ok, float64 answer)."""
        idx, tt, edge = self.candidates(o, d, tfar)
        inside = (tt > 0) & (tt < tfar)
        firm = inside & (edge > self.tol) & (tt > self.tol) & (tt < tfar - self.tol)
        ref = bool(inside[edge >= 0].any())
        if occluded:
            return bool(len(idx) > 0), ref        # any hit within tolerance justifies it
        return bool(not firm.any()), ref


def _repro(scene_name, rays, i, **extra):
    return dict(scene=scene_name, set=rays.kind, query=rays.query, ray=int(i),
                org=rays.org[i].tolist(), dir=rays.dir[i].tolist(), tfar=float(rays.tfar[i]),
                **extra)


def compare_intersect(ref: Reference, scene_name, rays, d_hits, e_hits) -> dict:
    """d_hits: DACRT HIT_DTYPE array by ray id; e_hits: Embree (prim, t, u, v)."""
    dp, dt = d_hits["prim"], d_hits["t"]
    ep, et = e_hits[0], e_hits[1]
    n = len(dp)
    same = dp == ep
    both = same & (dp >= 0)
    rel = np.abs(dt[both] - et[both]) / np.maximum(np.abs(et[both]), 1e-30)
    diff = np.nonzero(~same)[0]
    # A tie: both hit, at the same distance, and each claimed triangle really is there.
    tie = (dp[diff] >= 0) & (ep[diff] >= 0) & \
        (np.abs(dt[diff] - et[diff]) <= ref.tol + 1e-5 * np.abs(et[diff]))
    tie &= ref.claims_hold(rays.org[diff], rays.dir[diff], dp[diff], dt[diff])
    tie &= ref.claims_hold(rays.org[diff], rays.dir[diff], ep[diff], et[diff])
    # Same triangle but a distance apart by more than float32 precision allows: judged too.
    both_i = np.nonzero(both)[0]
    t_off = both_i[np.abs(dt[both_i] - et[both_i]) > ref.tol + 1e-5 * np.abs(et[both_i])]
    hard = np.concatenate([diff[~tie], t_off])
    out = dict(rays=n, same_prim=float(same.mean()) if n else 1.0,
               hit_fraction_dacrt=float((dp >= 0).mean()) if n else 0.0,
               hit_fraction_embree=float((ep >= 0).mean()) if n else 0.0,
               differ=int(len(diff)), ties_same_t=int(tie.sum()),
               dacrt_hit_embree_miss=int(((dp[diff] >= 0) & (ep[diff] < 0)).sum()),
               dacrt_miss_embree_hit=int(((dp[diff] < 0) & (ep[diff] >= 0)).sum()),
               same_prim_t_mismatch=int(len(t_off)),
               t_rel_diff_same_prim_max=float(rel.max()) if len(rel) else 0.0,
               t_rel_diff_same_prim_p99=float(np.quantile(rel, 0.99)) if len(rel) else 0.0)
    checked = hard[np.linspace(0, len(hard) - 1, min(len(hard), MAX_CHECKED)).astype(int)] \
        if len(hard) else hard
    d_wrong, e_wrong, repro = 0, 0, []
    for i in checked:
        o, d, tf = rays.org[i], rays.dir[i], float(rays.tfar[i])
        d_ok, rp, rt = ref.judge_intersect(o, d, tf, int(dp[i]), float(dt[i]))
        e_ok, _, _ = ref.judge_intersect(o, d, tf, int(ep[i]), float(et[i]))
        d_wrong += not d_ok
        e_wrong += not e_ok
        if not d_ok and len(repro) < MAX_REPRO:
            repro.append(_repro(scene_name, rays, i, dacrt=[int(dp[i]), float(dt[i])],
                                embree=[int(ep[i]), float(et[i])], float64=[rp, rt]))
    out.update(checked=int(len(checked)), dacrt_wrong=int(d_wrong), embree_wrong=int(e_wrong),
               dacrt_wrong_examples=repro)
    return out


def compare_occluded(ref: Reference, scene_name, rays, d_occ, e_occ) -> dict:
    n = len(d_occ)
    same = d_occ == e_occ
    diff = np.nonzero(~same)[0]
    out = dict(rays=n, same_answer=float(same.mean()) if n else 1.0,
               occluded_fraction_dacrt=float(d_occ.mean()) if n else 0.0,
               occluded_fraction_embree=float(e_occ.mean()) if n else 0.0,
               differ=int(len(diff)))
    checked = diff[np.linspace(0, len(diff) - 1, min(len(diff), MAX_CHECKED)).astype(int)] \
        if len(diff) else diff
    d_wrong, e_wrong, repro = 0, 0, []
    for i in checked:
        o, d, tf = rays.org[i], rays.dir[i], float(rays.tfar[i])
        d_ok, r = ref.judge_occluded(o, d, tf, bool(d_occ[i]))
        e_ok, _ = ref.judge_occluded(o, d, tf, bool(e_occ[i]))
        d_wrong += not d_ok
        e_wrong += not e_ok
        if not d_ok and len(repro) < MAX_REPRO:
            repro.append(_repro(scene_name, rays, i, dacrt=bool(d_occ[i]),
                                embree=bool(e_occ[i]), float64=r))
    out.update(checked=int(len(checked)), dacrt_wrong=int(d_wrong), embree_wrong=int(e_wrong),
               dacrt_wrong_examples=repro)
    return out
