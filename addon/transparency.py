"""Transparent surfaces, part of the Integrator (a mixin of it): camera and bounce rays passing
or stopping at cut-outs, Transparent BSDFs and clear glass at random (weighted so the estimate
stays unbiased, counted against Transparent and Transmission Max Bounces), light sampled at
passed semi-transparent surfaces, emission and the world seen along passed segments, and shadow
rays dimmed by every transparent surface they cross."""
from __future__ import annotations

import numpy as np

import dacrt

from .pathstate import Paths, clamp_classes, compact, diffuse_reflections
from .sampling import DIM_GLASS, DIM_LOBE, DIM_PASSED, DIM_ROULETTE, DIM_TRANSPARENT
from .scenedata import HOLDOUT
from .specular import view_table
from .translucency import valid_reflection_normal

F32 = np.float32

# the first bounce Cycles' Russian roulette may end (bounce > min_bounce, which it stores as
# Min Light Bounces (0) + 1); glass passes count as bounces (Transparency._glass_roulette)
ROULETTE_FROM = 2


def light_classes(k, xb, contrib, clamps):
    """[(mask, clamp)]: the light samples taken at vertex k (contrib: those that count) split by
    Cycles' clamp classes: the path's bounce count there is k plus its glass passes xb."""
    return [(contrib if m is None else contrib & m, c) for m, c in clamp_classes(k, xb, clamps)]


class Transparency:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    def _opaque_weight_at(self, prim, u, v, mat, back):
        """((k,) Materials.opaque_weight at hits (prim, u, v) of materials mat, with the colour
        textures, attribute colours and translucency textures of those that have them; (3, k)
        the albedo there, which _light_passed reuses for the paths that pass)."""
        albedo = np.take(self.mats.base, mat, axis=1)
        if self._albedo_varies:
            self._albedo_maps(prim, u, v, albedo, back)
        weight = albedo + self._translucency_at(prim, u, v, back) if self._any_translucent else albedo
        return weight.mean(axis=0).astype(F32), albedo

    def _through(self, k, camera, path, hits, sinks, chain=None):
        """Rays that hit a transparent surface pass it or stop there, at random by the
        transparent and the opaque weights (as Cycles picks a closure by its mean weight; the
        estimate is the same whichever probability p is used). Passing multiplies the
        throughput by transparency / p and traces on from just behind the surface, gathering
        the lamps along the new segment and the world where it then misses; stopping
        multiplies it by opacity / (1 - p), so all the surface does next (emission, reflection,
        light sampling) carries its weight. hits, path.thr and path.tb (surfaces passed) change in
        place; a path that has passed max_transparent transparent surfaces (at least one) stops
        at the next one (Cycles' PATH_RAY_TERMINATE_ON_NEXT_SURFACE, _vertex).

        One step per layer of surfaces, whose fixed cost, not the ray count, sets the time of a
        stack of cut-outs (20 layers had made this loop ~90% of a render): the columns of the
        rays still passing are kept compacted (h, D, keys, tmax; one native gather a step for
        them all, not a take per field from the block's arrays), and the surface a ray passes
        is computed once for its light sample and its next segment."""
        kind = 'camera' if camera else self._bounce_kind(k)
        thr = path.thr
        rows = None                             # all rays, then those that passed
        h, D, keys, tmax = hits, path.D, path.keys, path.tmax     # their columns at rows
        j = 0
        while True:
            prim = np.ascontiguousarray(h['prim'])
            at = np.flatnonzero((prim >= 0) & np.take(self._tri_transparent, np.maximum(prim, 0)))
            if not len(at):
                return
            if rows is None or len(at) < len(rows):
                rows, prim, h = (at if rows is None else rows[at]), prim[at], h[at]
                D, keys, tmax = compact(at, D, keys, tmax)
            if thr is None:                     # camera rays: throughput 1 until now
                thr = path.thr = np.ones((3, len(hits)), F32)
            if path.tb is None:
                path.tb = np.zeros(len(hits), np.int32)
            if path.gb is None:             # (a translucent bounce may have made it)
                path.gb = np.zeros(len(hits), np.int32)
            if path.xb is None:
                path.xb = np.zeros(len(hits), np.int32)
            # Cycles counts transparent surfaces over the whole path: once a pass reaches the
            # limit, the next surface, this one too, is not passed (nor lit, nor bounced off:
            # _vertex); what it emits still counts. Glass: against its own limit
            u_hit, v_hit = np.ascontiguousarray(h['u']), np.ascontiguousarray(h['v'])
            tau, opacity, mat = self._transparency(prim, u_hit, v_hit, None if not self._sided else
                                                   self._back(prim, -D, -D))
            glass = np.take(self._mat_glass, mat)
            if self._opaque_glass:
                glass = 2.0 * self._glass_part(mat, tau, opacity).mean(axis=0) > tau.mean(axis=0)
            tb, gb, xb = compact(rows, path.tb, path.gb, path.xb)
            # (glass: Cycles refracts at a surface after n transmissions while n <= the limit, two
            # clear panes before an emitter seen through at limit 1: they had been black there)
            # Past Total Max Bounces (k + glass passes over it) glass is not passed either, as
            # Cycles keeps only transparent closures there; clear surfaces still are
            spent_total = k + xb > self._total_stop
            spent = np.where(glass, (gb > self._glass_stop) | spent_total, tb >= self._transparent_stop)
            # (paths past their diffuse reflections, where translucent bounces let k pass Max
            # Bounces, pass as at k = Max Bounces + 1: unlit)
            unlit = spent_total | (diffuse_reflections(k, gb, xb) > self._diffuse_stop) if self._translucent_apart else spent_total
            surface = None
            if chain is not None:                   # what the data passes read here, before the pick
                surface = self._surface(h, None, D)
                entry = dict(rows=rows, prim=prim, u=u_hit, v=v_hit, thr=thr[:, rows], tau=tau,
                             opacity=opacity, P=surface[0], ng=surface[1], ns=surface[2],
                             glass=self._glass_part(mat, tau, opacity))
                # (none at a surface met after Transparent Max Bounces passes: Cycles ends the
                # path there before its data passes, Integrator._passes_before_limit)
                lim = tb >= self._transparent_stop
                if lim.any():
                    entry = {key: x[..., ~lim] for key, x in entry.items()}
                if len(entry['rows']):
                    chain.append(entry)
            if self._any_emissive:
                self._emission_before_pick(camera, k, path, hits, rows, prim, opacity, sinks)
                if path.emitted is not None:    # (counted at the roulette: once is enough)
                    path.emitted[rows] = False
            t_mean = tau.mean(axis=0)
            if chain is not None and (self._albedo_varies or self.mats.translucency_textures):
                # Cycles weighs the opaque closures by their colours at the point: a textured
                # one's texel, not the material's constant factor (a sheet of Alpha 0.49 and a
                # Checker base had stopped too many paths, the Normal pass behind it 0.90x).
                # Only where data passes are written along the chain: elsewhere the pick changes
                # the noise alone, not the estimate, and the lookups cost 20-30% of a textured
                # cut-out's render
                w_opaque, albedo_at = self._opaque_weight_at(prim, u_hit, v_hit, mat,
                                                             None if not self._sided else self._back(prim, -D, -D))
            else:
                w_opaque, albedo_at = np.take(self.mats.opaque_weight, mat), None
            if self.mats.pick_delta is not None:
                # Cycles weighs a specular layer or metal by its albedo at this view, not averaged
                # over views (behind a sheet of Alpha 0.44 and Specular 0.5 seen straight on, 4.4%
                # of paths had stopped at it where Cycles stops 2.8%: its Normal pass 0.98x)
                if surface is None:
                    surface = self._surface(h, None, D)
                mu = np.abs(np.einsum('ij,ij->j', surface[2], D))
                w_opaque = np.maximum(w_opaque + view_table(self.mats.pick_delta, mat, mu), 0.0)
            total = t_mean + w_opaque * opacity
            p = np.where(total > 0, t_mean / np.where(total > 0, total, 1.0), 0.0).astype(F32)
            p[spent] = 0.0                      # stops, at its opaque part's weight
            u = self.rng.uniform2(keys, DIM_TRANSPARENT + (k << 11) + j)[0]
            go = u < p
            gone = np.flatnonzero(go)
            if len(gone) < len(go):
                stop = np.flatnonzero(~go)
                if path.nee is None:
                    path.nee = np.ones(len(hits), F32)
                p_stop, r_stop = p[stop], rows[stop]
                path.nee[r_stop] = 1.0 - p_stop
                thr[:, r_stop] *= opacity[stop] / (1.0 - p_stop)
            if not len(gone):
                return
            # the passing rays' columns, and the surface each leaves: its light sample's point
            # and its next segment's origin
            rows, prim, h, glass, mat = rows[gone], prim[gone], h[gone], glass[gone], mat[gone]
            tau, opacity, p = tau[:, gone], opacity[gone], p[gone]
            D, keys, tmax, tb = compact(gone, D, keys, tmax, tb)
            P, ng, ns, P_off = self._surface(h, None, D) if surface is None else (x[:, gone] for x in surface)
            if self.lights and k <= self.max_bounces:
                # (none past Total Max Bounces: Cycles keeps no opaque closure there)
                lit = opacity if not unlit.any() else np.where(unlit[gone], F32(0.0), opacity)
                # As Cycles, the surface's light is sampled at every hit, passed or not, at the
                # opaque part's weight: here for the paths that pass; those that stop sample it
                # at their vertex with 1 - p of the 1 / (1 - p) their bounce carries. (Sampled
                # only where the path stopped, a window of 80% Transparent and 20% Diffuse had
                # 5-8x Cycles' noise.)
                self._light_passed(k, j, path, sinks, rows, prim, u_hit[gone], v_hit[gone], lit, P, ng, ns, P_off,
                                   keys, tb, None if albedo_at is None else albedo_at[:, gone])
            if (camera and self._glass_film) or self._transmit_split:
                self._glass_or_clear(camera, path, rows, mat, tau, opacity, p,
                                     self.rng.uniform2(keys, DIM_GLASS + (k << 11) + j)[0])
            else:
                thr[:, rows] *= tau / p
            path.tb[rows[~glass]] += 1
            path.gb[rows[glass]] += 1
            path.xb[rows[glass]] += 1
            # on from just behind the surface (P stepped off it away from the ray's side)
            t0 = h['t']
            sub = self._intersect_past(kind, path.transmit, rows, np.ascontiguousarray(P + P - P_off), D,
                                       (tmax - t0).astype(F32), prim,
                                       None if camera else self._deeper_rows(k, np.take(path.xb, rows)))
            sub['t'] += t0                      # distances from the path vertex, for lamps and MIS
            # the segment's paths: only the columns _gather_segment reads
            pid, O, thr_seg, pdf, prim_seg, N, refracted, transmit, dark_pdf, xb_seg = compact(
                rows, path.pid, path.O, thr, path.pdf, path.prim, path.N, path.refracted, path.transmit,
                path.dark_pdf, path.xb)
            seg = Paths(pid, None, O, D, tmax, thr_seg, pdf, prim_seg, N=N, refracted=refracted, transmit=transmit,
                        dark_pdf=dark_pdf, xb=xb_seg)
            self._gather_segment(seg, sub, t0, sinks, k)
            hits[rows] = sub
            h = sub
            if camera:
                kept = self._transparent_roulette(k, j, path, hits, sub, rows, sinks)
                if kept is not None:
                    rows, h = rows[kept], h[kept]
                    D, keys, tmax = compact(kept, D, keys, tmax)
            j += 1

    def _transparent_roulette(self, k, j, path, hits, sub, rows, sinks):
        """Cycles' Russian roulette at the surfaces camera paths rows now hit (sub, their hits;
        hits: all paths') after their j-th transparent pass (integrator_intersect_terminate):
        where the path has passed more than min_transparent_bounces + 1 transparent surfaces, it
        goes on with probability min(sqrt(max |throughput|), 1), its throughput divided by it,
        or ends there unshaded: that surface and those behind write no passes (Normal, UV, AOVs,
        sample 0's Depth: unweighted, so fewer samples write them, as in Cycles; Combined, alpha
        and the weighted passes stay unbiased). Ended paths are marked in path.dead; returns the
        positions in rows of those left (None: all of them).
        Emissive surfaces are rouletted too: Cycles shades them to add their emission at the
        throughput before the division, then ends the path before its data passes
        (shade_surface); here that emission is counted now (_emission_at_roulette).
        So are the opaque holdout surfaces without emission that _vertex holds out: Cycles ends
        the path there unshaded, so it writes no holdout, and a path that goes on writes it at
        the throughput before the division, its last use (integrate_surface_holdout): the
        transparency behind them is q of the true one, as Cycles' (alpha 0.78 where 0.64 is the
        unrouletted one behind a Transparent sphere of 0.6). The other holdout surfaces are
        not rouletted (Cycles writes an emissive one's holdout before it ends the path)."""
        prim = sub['prim']
        sel = np.flatnonzero((np.take(path.tb, rows) > self._roulette_after) & (prim >= 0))
        held = None
        if self._any_holdout and len(sel):
            held, keep = self._held_at_roulette(path, rows[sel], prim[sel])
            sel, held = sel[keep], held[keep]
        if not len(sel):
            return None
        r = rows[sel]
        q = np.minimum(np.sqrt(np.abs(path.thr[:, r]).max(axis=0)), 1.0).astype(F32)
        u = self.rng.uniform2(np.take(path.keys, r, axis=1), DIM_ROULETTE + (k << 11) + j)[0]
        live = u < q
        if self._any_emissive:
            self._emission_at_roulette(k, path, hits, r, prim[sel], sinks)
        div = live if held is None else live & ~held
        path.thr[:, r[div]] /= q[div]
        if live.all():
            return None
        if path.dead is None:
            path.dead = np.zeros(len(path.pid), bool)
        path.dead[r[~live]] = True
        self._ended['roulette'] += int((~live).sum())
        out = np.ones(len(rows), bool)
        out[sel[~live]] = False
        return np.flatnonzero(out)

    def _held_at_roulette(self, path, rows, prim):
        """At the hits prim of camera paths rows on the transparent roulette: (held, keep), bool
        per hit: held, the opaque holdout surfaces without emission that _vertex will hold out
        (not after glass nor past Transparent Max Bounces); keep, the hits rouletted (these and
        those not on holdout surfaces)."""
        ho = (np.take(self.tri.visibility, prim) & HOLDOUT) != 0
        held = ho & ~np.take(self._tri_transparent, prim) & ~np.take(self.mats.emissive, np.take(self.tri.material, prim))
        held &= np.take(path.tb, rows) < self._transparent_stop
        if path.transmit is not None:
            held &= ~np.take(path.transmit, rows)
        return held, ~ho | held

    def _emission_at_roulette(self, k, path, hits, rows, prim, sinks):
        """The emission of the emissive surfaces (prim) that camera paths rows meet at the
        transparent roulette, at the throughput before it (Cycles adds it in shade_surface
        before ending or dividing: ended paths keep it), as the emission of a transparent surface
        (x its opacity, _emission_before_pick) or of an opaque one (_vertex); those paths are
        marked in path.emitted so that neither counts it again."""
        e = np.flatnonzero(np.take(self.mats.emissive, np.take(self.tri.material, prim)))
        if not len(e):
            return
        rows, prim = rows[e], prim[e]
        opacity = np.ones(len(rows), F32)
        t = np.flatnonzero(np.take(self._tri_transparent, prim))
        if len(t):
            h = hits[rows[t]]
            D = np.take(path.D, rows[t], axis=1)
            opacity[t] = self._transparency(prim[t], np.ascontiguousarray(h['u']), np.ascontiguousarray(h['v']),
                                            None if not self._sided else self._back(prim[t], -D, -D))[1]
        self._emission_before_pick(True, k, path, hits, rows, prim, opacity, sinks)
        if path.emitted is None:
            path.emitted = np.zeros(len(path.pid), bool)
        path.emitted[rows] = True

    def _glass_roulette(self, k, path, hit, u):
        """Cycles' Russian roulette at vertex k (< ROULETTE_FROM) of the paths hit that passed
        glass: Cycles counts each glass pass as a bounce, so a path that has passed
        ROULETTE_FROM - k panes already survives there only with probability
        min(sqrt(max |throughput|), 1), its throughput divided by it (u: the vertex's roulette
        uniforms). Unbiased either way, but the clamps see the divided throughputs: a floor seen
        through a pane was 1% bright with Clamp Indirect 10. path.thr changes in place; returns
        hit without the paths ended."""
        sel = np.flatnonzero(hit & (k + path.xb >= ROULETTE_FROM))
        if not len(sel):
            return hit
        q = np.minimum(np.sqrt(np.abs(path.thr[:, sel]).max(axis=0)), 1.0).astype(F32)
        live = np.take(u, sel) < q
        path.thr[:, sel[live]] /= q[live]
        self._ended['roulette'] += int((~live).sum())
        hit = hit.copy()
        hit[sel[~live]] = False
        return hit

    def _glass_part(self, mat, tau, opacity):
        """(3, k) the glass part of transparency tau at hits on materials mat of opacity (k,)."""
        return np.minimum(np.take(self.mats.refraction, mat, axis=1)
                          + np.take(self.mats.opaque_refraction, mat, axis=1) * opacity, tau)

    def _glass_or_clear(self, camera, path, rows, mat, tau, opacity, p, u):
        """Paths rows passing surfaces of materials mat with transparency tau (3, k): each passes
        as glass (its refraction part, with probability mean(glass) / mean(tau)) or as clear
        transparency (the rest), weighted by the part over its probability (and p, the pass's).
        Those that pass glass go on as transmission rays (path.transmit) and, camera paths under
        a transparent film (_glass_film), are refracted from then on (path.refracted)."""
        glass = self._glass_part(mat, tau, opacity)
        q = np.where(tau.mean(axis=0) > 0, glass.mean(axis=0) / np.maximum(tau.mean(axis=0), 1e-30), 0.0)
        go = u < q
        part = np.where(go, glass / np.where(go, q, 1.0), (tau - glass) / np.where(go, 1.0, 1.0 - q))
        path.thr[:, rows] *= (part / p).astype(F32)
        if path.transmit is None:
            path.transmit = np.zeros(len(path.pid), bool)
        path.transmit[rows[go]] = True
        if camera and self._glass_film:
            if path.refracted is None:
                path.refracted = np.zeros(len(path.pid), bool)
            path.refracted[rows[go & np.take(self._film_refracts, mat)]] = True

    def _intersect_past(self, kind, transmit, rows, O, D, tfar, skip, deep=None):
        """Closest hits of rays (O, D, tfar; skip: the triangle each leaves) that paths rows trace
        on past a transparent surface: as `kind`, or as transmission rays where transmit[rows]
        (they passed glass), which see triangles by their Transmission visibility; bounce rays
        where deep (Integrator._deeper_rows) in the deeper builds' scene."""
        tx = None if transmit is None or 'transmission' not in self._scenes else np.take(transmit, rows)
        if deep is not None:
            tx = np.zeros(len(rows), bool) if tx is None else tx
            hits = np.empty(len(rows), dacrt.HIT_DTYPE)
            for sel, k in ((np.flatnonzero(~tx & ~deep), kind), (np.flatnonzero(~tx & deep), 'bounce_deep'),
                           (np.flatnonzero(tx), 'transmission')):
                if len(sel):
                    hits[sel] = self._intersect(k, np.ascontiguousarray(O[:, sel]), np.ascontiguousarray(D[:, sel]),
                                                np.ascontiguousarray(tfar[sel]), np.take(skip, sel))
            return hits
        if tx is None or not tx.any():
            return self._intersect(kind, O, D, tfar, skip)
        if tx.all():
            return self._intersect('transmission', O, D, tfar, skip)
        hits = np.empty(len(rows), dacrt.HIT_DTYPE)
        for sel, k in ((np.flatnonzero(~tx), kind), (np.flatnonzero(tx), 'transmission')):
            hits[sel] = self._intersect(k, np.ascontiguousarray(O[:, sel]), np.ascontiguousarray(D[:, sel]),
                                        np.ascontiguousarray(tfar[sel]), np.take(skip, sel))
        return hits

    def _light_passed(self, k, j, path, sinks, rows, prim, u, v, opacity, P, ng, ns, P_off, keys, tb, albedo=None):
        """Light sampling at the semi-transparent surfaces (layer j) that paths rows pass (their
        hits prim, u, v, the surface's opacity, points and normals (3, k), keys and transparent
        passes so far tb): the path's throughput so far x the opaque part's weight (opacity x
        albedo), as vertex k's sampling is (the same sinks and light choice), with random
        dimensions of their own. albedo (3, k) or None: the albedo at the hits, with its maps,
        where the pick computed it."""
        if albedo is not None:
            thr = albedo * opacity * np.take(path.thr, rows, axis=1)
        else:
            thr = np.take(self._tri_albedo, prim, axis=1) * opacity * np.take(path.thr, rows, axis=1)
            if self._albedo_varies:
                self._albedo_maps(prim, u, v, thr, self._back(prim, ng, -np.take(path.D, rows, axis=1)))
        side = self._back(prim, ng, -np.take(path.D, rows, axis=1)) if self._sided and self._bumped else None
        ns, bump = self._bent_normals(prim, u, v, ns, ng, side)
        u_pick = None
        if self.lights.num_entries > 1:
            u_pick = self.rng.uniform_pick(keys, DIM_PASSED + (k << 11) + 2 * j)[0]
        pid = np.take(path.pid, rows)
        xb = None if path.xb is None else np.take(path.xb, rows)
        self._next_event(k, np.ascontiguousarray(P), np.ascontiguousarray(P_off), prim, np.ascontiguousarray(ng),
                         np.ascontiguousarray(ns), np.ascontiguousarray(thr, F32), pid, keys,
                         u_pick, sinks.sampled(k), tb, u, v, sinks.groups, bump,
                         dims=DIM_PASSED + (k << 11) + 2 * j + 1,
                         rough=self._rough_rows(prim, u, v, ng, ns, np.take(path.D, rows, axis=1))
                         if self.mats.any_rough else None, xb=xb)
        if self._any_translucent:             # a translucent surface's transmission, from the far side
            mat = np.take(self.tri.material, prim)
            sel = np.flatnonzero(np.take(self.mats.translucent, mat))
            if len(sel):
                T = np.take(self.mats.translucency, np.take(mat, sel), axis=1)
                thr_far = T * np.take(opacity, sel) * np.take(path.thr, np.take(rows, sel), axis=1)
                incoming = -np.take(path.D, rows, axis=1)
                if self.mats.translucency_textures:
                    self._translucency_maps(sel, prim, u, v, thr_far, ng, incoming)
                # (its normal raised as at a vertex: integrator._vertex's ns_far)
                ns_far = valid_reflection_normal(np.take(ng, sel, axis=1), np.take(incoming, sel, axis=1),
                                                 np.take(ns, sel, axis=1),
                                                 np.take(self.mats.bump_correction, np.take(mat, sel)))
                self._next_event_far(k, sel, thr_far, P, ng, ns, P_off, prim, pid, keys,
                                     u_pick, sinks, tb, u, v, DIM_LOBE + (1 << 20) + (k << 11) + j, ns_far,
                                     bump=bump, xb=xb)

    def _emission_before_pick(self, camera, k, path, hits, rows, prim, opacity, sinks):
        """The emission of the transparent surfaces the rays `rows` of path meet now (hits
        [rows], prim), at the throughput they arrive with times the opacity there, as Cycles
        counts a surface's emission before it picks a closure: whether the ray then passes or
        stops does not change it, so the pick can weigh the scattering closures alone (_vertex
        leaves these surfaces' emission out where paths stopped). Holdout surfaces seen by
        camera rays are left to _vertex, which holds them out."""
        mask = np.zeros(len(hits), bool)
        mask[rows] = True
        if camera and self._any_holdout:
            mask[rows] = (np.take(self.tri.visibility, prim) & HOLDOUT) == 0
        if path.emitted is not None:            # (counted at the roulette)
            mask &= ~path.emitted
        saved = path.thr
        if (opacity != 1.0).any():
            path.thr = saved.copy()
            path.thr[:, rows] *= opacity
        try:
            self._gather_emission(camera, mask, hits, path, sinks.found(k), k, sinks.groups)
        finally:
            path.thr = saved

    def _gather_segment(self, seg, sub, t0, sinks, k):
        """Lamps beyond distance t0 along a segment past a transparent surface, and the world
        where it misses: lamp_gather counts lamps from the path vertex (so MIS sees the true
        distance) up to the new hit; the same lamps up to t0, already gathered, are taken off."""
        hit = sub['prim'] >= 0
        self._gather_lamps(seg, hit, sub, sinks, k)
        # (lamps at infinity count only where a ray missed: nothing to take off for them)
        camera = k == 0
        lamps = self._bsdf_lamps if not camera else self._camera_emitters if sinks.split else self._camera_lamps
        outs = [(lamps, sinks.found(k))]
        outs += self._group_lamps(camera, sinks)
        # (taken off in the clamp classes they were just gathered in)
        for lamps, out in outs:
            if not len(lamps):
                continue
            for thr_c, clamp in self._found_classes(k, seg, -seg.thr):
                for lamps_l, thr in self._linked(lamps, seg, thr_c, camera):
                    for lamps_p, pdf in self._mis_pdfs(lamps_l, seg, k, camera):
                        dacrt.lamps.lamp_gather(self._lamp_records, lamps_p, seg.O, seg.D, t0.astype(F32),
                                                np.zeros(len(t0), bool), seg.pid, out, thr=thr,
                                                pdf_bsdf=pdf, clamp=clamp, **self._lamp_mis(camera, seg))
        if camera and seg.refracted is not None:
            self._world_through_glass(seg, sub, ~hit & seg.refracted, sinks)

    def _world_through_glass(self, seg, sub, where, sinks):
        """The world camera rays see through glass under a transparent film (_glass_film), where
        `where` (bool per ray of seg) they missed after passing it: into Combined (and the world's
        light group) as through an opaque film; the Environment pass has it already."""
        if not where.any():
            return
        outs = [sinks.L]
        if sinks.groups and self._world_group >= 0:
            outs.append(sinks.groups[self._world_group])
        for out in outs:
            for thr, clamp in self._found_classes(0, seg):     # (past two panes: indirect)
                if self._glass_env is not None:
                    self._glass_env.native.gather(0.0, seg.D, where, thr, None, seg.pid, out, clamp)
                if len(self._glass_world_lamps):
                    dacrt.lamps.lamp_gather(self._lamp_records, self._glass_world_lamps, seg.O, seg.D, sub['t'],
                                            where, seg.pid, out, thr=thr, pdf_bsdf=None, clamp=clamp)

    def _shadow_through(self, rays, skip, send, occluded, value, tb=None, kind='through'):
        """Shadow rays not stopped by opaque triangles pass the transparent ones (the 'through'
        scene), their light multiplied by each surface's transparency, as Cycles' transparent
        shadows; more surfaces than the path has left of max_transparent (tb: surfaces its
        vertex's path passed, per light sample) block them."""
        # the records as the occlusion query left them (reordered, ids kept; the tfar of rays
        # that reach their light untouched), renumbered for the rays still open
        ids = rays['id']
        keep = ~np.take(occluded, ids)
        r = rays[keep]
        if not len(r):
            return
        cols = np.take(send, ids[keep])              # the light samples they carry
        prim = None if skip is None else np.take(skip, ids[keep])
        r['id'] = np.arange(len(r), dtype=np.uint32)
        tfar = r['tfar'].copy()
        hits = self._intersect(kind, None, None, None, prim, rays=r)
        at = np.flatnonzero(hits['prim'] >= 0)
        if not len(at):
            return
        # from here on only the rays that met a transparent triangle (by id; the tracer
        # reordered r): their directions, remaining lengths, light samples and attenuation
        pos = np.empty(len(r), np.int64)
        pos[r['id']] = np.arange(len(r))
        D = np.ascontiguousarray(r['dir'][pos[at]].T)
        tfar, cols = np.take(tfar, at), np.take(cols, at)
        left = np.full(len(at), self.max_transparent, np.int64) if tb is None else \
            self.max_transparent - np.take(tb, cols).astype(np.int64)
        hits = hits[at]
        atten = np.ones((3, len(at)), F32)
        rows = np.arange(len(at))
        at = rows
        for j in range(self.max_transparent + 1):
            if j:
                hits = self._intersect(kind, None, D, None, prim, rays=r)
                at = np.flatnonzero(hits['prim'] >= 0)
                if not len(at):
                    break
            rows_at = rows[at]
            tau = self._transparency(hits['prim'][at], hits['u'][at], hits['v'][at],
                                     None if not self._sided else
                                     self._back(hits['prim'][at], -np.take(D, at, axis=1),
                                                -np.take(D, at, axis=1)))[0]
            tau[:, np.take(left, rows_at) <= j] = 0.0      # over the path's limit: blocked
            atten[:, rows_at] *= tau
            go = at[tau.max(axis=0) > 0]        # fully opaque there: nothing left to trace
            if not len(go):
                break
            P, _, _, P_off = self._surface(hits, go, D)
            D = np.ascontiguousarray(np.take(D, go, axis=1))
            tfar = np.maximum(np.take(tfar, go) - np.take(hits['t'], go), 0.0).astype(F32)
            prim = np.take(hits['prim'], go)
            rows = rows[go]
            r = self._ray_array(np.ascontiguousarray(P + P - P_off), D, tfar)
        value[:, cols] *= atten


# scenedata.Geometry's per-triangle arrays (aovs, a dict of them, apart)
TRIANGLE_FIELDS = ('triangles', 'material', 'normals', 'uvs', 'visibility', 'object_index', 'instance',
                    'terminator', 'has_uv', 'tangents', 'colors', 'coords', 'unbumped', 'one_sided')


def line_crossings(vertices, tris, limit=4_000_000):
    """The most of these triangles (k, 3) one straight line can cross (not lying in them): 1
    when they are flat (all their vertices within float rounding of each one's plane), 2 when
    each has every vertex on one side of its plane (they lie on their convex hull's boundary,
    which a line crosses twice at most), else their count; the test only up to `limit` vertex x
    triangle pairs."""
    k = len(tris)
    if k <= 1:
        return k
    used = np.unique(tris)
    if k * len(used) > limit:
        return k
    V = vertices[used].astype(np.float64)
    a, b, c = (vertices[tris[:, i]].astype(np.float64) for i in range(3))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1)
    ok = length > 0
    if not ok.any():
        return k
    n, a = n[ok] / length[ok, None], a[ok]
    d = V @ n.T - np.einsum('ij,ij->i', a, n)[None, :]      # (vertices, triangles)
    tol = 1e-5 * max(float(np.abs(V).max()), float(np.ptp(V, axis=0).max()), 1e-30)
    if (np.abs(d) <= tol).all():
        return 1
    if ((d <= tol).all(axis=0) | (d >= -tol).all(axis=0)).all():
        return min(2, k)
    return k


def seen_through(alpha, path, rows):
    """Camera paths `rows` that end transparent (at transparent film's background or a
    holdout) after passing transparent surfaces: alpha 1 - what passed, as Cycles adds the
    throughput reaching them to the transparency."""
    alpha[np.take(path.pid, rows)] = 1.0 - np.take(path.thr, rows, axis=1).mean(axis=0)
