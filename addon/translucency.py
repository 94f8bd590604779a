"""Diffuse transmission (Translucent BSDF and Principled's diffuse transmission), part of the
Integrator (a mixin of it): which hits transmit, the reflection-or-transmission lobe chosen per
vertex and weighted back, and light sampling of the far side, whose receivers face away from
the incoming ray."""
from __future__ import annotations

import numpy as np

from .sampling import DIM_LOBE, max3

F32 = np.float32


class Translucency:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    def _translucent_hits(self, prim, thr):
        """Diffuse transmission (Translucent BSDF): at hits on translucent materials, whose
        throughput continue_paths left before any albedo, thr takes the reflection's albedo R
        (the base colour; its maps follow) in place, and (sel (j,) those hits' columns, thr_far
        (3, j) their throughput x T, p (j,) the transmission's pick probability for
        _choose_lobes) is returned; None when no hit is on one. Light sampling then takes both
        lobes (T's from the far side, far_side), as Cycles evaluates every closure; the bounce
        takes one (_choose_lobes)."""
        mat = np.take(self.tri.material, prim)
        sel = np.flatnonzero(np.take(self.mats.translucent, mat))
        if not len(sel):
            return None
        m = np.take(mat, sel)
        R = np.take(self.mats.base, m, axis=1)
        T = np.take(self.mats.translucency, m, axis=1)
        before = np.take(thr, sel, axis=1)
        thr[:, sel] = before * R
        rt, tt = max3(R), max3(T)
        return sel, before * T, tt / (rt + tt)           # tt > 0 on translucent materials

    def _translucency_maps(self, sel, prim, u, v, thr_far, ng, incoming):
        """Multiply the transmission that varies per point (mats.translucency_textures: over
        the material's own) into thr_far (3, len(sel)) in place, at the hits sel of (prim, u, v),
        ng (3, k) their normals facing the rays, incoming (3, k) the rays' directions negated."""
        take = lambda a: np.take(a, sel, axis=-1)  # noqa: E731
        self._texture(take(prim), take(u), take(v), thr_far, textures=self.mats.translucency_textures,
                      back=self._back(take(prim), take(ng), take(incoming)))

    def _translucency_at(self, prim, u, v, back=None):
        """(3, k) the diffuse transmission's colour at hits (prim, u, v), per point where it varies."""
        T = np.take(self.mats.translucency, np.take(self.tri.material, prim), axis=1)
        if self.mats.translucency_textures:
            self._texture(prim, u, v, T, textures=self.mats.translucency_textures, back=back)
        return T

    def _next_event_far(self, k, sel, thr_far, P, ng, ns, P_off, prim, pid, keys, u_pick, sinks, tb, u, v, dims,
                        ns_far=None, bump=None, xb=None):
        """Light sampling of the transmission lobe at the vertices sel (columns of the other
        arrays) of translucent surfaces, from their far side (far_side), with throughput
        thr_far (3, len(sel)) and random dimensions dims of its own; ns_far (3, len(sel)): the
        lobe's own normal where it is not ns (valid_reflection_normal); bump: _bent_normals'
        rows of all the columns, or None."""
        fP, fng, fns, fP_off = far_side(sel, P, ng, ns, P_off, ns_far)
        take = lambda a: None if a is None else np.take(a, sel, axis=-1)  # noqa: E731
        # Cycles' bsdf_eval takes the bump shadowing term of every diffuse-labelled closure,
        # the Translucent BSDF's too (from the far side: the smooth normal turned as fns is);
        # a back-lit leaf bumped at distance 1 was 15% bright without it. It applies no
        # terminator shading offset to a transmitted sample (0.69 / 0.72 / 0.81 of its mean
        # with an offset of 0.3, when it was)
        far_bump = None
        if bump is not None:
            far_bump = np.take(bump, sel, axis=1)
            far_bump[:3] *= F32(-1.0)
        elif ns_far is not None:
            # a smooth normal the lobe raised (valid_reflection_normal) is one it differs from:
            # the term applies there too (1 where it was not raised)
            far_bump = np.empty((4, len(sel)), F32)
            far_bump[:3] = -take(ns)
            far_bump[3] = np.take(self.mats.bump_correction, np.take(self.tri.material, take(prim)))
        self._next_event(k, fP, fP_off, take(prim), fng, fns, np.ascontiguousarray(thr_far, F32), take(pid),
                         np.ascontiguousarray(take(keys)), take(u_pick), sinks.sampled(k), take(tb), take(u),
                         take(v), sinks.groups, far_bump, dims=dims, shading_offset=False, xb=take(xb))

    def _choose_lobes(self, k, far, keys, thr, P, ns, ng, P_off, ns_far=None):
        """The bounce's lobe at translucent hits (far: _translucent_hits'): the transmission with
        probability p = max(T) / (max(R) + max(T)), its throughput / p, else the reflection's
        (in thr, with its maps) / (1 - p); the transmitting vertices moved to the far side. The
        bounce's pdf for MIS stays the lobe's cosine (p left out on both sides of the
        heuristic: the weights still sum to one, and p > 0 wherever a lobe's albedo is).
        Returns (ns, ng, P_off, moved: the transmitting columns, or None)."""
        sel, thr_far, p = far
        u, _ = self.rng.uniform2(np.take(keys, sel, axis=1), DIM_LOBE + 2 * k)
        go = u < p
        near = np.take(thr, sel, axis=1) / np.where(go, F32(1.0), F32(1.0) - p)
        thr[:, sel] = np.where(go, thr_far / p, near)
        if not go.any():
            return ns, ng, P_off, None
        cols = sel[go]
        moved = np.zeros(len(ns[0]), bool)
        moved[cols] = True
        _, fng, fns, fP_off = far_side(cols, P, ng, ns, P_off, None if ns_far is None else ns_far[:, go])
        shared = ng is ns
        ns, P_off = ns.copy(), P_off.copy()
        ns[:, cols], P_off[:, cols] = fns, fP_off
        if shared:
            ng = ns
        else:
            ng = ng.copy()
            ng[:, cols] = fng
        return ns, ng, P_off, moved


def far_side(sel, P, ng, ns, P_off, ns_sel=None):
    """The vertices sel seen from the far side of their surface, for its diffuse transmission:
    (P, ng, ns, P_off) of those columns with the normals turned (ns_sel: the shading normals of
    those columns to turn instead of ns's) and the offset point mirrored through the hit point,
    so light sampling treats each as a reflector facing away from the incoming ray."""
    fP, fPo = np.take(P, sel, axis=1), np.take(P_off, sel, axis=1)
    fns = -(np.take(ns, sel, axis=1) if ns_sel is None else ns_sel)
    fng = fns if ng is ns else -np.take(ng, sel, axis=1)
    return fP, fng, fns, (fP + (fP - fPo)).astype(F32)


def valid_reflection_normal(Ng, I, N, correction):
    """Cycles' ensure_valid_specular_reflection (closure/bsdf_util.h), which it gives the
    Translucent BSDF's normal under Bump Map Correction (correction (k,) bool; its
    maybe_ensure_valid_specular_reflection): a bent normal N whose mirror reflection of the
    view direction I would dip below the geometric normal Ng's plane is raised toward Ng just
    enough; all (3, k), Ng and N facing I. Float64 inside, float32 out."""
    out = np.array(N, F32)
    Ng, I, N = (np.asarray(a, np.float64) for a in (Ng, I, N))
    dot = lambda a, b: (a * b).sum(axis=0)  # noqa: E731
    R = 2.0 * dot(N, I) * N - I
    Iz = dot(I, Ng)
    t = np.minimum(0.9 * Iz, 0.01)
    # (only those that dip are raised: the Normal pass calls this for every camera hit)
    raise_at = np.flatnonzero(~(~np.broadcast_to(correction, Iz.shape) | (dot(Ng, R) >= t)))
    if not len(raise_at):
        return out
    Ng, I, N, Iz, t = Ng[:, raise_at], I[:, raise_at], N[:, raise_at], Iz[raise_at], t[raise_at]
    X = N - dot(N, Ng) * Ng
    length = np.sqrt(dot(X, X))
    X = np.where(length > 0, X / np.where(length > 0, length, 1.0), N)
    Ix = dot(I, X)
    a = Ix * Ix + Iz * Iz
    b = 2.0 * (a + Iz * t)
    c = (t + Iz) ** 2
    root = np.sqrt(np.maximum(b * b - 4.0 * a * c, 0.0))
    with np.errstate(divide='ignore', invalid='ignore'):
        Nz2 = np.where(Ix < 0, 0.25 * (b + root) / a, 0.25 * (b - root) / a)
    Nz2 = np.nan_to_num(Nz2, nan=1.0)
    raised = np.sqrt(np.maximum(1.0 - Nz2, 0.0)) * X + np.sqrt(np.maximum(Nz2, 0.0)) * Ng
    out[:, raise_at] = raised
    return out
