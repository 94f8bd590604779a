"""The frame's light set and light choice, part of the Integrator (a mixin of it): the lamps,
emissive triangles and world built from SceneData, the light-selection table and its
per-entry columns, light and shadow linking, the light-choice weights (measured by probes for
normal-mapped and translucent receivers) and the emitted power of emitters whose emission
varies per point (procedural and attribute emission), which weighs them in the choice."""
from __future__ import annotations

import numpy as np

import dacrt

from .lights import BackgroundLight, EmissiveTriangles, EnvironmentLight, LightSet, lamp_records, make_lamp
from .lights.base import RECORD_FIELDS
from .lights.coincident import coincident_copies, near_copies
from .lights.overlap import coplanar_overlaps
from .lights.point import SpotLight
from .lights.sphereinside import TriangleReach
from .lights.linking import LightLinking
from .lights.madelamp import taken_lamp
from .procedural import VIEW, ProceduralTexels
from .scenedata import (NO_TRANSMISSION, STAND_IN_ZERO, VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW, Environment,
                        SceneData)
from .translucency import far_side
from .viewside import Facing

F32 = np.float32


def _bounce_worlds(bounce_world, visibility):
    """The maps (lights.EnvironmentLight) diffuse bounce rays that miss see where a world Light
    Path mix gives them a world of their own (scenedata.bounce_world): its image, and its uniform
    colour as a constant map (each gathered by emitterhits._gather_bounce_world); [] where they
    see nothing of it (black, or hidden from diffuse rays); None without such a world."""
    if bounce_world is None:
        return None
    if not visibility & VIS_DIFFUSE:
        return []
    uniform, env = bounce_world
    maps = [EnvironmentLight(env)] if env is not None else []
    if np.asarray(uniform).max() > 0:
        maps.append(EnvironmentLight(Environment(np.ones((1, 2, 3), F32), np.asarray(uniform, F32))))
    return [m for m in maps if not m.dark]


class LightSetup:
    """A mixin of integrator.Integrator (see the module docstring): its methods read and set
    the Integrator's state."""

    _bounce_worlds = None       # (_build_lights: the world diffuse bounces see apart, if any)

    def _build_lights(self, sd: SceneData):
        self._init_linking(sd)
        # (the lamps the export's float32 check made, where the lights still hold their values)
        lamps = [taken_lamp(light, make_lamp) for light in sd.lights]
        world = np.asarray(sd.world, F32)
        wv = int(sd.world_visibility)
        # Light Groups: each triangle's group as an emitter (-1: none) and the world's
        self._groups = tuple(getattr(sd.settings, 'lightgroups', ()))
        group = {name: g for g, name in enumerate(self._groups)}
        ob = np.asarray(sd.geometry.object_index, np.int64)
        names = sd.per_object(sd.object_lightgroups, lambda i: '')
        self._tri_group = np.take(np.array([group.get(n, -1) for n in names] or [-1], np.int64), ob) \
            if self._groups and len(ob) else None
        self._world_group = group.get(getattr(sd, 'world_lightgroup', ''), -1)
        # Cycles' World > Max Bounces: the environment map's light samples light nothing past it
        self._world_max_bounces = int(getattr(sd, 'world_max_bounces', 1024))
        self._group_index = group
        camera_world = getattr(sd, 'camera_world', None)
        # camera rays past glass are transmission rays: they see the world by its Transmission
        # visibility, and the world itself where a Light Path's Is Camera Ray picks another
        world_transmit = not wv & NO_TRANSMISSION
        if world.max() > 0:
            bg = BackgroundLight(world)
            bg.visible_camera, bg.visible_diffuse = bool(wv & VIS_CAMERA), bool(wv & VIS_DIFFUSE)
            bg.visible_transmission = world_transmit
            if camera_world is not None:        # camera rays see camera_world's instead
                bg.visible_camera = False
                # named so where it is skipped: the camera still sees the world's other side
                # (a plain 'World' had read as the whole world unseen)
                bg.name = "World (its non-camera side)"
            lamps.append(bg)
        if camera_world is not None and np.asarray(camera_world[0]).max() > 0 and wv & VIS_CAMERA:
            bgc = BackgroundLight(np.asarray(camera_world[0], F32))
            bgc.visible_camera, bgc.visible_diffuse, bgc.visible_transmission = True, False, False
            lamps.append(bgc)
        vis = self.tri.visibility
        # Only triangles BSDF rays can hit are sampled as lights, so both MIS strategies see the
        # same emitters; of those, the materials' Emission Sampling (None: BSDF rays alone)
        hittable = self._tri_emissive & ((vis & VIS_DIFFUSE) != 0)
        self._tri_alias = None
        if self._any_emissive:
            hittable = self._without_coincident_copies(sd, hittable, vis)
            self._say_near_copies(sd, hittable)
        sampled = hittable & self.mats.light_sampled[self.tri.material]
        if self._shadow_link is not None:
            # shadow-linked emitters are light-sampled whatever their Emission Sampling says: a
            # BSDF ray is stopped by every object, so only a light sample's shadow ray can be
            # traced against the emitter's blockers alone (one left to BSDF rays had kept the
            # shadow of a blocker its collection excludes: floor 0.44x Cycles under the plate;
            # Cycles traces a dedicated shadow ray from the BSDF hit, the same expected image)
            # Those Cycles would not light-sample (None, or Auto on a dim emitter) are found there
            # by BSDF rays, whose dedicated-light search stops at any opaque object in no blocker
            # collection: their light samples' shadow rays meet those too (_build_scenes)
            self._tri_forced = hittable & (self._tri_shadow_set > 0) & ~sampled
            sampled |= hittable & (self._tri_shadow_set > 0)
        self._tri_sampled = sampled
        self._say_shadowless_emitters(sd, sampled, vis)
        table, power = self._emission_table(), self._tri_emission
        if self._any_emissive and self.mats.light_scale is not None:
            # light samples and the choice's power see the emission undimmed by a coat or sheen
            # (Material.light_emission_scale); BSDF and camera hits keep the table's dimmed one
            scale = np.take(self.mats.light_scale, self.tri.material, axis=1)
            table, power = table * scale, power * scale
        tris = EmissiveTriangles(self.tri.geo, self.tri.area, table, sampled,
                                 power_emission=power) if self._any_emissive else None
        env = EnvironmentLight(sd.environment) if sd.environment is not None else None
        camera_env = env
        if camera_world is not None:
            camera_env = EnvironmentLight(camera_world[1]) if camera_world[1] is not None else None
        # a map diffuse rays cannot see lights nothing; camera rays may still see it (not
        # through transparent film)
        # with light linking, the tree picks each point's light among the sets it is lit by
        sets = None if self._link is None else (lambda lamp: _light_set(self._link, lamp), self._tri_set)
        # (what only diffuse bounce rays see of the world: found by them, never light-sampled)
        self._bounce_worlds = _bounce_worlds(getattr(sd, 'bounce_world', None), wv)
        self.lights = LightSet(lamps, tris, len(self.tri), env if wv & VIS_DIFFUSE else None,
                               use_tree=bool(getattr(self.settings, 'use_light_tree', True)), light_sets=sets,
                               tri_object=ob if sd.geometry.instance is None else sd.geometry.instance,
                               unsampled_emitters=bool((hittable & ~sampled).any()) or bool(self._bounce_worlds),
                               glass=self._any_glass)
        self._camera_env = camera_env if (camera_env is not None and wv & VIS_CAMERA and not self.transparent
                                          and not camera_env.dark) else None
        # the map camera rays past glass see: the lighting world by its Transmission visibility,
        # never a camera backdrop (under a transparent film, _world_through_glass had added both
        # and ignored the visibility: (1, 0.91, 0) where Cycles shows the non-camera side (1, 0, 0))
        self._glass_env = env if (env is not None and world_transmit and not env.dark) else None
        self._say_shadowless_lamps()
        self._say_split_occluders(sd)
        self._say_bounce_world_share()
        self._say_surfaces_inside_sphere_spots()
        self._say_lamps_ending_paths()
        # through an opaque film, where it differs from _camera_env (under a transparent one the
        # world behind glass is _world_through_glass's)
        transmit_env = None if self.transparent else self._glass_env
        self._env_apart = self._any_glass and transmit_env is not self._camera_env
        self._transmit_env = transmit_env if self._env_apart else None
        # each light named once (an instanced lamp's 5000 copies had been 5000 names in 34 lines)
        # a lamp whose node tree emits nothing (an output targeted at EEVEE, a muted Emission)
        # is named with that cause: "zero strength" had contradicted its 300 W panel
        why = {l.name: getattr(l, 'no_emission', '') for l in lamps if l.dark}
        zero = [n for n in self.lights.skipped_lamps if not why.get(n)]
        if zero:
            self.messages.append(('INFO', f"skipped {len(zero)} light(s) with zero strength: "
                                          f"{', '.join(dict.fromkeys(zero))}"))
        treeless = {n: why[n] for n in self.lights.skipped_lamps if why.get(n)}
        # a strength 0 only from a stand-in (a Noise into the Strength): not said "as in Cycles"
        stood = {n: w for n, w in treeless.items() if STAND_IN_ZERO in w}
        treeless = {n: w for n, w in treeless.items() if n not in stood}
        if stood:
            self.messages.append(('WARNING', f"skipped {len(stood)} light(s) whose node-tree strength reads 0 "
                                             "here (nodes not evaluated for a light stand at their own values; "
                                             "Cycles evaluates them): " +
                                  ', '.join(f"{n} ({w})" for n, w in stood.items())))
        if treeless:
            self.messages.append(('INFO', f"skipped {len(treeless)} light(s) whose node tree emits nothing, as in "
                                          "Cycles: " + ', '.join(f"{n} ({w})" for n, w in treeless.items())))
        if self.lights.unseen_lamps:
            self.messages.append(('INFO', f"skipped {len(self.lights.unseen_lamps)} light(s) that neither camera "
                                          "nor diffuse rays can see, nor camera rays past glass (the scene has "
                                          "none, or they are hidden from its transmission rays): "
                                          f"{', '.join(dict.fromkeys(self.lights.unseen_lamps))}"))
        if self.lights.choice_only_lamps:
            # (Cycles keeps them in its light choice, where they take samples from the others)
            self.messages.append(('INFO', f"{len(self.lights.choice_only_lamps)} light(s) that neither camera nor "
                                          "diffuse rays can see, nor camera rays past glass (the scene has none, or "
                                          "they are hidden from its transmission rays), light nothing here, but "
                                          "keep their share of the light choice, as in Cycles (it spends light "
                                          "samples on them): "
                                          f"{', '.join(dict.fromkeys(self.lights.choice_only_lamps))}"))
        # Native lamp records (dacrt.lamps): the lamps light sampling may choose (0..nl-1), then
        # those only BSDF and camera rays find (the world), then those only camera rays see.
        # Record index lists per ray kind, for lamp_gather.
        nl = self.lights.num_lamps
        diffuse = self.lights.lamps + self.lights.unsampled_lamps
        every = self._record_lamps = diffuse + self.lights.camera_lamps
        self._lamp_records = lamp_records(every)
        self._nee_records = np.ascontiguousarray(self._lamp_records[:nl])
        # Camera rays past glass are Cycles' transmission rays: they see lamps by their
        # Transmission visibility (a lamp hidden from the camera seen through a pane, one hidden
        # from transmission not). The camera lists hold lamps seen either way; _linked masks
        # each kind out of the other's rays
        self._record_camera = np.array([l.seen_by_camera for l in every], bool)
        self._record_transmit = np.array([l.seen_by_transmission for l in every], bool)
        self._lamps_transmit_apart = self._any_glass and bool((self._record_camera != self._record_transmit).any())
        self._transmit_split = self._transmit_split or self._lamps_transmit_apart or self._env_apart
        # camera rays' lamps: (record index, is the world), in record order
        seen = [(j, isinstance(l, BackgroundLight)) for j, l in enumerate(every)
                if l.seen_by_camera or (self._lamps_transmit_apart and l.seen_by_transmission)]
        pick = lambda keep: np.array([j for j, world in seen if keep(world)], np.int32)
        self._camera_lamps = pick(lambda world: not (world and self.transparent))   # transparent film: no world
        # with light passes, camera rays' lamps go to Emission and their world to Environment,
        # which holds the world seen through transparent film too (as Cycles), though Combined
        # does not
        # Light groups: the world camera rays see behind transparent film too, but only when
        # the Environment pass is asked for: Cycles evaluates the background of a transparent
        # camera ray only for that pass (integrate_background), and its light group then takes
        # it (Cycles 5.0: sky pixels in the world's group 0.5 with the pass, 0.0 without). Not
        # when the film adds Environment itself (for Denoising Albedo): the world is then not
        # evaluated, and the albedo has none of it (Cycles 0 there)
        self._world_lamps = pick(lambda world: world)
        self._camera_world = self._world_lamps if self._env_requested or not self.transparent \
            else np.zeros(0, np.int32)
        self._camera_emitters = pick(lambda world: not world)
        self._camera_grouped = pick(lambda world: True) if self._env_requested else self._camera_lamps
        self._camera_env_pass = camera_env if (camera_env is not None and wv & VIS_CAMERA
                                               and not camera_env.dark) else None
        self._glass_world_lamps = np.array([j for j, l in enumerate(every)
                                            if isinstance(l, BackgroundLight) and l.seen_by_transmission], np.int32)
        # (with a world of their own, bounce rays see it instead of the lighting world's colour)
        self._bsdf_lamps = self._bsdf_every = np.array(
            [j for j, l in enumerate(diffuse) if l.seen_by_bsdf
             and not (self._bounce_worlds is not None and isinstance(l, BackgroundLight))], np.int32)
        self._bsdf_linked = np.zeros(0, np.int32)
        self._linked_tri_sets = np.zeros(0, np.int64)
        self._selection_table()

    def _without_coincident_copies(self, sd: SceneData, hittable, vis):
        """hittable without the emitters a BSDF ray never returns: those exactly covered by a
        lower-index triangle it stops at (lights/coincident.py), so light sampling sees the one
        surface hits see (a twin's samples had added its emission again: 2.1x Cycles, 1.42x the
        single quad); said, naming the objects."""
        blockers = ((vis & VIS_DIFFUSE) != 0) & (self.tri.area > 0) & ~self._tri_transparent
        copies, winners, grouped = coincident_copies(self.tri.vertices, self.tri.indices, hittable, blockers)
        if grouped is None:
            return hittable
        # copies listed in another corner order may still be hit where t rounds lower: such a
        # hit is MIS-weighted as one on its winner, the same surface (_selection_table)
        self._tri_alias = (copies, winners)
        hittable = hittable.copy()
        hittable[copies] = False
        copies, winners, grouped = _user_copies(sd.geometry, copies, winners, grouped)
        if not grouped.any():
            return hittable
        shown = sd.named_objects(grouped)
        # Cycles' bounce ray leaves one copy and meets the other at t ~ 0: copies that only emit
        # come out darker there (their shadow rays stop at each other), but where a copy that
        # reflects lies on an emitting one, each bounce gathers that emission again (an Add of
        # Diffuse and Emission mirrored twice: Combined 0.3515 in Cycles, 0.2158 as one surface;
        # "darker" had been said for it)
        reflects = np.asarray(self.mats.base).max(axis=0) > 0
        mat = np.asarray(self.tri.material)
        brighter = bool(reflects[mat[grouped]].any() or (len(winners) and reflects[mat[winners]].any()))
        how = ("Cycles renders these faces brighter: its bounce ray leaving one copy meets the other at zero "
               "distance and gathers its emission again") if brighter else "Cycles renders coincident faces darker"
        # Copies that emit differently (a duplicated panel given another strength, a glow decal on
        # a diffuse copy): the surface emits what the copy hits return emits, where Cycles shows
        # mostly the other copy. Said by the dropped copy's side: a quad of strength 1 over its
        # twin of 10 rendered 0.0456 against Cycles' 0.2955, 10 over 1 0.4558 against 0.0580;
        # both had been said "darker"
        emitted = np.asarray(self._tri_emission, np.float64).mean(axis=0)
        dropped, kept = emitted[copies], emitted[winners]
        differ = np.abs(dropped - kept) > 1e-3 * np.maximum(np.abs(dropped), np.abs(kept))
        more = differ & (dropped > kept)
        if differ.any():
            which = more if more.any() else differ
            lost, won = (np.zeros(len(self.tri), bool) for _ in range(2))
            lost[copies[which]], won[winners[which]] = True, True
            what = (f"DACRT renders what the copy its rays hit emits ({sd.named_objects(won)}), not the "
                    f"{'brighter' if more.any() else 'dimmer'} emission of {sd.named_objects(lost)}, which "
                    "Cycles shows too")
            how = (f"Cycles renders these faces brighter: the copies emit differently; {what}" if more.any() else
                   f"{how}; the copies emit differently: {what}")
        self.messages.append(('INFO', f"{int(grouped.sum())} emissive triangles of {shown} coincide with other "
                                      f"triangles: rendered as one surface ({how})"))
        return hittable

    def _say_near_copies(self, sd: SceneData, hittable):
        """Said where emitters repeat each other only up to rounding (lights/coincident.py
        near_copies: a twin under another transform, or moved by ~1e-6): not bit for bit, so
        both stay light-sampled and next-event estimation adds each copy's emission where BSDF
        hits count one surface (a quad's twin 1e-6 below it: 1.41x Cycles, which renders it as
        the quad alone). Then those that overlap other emitters in their plane without repeating
        them (lights/overlap.py: a twin turned 90 degrees splits along the other diagonal, 1.82x
        Cycles, and had been said nothing)."""
        # (only light-sampled ones: copies left to BSDF rays alone are not added twice)
        sampled = hittable & self.mats.light_sampled[self.tri.material]
        near, tol = near_copies(self.tri.vertices, self.tri.indices, sampled, _tubes(sd.geometry))
        over, over_tol = coplanar_overlaps(self.tri.vertices, self.tri.indices, sampled)
        if over is not None and near is not None:
            over &= ~near
        if over is not None and over.any():
            self.messages.append(('WARNING', f"{int(over.sum())} emissive triangles of {sd.named_objects(over)} "
                                             f"overlap other emissive triangles in their plane (within "
                                             f"{over_tol:.1g}) without repeating them corner for corner: each is "
                                             "light-sampled, so where they overlap their light comes out up to "
                                             "twice as bright as in Cycles, which renders them as one surface or "
                                             "darker; delete the duplicate or move it apart"))
        if near is None:
            return
        self.messages.append(('WARNING', f"{int(near.sum())} emissive triangles of {sd.named_objects(near)} "
                                         f"repeat other emissive triangles up to rounding (corners within "
                                         f"{tol:.1g}, not bit for bit): each copy is light-sampled, so their "
                                         "light comes out up to twice as bright as in Cycles, which renders "
                                         "them as one surface or darker; delete the duplicate or move it apart"))

    def _say_shadowless_emitters(self, sd: SceneData, sampled, vis):
        """Light-sampled emitters with Ray Visibility > Shadow off: their light samples pass
        through their own faces, where bounce rays stop, so light they reach only that way (an
        emitting inner shell behind its bounce-visible outer one) weighs what MIS gives it, and
        so depends on the light-selection pdf. Cycles' light tree picks each emissive triangle
        by its own bounds and orientation, DACRT's picks the object, then its triangles by power
        (lights/tree.py): what Cycles gives with Light Tree off (a Solidified emissive cube over
        a floor 1.08x Cycles, 0.995x with the tree off in both; per-face Front sampling 1.24x).
        Said only with the tree on (the setting is Cycles': operators.py copies it)."""
        if not (self._any_emissive and getattr(self.settings, 'use_light_tree', True)):
            return
        through = sampled & ((vis & VIS_SHADOW) == 0)
        if through.any():
            # (an emitter built per ray kind: shadow rays meet its copy, export/rayvariants.py)
            apart = np.array([m.ray_kinds_apart for m in sd.materials], bool)
            through &= ~apart[self.tri.material]
        if through.any():
            through &= ~self._coplanar_placements(sd, through, vis)
        if not through.any():
            return
        self.messages.append(('WARNING', f"emitter(s) {sd.named_objects(through)} have Ray Visibility > "
                                         "Shadow off: their light samples pass through their own faces, which stop "
                                         "bounce rays, so where those faces hide them the image depends on how a "
                                         "light is chosen; DACRT renders them as Cycles does with its Light Tree "
                                         "off (Cycles' light tree picks each emissive triangle apart)"))

    def _say_bounce_world_share(self):
        """Said where diffuse bounces see a world of their own (a Light Path mix) and the lighting
        world is light-sampled beside other light sources: the bounce world takes the MIS weight
        of the world's light samples (emitterhits._gather_bounce_world), so how often the light
        choice picks the world shapes the image, and DACRT's choice (a share for the world) is not
        Cycles' (its light tree weighs the world per shading point): a Noise world beside one
        emissive cube, fuzz 1589, 1.08-1.09x Cycles in the bounce world's channels (1.04x without
        the light tree); 0.9997-0.9999x without the cube, and with the same world on both sides."""
        if not self._bounce_worlds or self.lights.environment is None or self.lights.num_entries < 2:
            return
        self.messages.append(('WARNING', "world approximated: diffuse bounces see another world than light samples "
                                         "(a Light Path mix), weighted against the world's light samples, whose "
                                         "share of the light choice beside the other lights is DACRT's, not "
                                         "Cycles': the world's light may differ by several percent"))

    def _say_split_occluders(self, sd: SceneData):
        """Objects that light samples and bounce rays see differently (hidden from diffuse rays
        but casting shadows, or the reverse) beside lamps hidden from diffuse rays whose share of
        the light choice is DACRT's, not Cycles'. Behind such an object a light's samples and the
        bounce rays toward it disagree (shadowed or not), and MIS weighs the two by how likely
        the light is chosen. Both engines keep the hidden lamps in their choice
        (lights/choiceonly.py: fuzz seed 306, 0.97x Cycles while DACRT left them out, now
        matched, tests/parity/test_split_occluders.py); among lamps the light tree weighs them
        as Cycles' does, by their power. But DACRT's reweighting (LightSet.reweight) splits the
        choice between the suns, the tree and the world by what each gives the view, so a
        lamp that lights nothing gets only the uniform part of its group's share, where Cycles
        gives it its power's: a hidden sun beside the split box, Cycles 0.44% brighter than
        without it, DACRT unchanged (0.996x); Light Tree off, 0.997x. Hidden lamps of the tree's
        kind beside a sun BSDF rays meet, or beside a light-sampled world: the sun keeps 0.9 of
        DACRT's choice whatever their power or number (one hidden point lamp is no tree but a
        group of its own, with the same share), while Cycles' share moves with them: a 1.5 rad
        sun over the split box, 0.986x Cycles' mean beside one hidden 5000 W point lamp (z -42),
        0.997x beside two (z -9; 100x their power, the same), 1.0000x with none. Said for one
        or many alike."""
        lights = self.lights
        if not lights.hidden_lamps or lights.num_entries < 2 or not len(self.tri):
            return
        tree_on = bool(getattr(self.settings, 'use_light_tree', True))
        # (a lamp's bounds: its place in a tree; None for suns, which no tree holds)
        apart = [l.name for l in lights.hidden_lamps if not tree_on or l.bounds() is None]
        visible = lights.lamps[:lights.num_lamps - len(lights.hidden_lamps)]   # (the stand-ins close the lamps)
        beside = lights.environment is not None or any(l.seen_by_bsdf and l.bounds() is None for l in visible)
        treed = [l.name for l in lights.hidden_lamps if beside and tree_on and l.bounds() is not None]
        if not (apart or treed):
            return
        vis = self.tri.visibility
        split = (((vis & VIS_DIFFUSE) != 0) != ((vis & VIS_SHADOW) != 0)) & (self.tri.area > 0)
        if not split.any():
            return
        def names(ns):
            return ', '.join(repr(n) for n in dict.fromkeys(ns))
        which = ([f"outside the light tree (suns, or all with Light Tree off: {names(apart)})"] if apart else []) + \
                ([f"of the light tree's kind beside a sun or the world (the tree's share against them "
                  f"is DACRT's: {names(treed)})"] if treed else [])
        self.messages.append(('WARNING', f"object(s) {sd.named_objects(split)} hidden from diffuse rays but not from "
                                         "shadows (or the reverse): behind them light samples and bounce rays "
                                         "disagree, weighed by how likely each light is chosen, and light(s) "
                                         f"hidden from diffuse rays {', and '.join(which)} take a share of that "
                                         "choice that is DACRT's, not Cycles', so the light near those objects "
                                         "differs (about 1%)"))

    def _say_shadowless_lamps(self):
        """Lamps with Cast Shadow off that BSDF rays meet (MIS on, a radius, size or angle):
        their light samples light every point unshadowed, while the BSDF rays that head for them
        stop at whatever lies between, so MIS weighs an unshadowed and a shadowed estimate by
        the light-selection pdf. Alone, both engines pick the lamp with probability 1 and agree
        (1.0001x); beside another light source (a lamp, an emitter, a light-sampled world) each
        picks it with its own probability (reweight, the tree's estimates), so near an occluder
        the light differs: a shadowless area light beside a point light 1.01x Cycles' mean, 1.1x
        by a cube; a wide shadowless sun under a Hosek sky (fuzz seed 305) 4x4 blocks 1.08x.
        Lamps hidden from diffuse rays count among those others: both engines keep them in
        their selection (lights/choiceonly.py), where they take their share of the picks (a
        wide shadowless sun beside an area light hidden from diffuse rays: Cycles 0.7% darker
        than without it, fuzz 1459)."""
        lights = self.lights
        if self.lights.num_entries < 2:
            return
        # (instances of one lamp share its name: said once)
        names = list(dict.fromkeys(l.name for l in lights.lamps if not l.cast_shadow and l.seen_by_bsdf))
        if names:
            self.messages.append(('WARNING', f"light(s) {', '.join(repr(n) for n in names)} have Cast Shadow off "
                                             "and Multiple Importance on: light samples light past occluders, "
                                             "BSDF rays toward the light stop at them, and the two are weighed "
                                             "by how likely each light is chosen, which differs from Cycles "
                                             "beside other light sources, so the light near occluders differs "
                                             "(turn off Multiple Importance, or Cast Shadow back on, to match)"))

    def _say_surfaces_inside_sphere_spots(self):
        """Spot lights with Soft Falloff off (a sphere) and MIS on that have surfaces within
        their radius. Cycles' spot_light_intersect is one-sided: a ray from inside the sphere
        heading away from its centre does not meet it, while its light samples and MIS weights
        count the sphere all round, so Cycles renders those surfaces darker than the sphere's
        light (a floor 0.1 m under a 0.17 m spot: DACRT 1.05x at the centre; fuzz seed 320, an
        instanced spot by the floor, 1.38x the image mean; 1.04-1.4x measured before). DACRT
        lights them all round, as a point light of that radius (where Cycles agrees); with MIS
        off or Soft Falloff on both agree. Said, naming the spots, only where some triangle
        comes within the radius."""
        spots = [l for l in self.lights.lamps
                 if isinstance(l, SpotLight) and l.sphere and l.seen_by_bsdf and l.radius > 0]
        if not spots:
            return
        reach = TriangleReach(self.tri.geo)
        names = [l.name for l in spots if reach.within(l.center, l.radius)]
        if names:
            self.messages.append(('WARNING', f"spot light(s) {', '.join(repr(n) for n in dict.fromkeys(names))} with "
                                             "Soft Falloff off have surfaces within their radius: Cycles lights "
                                             "those from inside the sphere only by the half facing its centre where "
                                             "its rays find it, darker than the sphere's light, which DACRT renders "
                                             "all round (Soft Falloff on, or Multiple Importance off, match Cycles)"))

    def _say_lamps_ending_paths(self):
        """Lamps rays can meet (an area light, a point or spot of some radius; MIS on, whatever
        its ray visibility, or seen by the camera) under a low Light Paths > Transparent. Cycles' shade_light counts each lamp a
        ray meets as a transparent bounce and ends the path once the count reaches the limit, so
        what lies behind that lamp (a surface, the world, the lamps past it) is not seen: at a
        limit of 0 or 1 the first lamp met ends it. DACRT's rays pass lamps freely (the lamp's
        own light is found alike): a constant world over a floor under a 1 W area light at
        Transparent 0, Cycles 0.27% darker than without the lamp, DACRT 0.35% brighter (the
        lamp's light), z 40 (fuzz seed 10); a 2 m lamp 0.5 m over a floor, 1 bounce: DACRT's
        mean 1.12x Cycles' (0.4071 / 0.3626; tests/parity/test_lamp_transparent_bounces.py). Said
        at a limit of 0 or 1 only: from 2 on a path must meet lamps that many times, and the same
        scene at Transparent 2, 3 and 8 gives Cycles' one mean, 0.4071 (a warning counting every
        lamp of a scene against the limit had fired on any street of 8 lamps at the default)."""
        limit = self.max_transparent
        if limit > 1:
            return
        lights = self.lights
        # Cycles' lights_intersect meets every lamp of MIS on with BSDF rays, hidden from them
        # or not (integrate_light then finds no light there, but the pass still counts: a
        # shadowless point of 1.5 m radius hidden from diffuse and camera rays in a grey world at
        # Transparent 1, Cycles 3.3% darker than without it, DACRT the same; fuzz seed 44)
        met = [l for l in lights.lit if not l.at_infinity and not l.delta and (l.use_mis or l.seen_by_camera)]
        if not met:
            return
        names = ', '.join(repr(n) for n in dict.fromkeys(l.name for l in met))
        self.messages.append(('WARNING', f"light(s) {names} can be met by rays, and Cycles counts each light a ray "
                                         f"meets as a transparent bounce: at Light Paths > Transparent {limit} a "
                                         f"ray ends at the first light it meets, so what lies behind it (surfaces, the "
                                         "world, other lights) goes unseen there, where DACRT's rays pass lights "
                                         "(Transparent Max Bounces 2 or more to match)"))

    def _coplanar_placements(self, sd: SceneData, through, vis):
        """Mask of the triangles of `through` whose placement (object or instance) stops bounce
        rays only in the plane of its emitting faces (a light card): no face of it can stand
        between a receiver and an emitting one, so nothing of it is reached by light samples
        alone and the light-selection pdf cannot change the image (a card with Shadow off
        matched Cycles, 1.000x, blocks within noise). Any face off that plane (a sphere's far
        side behind its near one, a Solidified shell's inner faces) keeps it said."""
        place = np.asarray(sd.geometry.instance if sd.geometry.instance is not None
                           else sd.geometry.object_index, np.int64)
        geo, area = self.tri.geo, self.tri.area
        # each placement's largest emitting triangle of `through` gives its plane
        idx = np.flatnonzero(through)
        order = idx[np.lexsort((-area[idx], place[idx]))]
        places, first = np.unique(place[order], return_index=True)
        rep = order[first]
        n = geo[9:12, rep].T.astype(np.float64)
        d = np.einsum('ij,ij->i', n, geo[0:3, rep].T.astype(np.float64))
        # (float32 corners of a rotated card stray ~1e-7 of their coordinates off its plane)
        eps = 1e-5 * (np.abs(d) + np.sqrt(area[rep]) + 1e-6)
        which = np.full(int(place.max()) + 1, -1, np.int64)
        which[places] = np.arange(len(places))
        stops = np.flatnonzero(((vis & VIS_DIFFUSE) != 0) & (which[place] >= 0))
        k = which[place[stops]]
        v0 = geo[0:3, stops].T.astype(np.float64)
        off = np.zeros(len(places))
        for corner in (v0, v0 + geo[3:6, stops].T, v0 + geo[6:9, stops].T):
            np.maximum.at(off, k, np.abs(np.einsum('ij,ij->i', corner, n[k]) - d[k]))
        flat = np.zeros(len(which), bool)
        flat[places] = off <= eps
        return through & flat[place]

    def _selection_table(self):
        """The light choice next-event estimation draws from (dacrt.shading.LightChoice): per
        entry (lamps, then emissive triangles) its selection probability, whether it is sampled
        without MIS (lamps BSDF rays cannot meet: weight 1, as a delta light) and whether its
        samples cast shadow rays. lamp_prob per native lamp record (0 for the camera-only ones)
        weights BSDF hits on lamps."""
        lights = self.lights
        tris = lights.triangles
        nl = lights.num_lamps
        ntri = 0 if tris is None else len(tris.index)
        tri_prob = lights.tri_prob[tris.index] if ntri else np.zeros(0, F32)
        env = lights.environment
        nenv = int(env is not None)
        self._light_choice = dacrt.shading.LightChoice(
            self._nee_records, lights.cdf,
            np.concatenate([lights.lamp_prob, tri_prob, [lights.env_prob] * nenv]).astype(F32),
            np.concatenate([[not l.seen_by_bsdf for l in lights.lamps], np.zeros(ntri + nenv, bool)]),
            np.concatenate([[l.cast_shadow for l in lights.lamps], np.ones(ntri + nenv, bool)]),
            *((None, None, None) if tris is None else (tris.geo, tris.area, tris.emission)),
            environment=None if env is None else env.native, tree=lights.tree,
            tri_prim=None if tris is None else tris.index)       # (no point lights itself)
        # the light tree's keys of the lamp records and of the triangles (-1: not in it), for
        # the MIS weights of BSDF rays that meet them
        self._record_key = self._tri_key = None
        if lights.tree is not None:
            member = lights.tree_member
            self._record_key = np.full(len(self._record_lamps), -1, np.int32)
            self._record_key[:nl] = np.where(member[:nl], np.arange(nl), -1)
            self._tri_key = np.full(len(self.tri), -1, np.int32)
            if ntri:
                j = np.arange(ntri)
                self._tri_key[tris.index] = np.where(member[nl + j], nl + j, -1)
        if self._tri_alias is not None:
            copies, winners = self._tri_alias
            lights.tri_prob[copies] = lights.tri_prob[winners]
            if self._tri_key is not None:
                self._tri_key[copies] = self._tri_key[winners]
        every = self._record_lamps
        if self._groups:                    # light groups: each lamp record's and entry's group
            self._record_group = np.array([self._world_group if isinstance(l, BackgroundLight)
                                           else self._group_index.get(l.lightgroup, -1) for l in every],
                                          np.int64).reshape(-1)
            self._entry_group = self._entry_table(self._record_group, self._tri_group, self._world_group)
        if self._shadow_link is not None:   # shadow linking: each entry's set of blockers
            record_sets = np.array([_light_set(self._shadow_link, l) for l in every], np.int64).reshape(-1)
            self._entry_shadow_set = self._entry_table(record_sets, self._tri_shadow_set, 0)
            # its shadow rays' scene: 2 x set, + 1 for the emitters only Cycles' BSDF rays find
            # (their set's blockers and the objects in no blocker collection)
            self._entry_shadow_kind = 2 * self._entry_shadow_set + self._entry_table(
                np.zeros(len(record_sets), np.int64), self._tri_forced, 0)
            # A BSDF ray toward a shadow-linked emitter would be stopped by every object, its
            # blockers or not; Cycles traces a dedicated shadow ray toward the emitters it
            # passes, its search ending at the first opaque object in no blocker collection,
            # the ray stopped by the emitter's blockers. Shadow-linked lamps are gathered so
            # (_gather_shadow_linked: BSDF rays retraced against those objects), MIS-weighted
            # against their light samples as in Cycles, whose image then lacks their BSDF share
            # behind objects in no blocker collection (lit at weight 1 by light samples alone,
            # the shadows of such objects had been up to 1.05x Cycles beside two 1.8 m soft
            # point lamps). Light-sampled linked emissive triangles are gathered so too, per set
            # (a 6 m area light over a floor had been 0.68x Cycles under a plate its blockers
            # leave out when BSDF rays gathered it in the full scene; lit by light samples alone
            # at weight 1, 1.03x there); those Cycles leaves to BSDF rays (forced: light-sampled
            # here against the objects its search stops at) keep weight 1, as its BSDF rays'
            lamp = np.zeros(len(self._entry_shadow_set), bool)
            lamp[:nl] = True
            self._light_choice.no_mis[(self._entry_shadow_kind % 2 == 1) & ~lamp] = True
            forced = getattr(self, '_tri_forced', None)
            if forced is not None and self._tri_sampled is not None:
                linked = self._tri_sampled & (self._tri_shadow_set > 0) & ~forced
                self._linked_tri_sets = np.unique(self._tri_shadow_set[linked])
            self._bsdf_lamps = self._bsdf_every[record_sets[self._bsdf_every] == 0]
            self._bsdf_linked = self._bsdf_every[(record_sets[self._bsdf_every] > 0) & (self._bsdf_every < nl)]
            self._record_shadow_set = record_sets
        if self._link is not None:          # light linking: each entry's and lamp record's light set
            self._record_set = np.array([_light_set(self._link, l) for l in every], np.uint8).reshape(-1)
            self._entry_set = self._entry_table(self._record_set, self._tri_set, 0, np.uint8)
        # Cycles' Light > Max Bounces: at vertex k the lamps whose limit is below k are still
        # chosen with their probability but light nothing (their records' emission is 0), as
        # Cycles rejects their samples; BSDF rays still find them (Cycles does not limit those)
        self._max_bounces = np.array([l.max_bounces for l in lights.lamps], np.int64)
        self._choice_at = {}
        # lamps never chosen (unsampled, camera-only) have 0: a BSDF hit on them weighs 1
        self._record_prob = np.concatenate([lights.lamp_prob, np.zeros(len(lights.unsampled_lamps)
                                                                        + len(lights.camera_lamps), F32)]).astype(F32)

    def _entry_table(self, per_record, per_tri, env_value, dtype=np.int64):
        """A value per light-choice entry, from one per lamp record (the sampled lamps are the
        first records) and one per triangle: the lamps', the emissive triangles', the
        environment's (env_value)."""
        lights = self.lights
        tris = lights.triangles
        return np.concatenate([
            np.asarray(per_record, dtype).reshape(-1)[:len(lights.lamps)],
            np.asarray(per_tri, dtype)[tris.index] if tris is not None and len(tris.index) else np.zeros(0, dtype),
            np.full(int(lights.environment is not None), env_value, dtype)]).astype(dtype)

    def _init_linking(self, sd: SceneData):
        """Light linking (lights/linking.py): each triangle's receiver mask and, as emitter, its
        object's light set; None when no emitter links its light."""
        self._link = self._shadow_link = None
        links = getattr(sd, 'light_links', None) or {}
        shadow_links = getattr(sd, 'shadow_links', None) or {}
        if not (links or shadow_links) or not len(self.tri):
            return
        ob = np.asarray(sd.geometry.object_index, np.int64)
        names = sd.per_object(getattr(sd, 'object_keys', None) or sd.object_names, lambda i: None)
        # the emitters: lamps, objects with emissive triangles and a lighting world (in no link)
        emitters = [l.key or l.name for l in sd.lights]
        if self._any_emissive:
            emitters += [names[i] for i in np.unique(ob[self._tri_emissive])]
        world = np.asarray(sd.world).max() > 0 or sd.environment is not None
        link = LightLinking(links, names, self.messages,
                            unlinked=world or any(e not in links for e in emitters))
        if link.active:
            self._link = link
            self._tri_recv = np.take(link.object_mask, ob)
            self._tri_set = np.take(link.sets(names), ob)
        # shadow linking: the same sets of blocker objects; a light sample's shadow ray is then
        # traced against the triangles of its emitter's blockers only
        # (set 0 stays the unlinked emitters', every object blocking them: 63 sets fit)
        shadow = LightLinking(shadow_links, names, self.messages, kind='shadow linking blocker')
        if shadow.active:
            self._shadow_link = shadow
            self._tri_blocks = np.take(shadow.object_mask, ob)
            self._tri_shadow_set = np.take(shadow.sets(names), ob)
            # objects in no blocker collection (Cycles' blocker_shadow_set 0)
            listed = set()
            for included, excluded in shadow_links.values():
                listed.update(included)
                listed.update(excluded)
            self._tri_unlisted = np.take(np.array([n not in listed for n in names], bool).reshape(-1), ob)

    def _receivers(self, prim):
        """The receiver masks (k,) uint64 of the shading points (or ray origins) on prim."""
        return np.take(self._tri_recv, prim)

    def _light_choice_at(self, k):
        """The light choice of vertex k: the frame's, with the lamps past their Max Bounces dark."""
        past = self._max_bounces < k
        if not past.any():
            return self._light_choice
        key = past.tobytes()
        if key not in self._choice_at:
            c = self._light_choice
            records = c.records.copy()
            off, width = RECORD_FIELDS['emit']
            records[past, off:off + width] = 0.0
            self._choice_at[key] = dacrt.shading.LightChoice(
                records, c.cdf, c.prob, c.no_mis, c.shadow, c.tri_geo, c.tri_area, c.tri_emission, c.environment,
                c.tree, c.tri_prim)
        return self._choice_at[key]

    def _weight_lights(self, probes: int = 32):
        """Let the light choice follow where the camera looks: a probes x probes grid of camera
        rays (jittered by the seed) finds visible points, from which LightSet.reweight judges
        what each light group gives them and how narrow it looks (how badly BSDF sampling would
        find it)."""
        if self.lights.num_entries < 2 or not len(self.tri):
            return
        x0, y0, x1, y1 = self.camera.region
        rng = np.random.default_rng([int(self.settings.seed), 0x11847])
        g = (np.arange(probes) + 0.5) / probes
        rx = (x0 + (x1 - x0) * (g[None, :] + (rng.random((probes, probes)) - 0.5) / probes)).ravel()
        ry = (y0 + (y1 - y0) * (g[:, None] + (rng.random((probes, probes)) - 0.5) / probes)).ravel()
        O, D, tmax, rays = self.camera.rays(rx.astype(F32), ry.astype(F32), records=True)
        hits = self._global_prims('camera', self._scenes['camera'].intersect(
            rays, threads=self.threads, visible=self._visible['camera']))
        idx = np.flatnonzero(hits['prim'] >= 0)
        if not len(idx):
            return
        P, _, ns, P_off = self._surface(hits, idx, D)
        if self._any_translucent:
            # a translucent point is lit from its far side too: probed there as well (from the
            # near side alone, a leaf lit from behind, beside a sun, had 5x Cycles' noise; 2.5x)
            far = np.flatnonzero(np.take(self.mats.translucent, np.take(self.tri.material, hits['prim'][idx])))
            if len(far):
                _, _, fns, fPo = far_side(far, P, ns, ns, P_off)
                P_off, ns = np.concatenate([P_off, fPo], axis=1), np.concatenate([ns, fns], axis=1)
        self.lights.reweight(P_off, rng, N=ns)
        self._selection_table()

    def _procedural_emission_power(self):
        """Weigh the light choice of procedural emitters (noise-driven lava, a checker panel) by
        their emission's magnitude measured on their own surfaces: points spread by area over
        each such material's emitting triangles (16 a triangle, 4096 to 32768 a material),
        evaluated as its hits are; each triangle weighs 0.1 x the material's mean + 0.9 x its
        own points' mean (the material's where none fell on it). The weight moves noise only:
        every emitting triangle keeps a positive one (the floor; the export's guess over the
        unit cube where the points find nothing at all) and the table gathered from holds 1
        there. On a 32 x 32 grid under noise-driven lava, relMSE at 16 spp 0.100 -> 0.046 against
        the material's mean alone; thin stripes 0.233 -> 0.080; a smooth Wave the same."""
        entries = [e for e in self.mats.emission_textures if isinstance(e[1], ProceduralTexels)]
        if not entries:
            return
        rng = np.random.default_rng(0x5EED)
        budget = max(512, min(self._POWER_BUDGET, 8 * self._POWER_BUDGET // len(entries)))
        for m, tex, interp, ext, xf in entries:
            tris = np.flatnonzero((self.tri.material == m) & self._tri_emissive)
            if not len(tris):
                continue
            if not tex.name:            # attributes alone: measured at every triangle's corners
                self._attribute_emission_power(tex, interp, ext, xf, tris)
                continue
            n = min(budget, max(self._POWER_POINTS, self._POWER_POINTS_PER_TRIANGLE * len(tris)))
            cdf = np.cumsum(self.tri.area[tris].astype(np.float64))
            k = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side='right'), len(tris) - 1)
            s, r = np.sqrt(rng.random(n)), rng.random(n)       # uniform over each triangle
            u, v = (s * (1.0 - r)).astype(F32), (s * r).astype(F32)
            value = self._magnitude(tex, interp, ext, xf, tris[k], u, v)
            mean = value.mean(axis=1)
            if not mean.max() > 0:
                continue
            count = np.bincount(k, minlength=len(tris))
            own = np.stack([np.bincount(k, weights=value[c], minlength=len(tris)) for c in range(3)])
            own = np.where(count > 0, own / np.maximum(count, 1), mean[:, None])
            self._weigh_emitters(tris, mean, own)

    def _magnitude(self, tex, interp, ext, xf, prim, u, v):
        """|emission| (3, k) float64 of texture tex at (prim, u, v), NaN and infinity read 0.
        An emission that varies with the view (Fresnel, Layer Weight) is read from directions
        drawn about the front face's normal by cos, as its power weighs them; one that varies
        with the distance it is seen from (Light Falloff) from the camera's."""
        back = None
        if isinstance(tex, ProceduralTexels) and tex.needs & VIEW:
            g = self.tri.geo[:, prim].astype(np.float64)
            seen = self.camera.pos[:, None] - (g[0:3] + g[3:6] * u + g[6:9] * v)     # (both recentred)
            back = Facing.of(np.zeros(len(prim), bool), _cosine_directions(g[9:12], len(prim)),
                             np.sqrt((seen * seen).sum(axis=0)))
        value = self._lookup(tex, interp, ext, xf, prim, u, v, back)
        return np.abs(np.where(np.isfinite(value), value, F32(0.0))).astype(np.float64)

    def _weigh_emitters(self, tris, mean, own):
        """The light-choice weight of emitting triangles tris: 0.1 x their material's mean (3,)
        + 0.9 x their own measured magnitude (3, len(tris))."""
        floor = self._POWER_FLOOR
        self._tri_emission[:, tris] = (floor * mean[:, None] + (1.0 - floor) * own).astype(F32)

    def _attribute_emission_power(self, tex, interp, ext, xf, tris):
        """_procedural_emission_power for an emission of attributes alone (no texture: a
        vertex-coloured LED wall, an emission per object): each triangle weighs the mean
        magnitude at its three corners and its centre (every triangle measured, however many:
        the random points had left most of a large mesh at its material's mean), with the
        same floor of 0.1 x the material's (area-weighted) mean. Moves noise only: light
        samples read the sampled point's emission."""
        k = len(self._CORNER_POINTS)
        prim = np.repeat(tris, k)
        u = np.tile(self._CORNER_POINTS[:, 0], len(tris))
        v = np.tile(self._CORNER_POINTS[:, 1], len(tris))
        own = self._magnitude(tex, interp, ext, xf, prim, u, v).reshape(3, len(tris), k).mean(axis=2)
        area = self.tri.area[tris].astype(np.float64)
        mean = (own * area).sum(axis=1) / max(area.sum(), 1e-300)
        if mean.max() > 0:
            self._weigh_emitters(tris, mean, own)

    def _emission_table(self):
        """(3, M) per triangle: the radiance emission is gathered and light-sampled with (1 on
        image-emission triangles, whose hits and samples are then scaled by _emission_at)."""
        return self._tri_emission if self._tri_emission_unit is None else self._tri_emission_unit


def _light_set(linking, lamp) -> int:
    """A lamp's light set in linking (lights/linking.py, light or shadow linking): its own by
    unique name (Light.key); the world's is 0, every object's."""
    return 0 if isinstance(lamp, BackgroundLight) else linking.emitter_set(lamp.key)


def _tubes(geometry):
    """(one_sided bool (M,), placement (M,)): the hair and Curves tube triangles and each
    triangle's placement (Geometry.instance, else its object); None without tubes."""
    one = getattr(geometry, 'one_sided', None)
    if one is None:
        return None
    owner = geometry.instance if geometry.instance is not None else geometry.object_index
    return np.asarray(one, bool), np.asarray(owner)


def _user_copies(geometry, copies, winners, grouped):
    """coincident_copies' (copies, winners, grouped) without the pairs of one placement's own
    hair or Curves tube triangles (Geometry.one_sided): a strand tapering to its tip has rings
    thinner than float32 there, whose triangles round onto each other (fur of Shape 0.9: 2556
    of them, 1e-11 in area), a copy of DACRT's tessellation that Cycles' curves do not have
    (its image 1.02x Cycles'), not one the user modelled: not said."""
    tubes = _tubes(geometry)
    if tubes is None or not len(copies):
        return copies, winners, grouped
    one, place = tubes
    own = one[copies] & one[winners] & (place[copies] == place[winners])
    if not own.any():
        return copies, winners, grouped
    made = np.zeros(len(grouped), bool)
    made[copies[own]] = made[winners[own]] = True
    kept = np.zeros(len(grouped), bool)
    kept[copies[~own]] = kept[winners[~own]] = True
    return copies[~own], winners[~own], grouped & ~(made & ~kept)


def _cosine_directions(normals, k):
    """(3, k) unit directions drawn by cos about the normals (3, k) (a fixed sequence: the
    light choice is the same every frame)."""
    rng = np.random.default_rng(0xC05)
    r, phi = np.sqrt(rng.random(k)), 2.0 * np.pi * rng.random(k)
    n = normals.astype(np.float64)
    n = n / np.maximum(np.sqrt((n * n).sum(axis=0)), 1e-30)
    a = np.where(np.abs(n[0]) > 0.9, 0.0, 1.0)            # a helper axis not along n
    t = np.cross(n, np.stack([a, 1.0 - a, np.zeros(k)]), axis=0)
    t = t / np.maximum(np.sqrt((t * t).sum(axis=0)), 1e-30)
    b = np.cross(n, t, axis=0)
    return r * np.cos(phi) * t + r * np.sin(phi) * b + np.sqrt(np.maximum(1.0 - r * r, 0.0)) * n
