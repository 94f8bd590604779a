"""Emission found by camera and BSDF rays, part of the Integrator (a mixin of it): emissive
triangles hit, lamps met before the surface (lamps are not geometry), the world where rays
miss, each MIS-weighted against light sampling for BSDF rays, clamped as Cycles' Light Paths >
Clamping, split by light linking and light groups, and what the last bounce's rays may still
collect."""
from __future__ import annotations

import itertools

import numpy as np

import dacrt

from .lights.linking import reached
from .pathstate import clamp_classes

F32 = np.float32


class EmitterHits:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    def _gather_emission(self, camera, hit, hits, path, L, k, groups=(), shadow_set=0):
        """Emission of the triangles hit by rays `hit` (two-sided) arriving at vertex k,
        MIS-weighted for BSDF rays (one native pass); each contribution clamped as Cycles'
        sample clamp (_found_classes); with light groups, each group's triangles again into its
        own array. shadow_set: with shadow linking, the set of blockers whose emitters are
        gathered (0: those of none; the others by _gather_shadow_linked's retraced rays). hit
        None: every ray that met a triangle, read from the records (_bare_vertex: no light
        linking, light groups or image emission there)."""
        if self._link is not None and not camera and path.prim is not None:
            # light linking: emitters do not light the objects their set leaves out
            prim = np.maximum(hits['prim'], 0)
            hit = hit & reached(self._receivers(path.prim), np.take(self._tri_set, prim))
        if self._shadow_link is not None and not camera:
            # shadow-linked emitters: gathered by rays retraced against their set's blockers
            # (_gather_shadow_linked), or lit by their light samples alone where Cycles leaves
            # them to BSDF rays (forced: _build_lights)
            prim = np.maximum(hits['prim'], 0)
            hit = hit & (np.take(self._tri_shadow_set, prim) == shadow_set)
            if shadow_set:
                hit &= np.take(self._tri_sampled & ~self._tri_forced, prim)
        outs = [(hit, L)]
        if groups:
            grp = np.take(self._tri_group, np.maximum(hits['prim'], 0))
            outs += [(hit & (grp == g), G) for g, G in enumerate(groups)]
        thr = path.thr
        if self._tri_emit_tex is not None:
            # image emission: its radiance at each hit scales the ray's throughput, against 1 in
            # the table gathered from
            prim = np.maximum(hits['prim'], 0)
            at = np.flatnonzero(hit & np.take(self._tri_emit_tex, prim))
            if len(at):
                thr = np.ones((3, len(hit)), F32) if thr is None else thr.copy()
                thr[:, at] *= self._emission_at(prim[at], hits['u'][at], hits['v'][at],
                                                None if not self._sided else
                                                self._back(prim[at], -np.take(path.D, at, axis=1),
                                                           -np.take(path.D, at, axis=1), hits['t'][at]))
        for mask, out in outs:
            for thr_c, clamp in self._found_classes(k, path, thr):
                dacrt.shading.gather_emission(hits, mask, self._emission_table(), self._tri_emissive,
                                              None if camera else self.lights.tri_prob, self._area32, self.tri.geo,
                                              path.O, path.D, thr_c, path.pdf, path.pid, out, clamp=clamp,
                                              **({} if camera or self._tri_key is None
                                                 else dict(tree=self.lights.tree, tri_key=self._tri_key, N=path.N,
                                                           receivers=self._linked_receivers(path))))

    def _found_classes(self, k, path, thr=None):
        """[(throughput, clamp)]: the rays of path arriving at vertex k, of throughput thr
        (default path.thr; None: 1), by the clamp of the light they find. Cycles' bounce count
        there counts glass passes (path.xb) too, so a ray past glass may find indirect light
        before vertex 2 (a lamp seen by the BSDF rays of a floor behind a pane was 3.2x Cycles
        at Clamp Direct 0 / Indirect 1). Mixed rays are gathered twice, each time with the
        other class's throughput 0."""
        thr = path.thr if thr is None else thr
        classes = clamp_classes(k - 1, path.xb, self._clamps)   # bounce k - 1: the vertex it left
        if len(classes) == 1:
            return [(thr, classes[0][1])]
        one = np.ones((3, len(path.xb)), F32) if thr is None else thr
        return [(np.where(m, one, F32(0)), c) for m, c in classes]

    def _group_lamps(self, camera, sinks, combined=None):
        """[(lamp records, light group's array)]: per light group, the records of its lamps
        among those Combined gathers from camera or BSDF rays (or among `combined`), and the
        world behind transparent film (none: left out)."""
        if combined is None:
            combined = self._bsdf_lamps if not camera else self._camera_grouped
        if not sinks.groups or not len(combined):
            return []
        mine = ((combined[self._record_group[combined] == g], G) for g, G in enumerate(sinks.groups))
        return [(lamps, G) for lamps, G in mine if len(lamps)]

    def _gather_lamps(self, path, hit, hits, sinks, k):
        """Lamps the rays meet (lamps are not geometry): finite ones before the surface hit,
        the sun and the world where the ray misses everything; MIS-weighted for BSDF rays.
        One native pass over the rays for all lamps (dacrt.lamps.lamp_gather); with light
        passes, camera rays' emitters and world go to their two passes; with light groups,
        each group's lamps (and the world) again into its own array. hit None: no flags
        (Integrator._flags_unread): the gathers read which rays missed from the hit records."""
        camera, classes = k == 0, self._found_classes(k, path)
        L, L_env = sinks.found(k), sinks.world(k)
        bounce = not camera and self._bounce_worlds is not None
        if bounce:
            self._gather_bounce_world(path, ~hit, sinks, k)
        if not camera:
            env, groups = None if bounce else self.lights.environment, ((self._bsdf_lamps, L),)
        elif sinks.split:
            env = self._camera_env_pass if self._env_requested else self._camera_env
            groups = ((self._camera_emitters, L), (self._camera_world, L_env))
        else:
            env, groups = self._camera_env, ((self._camera_lamps, L),)
        # what goes to the light groups: Combined's, and, with the Environment pass, the world
        # behind transparent film too (Cycles writes it to the world's group then, though
        # Combined leaves it out)
        combined_env = ((None if bounce else self.lights.environment) if not camera else
                        self._camera_env_pass if self._env_requested else self._camera_env)
        envs = [(env, L_env)] if env is not None else []
        if sinks.groups and combined_env is not None and self._world_group >= 0:
            envs.append((combined_env, sinks.groups[self._world_group]))
        groups = [(lamps, out) for lamps, out in groups if len(lamps)] + self._group_lamps(camera, sinks)
        miss = hits if hit is None else ~hit         # (the records: prim < 0, read in place)
        # camera rays past glass see the map by the world's Transmission visibility (_env_apart)
        past = path.transmit if camera and self._env_apart and path.transmit is not None else None
        for (e, out), (thr, clamp) in itertools.product(envs, classes):
            e.native.gather(0.0 if camera else self.lights.env_prob, path.D, miss if past is None else miss & ~past,
                            thr, None if camera else path.pdf, path.pid, out, clamp)
        if past is not None and self._transmit_env is not None and past.any():
            outs = [L_env] + ([sinks.groups[self._world_group]] if sinks.groups and self._world_group >= 0 else [])
            for out, (thr, clamp) in itertools.product(outs, classes):
                self._transmit_env.native.gather(0.0, path.D, miss & past, thr, None, path.pid, out, clamp)
        if not groups:
            return
        # a lamp counts in front of the surface hit, or of the ray's end where it missed (the
        # tracer leaves a miss at t = inf: only camera rays end sooner, at the clip end; hit
        # None: the camera rays see lamps at infinity alone, which read no t_surf)
        t_surf = np.where(hit, hits['t'], path.tmax) if camera and hit is not None else hits['t']
        for (lamps, out), (thr_c, clamp) in itertools.product(groups, classes):
            for lamps, thr in self._linked(lamps, path, thr_c, camera):
                for lamps, pdf in self._mis_pdfs(lamps, path, k, camera):
                    dacrt.lamps.lamp_gather(self._lamp_records, lamps, path.O, path.D, t_surf,
                                            miss, path.pid, out, thr=thr, pdf_bsdf=pdf,
                                            clamp=clamp, **self._lamp_mis(camera, path))

    def _gather_bounce_world(self, path, miss, sinks, k):
        """The world diffuse bounce rays that missed see where a Light Path mix gives them their
        own (_bounce_worlds), into Combined (or its pass) and the world's light group. As in
        Cycles, where the world is one light whose samples (and importance map) read every ray
        type 0 (light_sample_shader_eval: PATH_RAY_EMISSION alone), these rays' world carries
        the MIS weight of the lighting world's map: light samples hold the rest of that world."""
        if not self._bounce_worlds or not miss.any():
            return
        thr = np.ones((3, len(miss)), F32) if path.thr is None else path.thr
        env0, prob = self.lights.environment, self.lights.env_prob
        if env0 is not None and prob > 0:
            # the power heuristic of these BSDF rays against sampling the lighting world's map
            at = np.flatnonzero(miss)
            _, pdf = env0.native.eval(np.ascontiguousarray(np.take(path.D, at, axis=1)))
            x = (prob * np.asarray(pdf, np.float64) / np.take(path.pdf, at)) ** 2
            thr = thr.copy()
            thr[:, at] *= (1.0 / (1.0 + x)).astype(F32)
        outs = [sinks.world(k)]
        if sinks.groups and self._world_group >= 0:
            outs.append(sinks.groups[self._world_group])
        for world, out, (thr_c, clamp) in itertools.product(self._bounce_worlds, outs,
                                                            self._found_classes(k, path, thr)):
            world.native.gather(0.0, path.D, miss, thr_c, None, path.pid, out, clamp)

    def _mis_pdfs(self, lamps, path, k, camera):
        """(lamp records, MIS pdf of the BSDF rays) pairs to gather segment k with: path.pdf,
        but path.dark_pdf for the lamps past their Max Bounces at the vertex the rays leave
        (k - 1). There light sampling is dark and the rays' MIS share is all their light, so
        their pdf must be Cycles': where the vertex stopped at a semi-transparent surface, the
        opaque part's pdf x its selection probability 1 - p (Cycles' pdf over every closure,
        the transparent one too). (With the full pdf a lamp at Max Bounces 0 over a veil of 0.5
        Transparent and 0.5 Diffuse was 1.18-1.32x Cycles; where light sampling is live the
        two pdfs give the same image, its MIS weight pairs with the full one.)"""
        if camera:
            return [(lamps, None)]
        if path.dark_pdf is None:
            return [(lamps, path.pdf)]
        nl = len(self._max_bounces)
        past = np.zeros(len(lamps), bool)
        sampled = lamps < nl
        past[sampled] = self._max_bounces[lamps[sampled]] < k - 1
        if not past.any():
            return [(lamps, path.pdf)]
        return [(recs, pdf) for recs, pdf in ((lamps[~past], path.pdf), (lamps[past], path.dark_pdf)) if len(recs)]

    def _gather_shadow_linked(self, path, sinks, k):
        """Shadow-linked lamps BSDF rays of segment k meet, as Cycles finds them (its dedicated
        light search along the ray ends at the first opaque object in no blocker collection,
        and the dedicated shadow ray is stopped by the lamp's blockers): the rays retraced
        against those objects per set ('shadow<set>u', transparent ones let through), the lamps
        they reach gathered with their MIS weight (past a lamp's Max Bounces, where light
        sampling skips it, with the pdf that holds all their light: _mis_pdfs). Light-sampled
        linked emissive triangles likewise, per set, against its blockers, the unlisted opaque
        objects and the set's emitters ('shadow<set>e'), MIS-weighted by _gather_emission."""
        for s in self._linked_tri_sets:
            kind = f'shadow{int(s)}e'
            if kind in self._scenes:
                hits = self._intersect(kind, path.O, path.D, path.tmax, path.prim)
                self._gather_emission(False, hits['prim'] >= 0, hits, path, sinks.found(k), k, sinks.groups,
                                      shadow_set=int(s))
        lamps = self._bsdf_linked
        if not len(lamps):
            return
        sets = self._record_shadow_set[lamps]
        classes, L = self._found_classes(k, path), sinks.found(k)
        for s in np.unique(sets):
            kind = f'shadow{s}u'
            if kind in self._scenes:
                hits = self._intersect(kind, path.O, path.D, path.tmax, path.prim)
                t, miss = hits['t'], hits['prim'] < 0
            else:                           # nothing opaque blocks them: nothing stops the rays
                t, miss = np.full(len(path.pid), np.inf, F32), np.ones(len(path.pid), bool)
            mine = lamps[sets == s]
            for (recs, out), (thr_c, clamp) in itertools.product([(mine, L)] + self._group_lamps(False, sinks, mine),
                                                                 classes):
                for recs, thr in self._linked(recs, path, thr_c, False):
                    for recs, pdf in self._mis_pdfs(recs, path, k, False):
                        dacrt.lamps.lamp_gather(self._lamp_records, recs, path.O, path.D, t, miss, path.pid, out,
                                                thr=thr, pdf_bsdf=pdf, clamp=clamp, **self._lamp_mis(False, path))

    def _lamp_mis(self, camera, path):
        """lamp_gather's MIS arguments: none for camera rays; for BSDF rays each lamp record's
        selection probability and, with a light tree, the records' keys in it and the normals
        the paths' vertices sampled lights with."""
        if camera:
            return {}
        if self._record_key is None:
            return dict(lamp_prob=self._record_prob)
        return dict(lamp_prob=self._record_prob, tree=self.lights.tree, lamp_key=self._record_key, N=path.N,
                    receivers=self._linked_receivers(path))

    def _linked_receivers(self, path):
        """With light linking, the receiver masks of the objects BSDF rays leave: the light tree
        picked their vertex's light among the sets it lights, and their MIS pdf must too."""
        return None if self._link is None else self._receivers(path.prim)

    def _linked(self, lamps, path, thr, camera):
        """(lamp records, throughput) pairs to gather with: per light set of the lamps, the
        throughput 0 on BSDF rays leaving objects that set does not light (light linking);
        camera rays see every lamp by their kind's visibility (_seen_apart)."""
        if camera:
            return self._seen_apart(lamps, path, thr)
        if self._link is None or path.prim is None:
            return [(lamps, thr)]
        recv = self._receivers(path.prim)
        sets = self._record_set[lamps]
        return [(lamps[sets == s], thr if s == self._link.everyone else thr * reached(recv, s).astype(F32))
                for s in np.unique(sets)]

    def _seen_apart(self, lamps, path, thr):
        """Camera rays' (lamp records, throughput) pairs: lamps seen by camera and transmission
        rays alike with thr; those only one kind sees with thr 0 on the other's rays (the paths
        that passed glass, path.transmit)."""
        if not self._lamps_transmit_apart:
            return [(lamps, thr)]
        cam, trans = self._record_camera[lamps], self._record_transmit[lamps]
        t = np.zeros(len(path.pid), bool) if path.transmit is None else path.transmit
        base = np.ones((3, len(t)), F32) if thr is None else thr
        out = [(lamps[cam & trans], thr)]
        if (cam & ~trans).any():
            out.append((lamps[cam & ~trans], base * (~t).astype(F32)))
        if (trans & ~cam).any() and t.any():
            out.append((lamps[trans & ~cam], base * t.astype(F32)))
        return [(l, w) for l, w in out if len(l)]
