"""Lights in Cycles' units, and the choice of one light per shading point for next-event estimation.

Owns the translation of SceneData lights, the world and emissive triangles into samplers
(one light type per module, like Cycles' kernel/light/), and the discrete distribution that
picks one of them per shading point. With two or more lights that have a position (point,
spot and area lamps, emissive triangles) they form one group, the light tree (tree.py), which
picks among them per shading point by estimated contribution, as Cycles' light tree does; a
single such light is a group of its own. Suns are a group each and the environment map one.
By default each kind (suns, the lights with a position, the environment) gets an equal share;
without a tree, every lamp is equally likely and emissive triangles are chosen by power.
`reweight` then tilts the split between the groups toward
the lights BSDF sampling finds badly from points the camera sees: small lights over wide ones,
mixed with 20% of the uniform split. Under MIS the cosine-weighted bounces already sample a
wide light well; giving the world half the light samples put DACRT 3-7x behind Cycles on sun +
sky and area light + world scenes, and even 10% left it 1.5x behind, so the uniform world now
takes none (background.py). (Weighting by estimated irradiance was tried and dropped: it is
global, and starved a spot light where it is the main light.) The selection probability of
every light is known, so a BSDF ray that meets a light can be weighted against light sampling
(MIS).
Lamps with diffuse ray visibility off light no diffuse surface (camera rays may see them) but,
as in Cycles, keep their share of that choice, as stand-ins whose samples give nothing
(choiceonly.py). The (uniform) world takes no part in it: BSDF rays alone collect it, with
weight 1, as in Cycles (background.py says why). An environment map, which varies over
directions, is a group of its own (environment.py), chosen last in the table.
"""
from __future__ import annotations

from collections import Counter

import numpy as np

from .area import AreaLight
from .background import BackgroundLight
from .environment import EnvironmentLight
from .lamplanes import lamp_group_stats
from .base import F32, RECORD_WIDTH, Lamp, LightSample
from .choiceonly import choice_only
from .point import PointLight, SpotLight
from .sun import SunLight
from .tree import build_tree
from .triangles import EmissiveTriangles

__all__ = ['LightSet', 'LightSample', 'Lamp', 'BackgroundLight', 'EnvironmentLight', 'EmissiveTriangles', 'make_lamp',
           'lamp_records']

_KINDS = {'POINT': PointLight, 'SPOT': SpotLight, 'SUN': SunLight, 'AREA': AreaLight}


def make_lamp(light) -> Lamp:
    cls = _KINDS.get(light.kind)
    if cls is None:
        raise ValueError(f"light {light.name!r}: kind {light.kind!r} is not one of {sorted(_KINDS)}")
    s = np.asarray(light.strength, np.float64)
    if s.shape != (3,) or not np.isfinite(s).all() or (s < 0).any():
        raise ValueError(f"light {light.name!r}: strength must be 3 finite non-negative numbers, got {light.strength!r}")
    m = np.asarray(light.matrix, np.float64)
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise ValueError(f"light {light.name!r}: matrix must be a finite 4x4 transform")
    return cls(light)


def lamp_records(lamps) -> np.ndarray:
    """(R, RECORD_WIDTH) float32: the native lamp records (dacrt.lamps) of lamps, in order."""
    rows = [lamp.record() for lamp in lamps]
    return np.stack(rows) if rows else np.zeros((0, RECORD_WIDTH), F32)


class LightSet:
    """All light sources of a frame and the choice of one per shading point (see module doc)."""

    def __init__(self, lamps, triangles: EmissiveTriangles | None, num_triangles: int,
                 environment: EnvironmentLight | None = None, use_tree: bool = True, tri_object=None,
                 unsampled_emitters: bool = False, light_sets=None, glass: bool = False):
        """light_sets: None, or with light linking (lamp -> its light set, (num_triangles,) the
        light set of each triangle as an emitter): the tree then never picks a light of a set
        the shading point's object is not lit by. glass: camera rays may pass glass (then a lamp
        they see by its Transmission visibility alone is kept)."""
        lit = [l for l in lamps if not l.dark]
        self.lit = lit                  # every lamp Cycles keeps, hidden from diffuse rays or not
        # emissive triangles light sampling never picks (Emission Sampling None): BSDF rays
        # still find them
        self.unsampled_emitters = unsampled_emitters
        self.skipped_lamps = [l.name for l in lamps if l.dark]
        if environment is not None and environment.dark:
            self.skipped_lamps.append('World (black environment map)')
            environment = None
        self.environment = environment
        # Cycles excludes a light with diffuse ray visibility off from diffuse surfaces
        # (its light samples light no diffuse closure, BSDF rays pass it): only camera rays may
        # still see it. It keeps its share of the light choice, though, which lowers every other
        # light's, and so their MIS weights: a stand-in that gives nothing takes it (choiceonly.py)
        self.hidden_lamps = [choice_only(l) for l in lit if not l.visible_diffuse and l.light_sampled]
        self.lamps = [l for l in lit if l.visible_diffuse and l.light_sampled] + self.hidden_lamps
        # lamps only BSDF (and camera) rays find: never chosen, so a BSDF hit weighs 1
        self.unsampled_lamps = [l for l in lit if l.visible_diffuse and not l.light_sampled]
        # (camera rays past glass see by Transmission visibility: the integrator tells them apart)
        seen = [l.seen_by_camera or (glass and l.seen_by_transmission) for l in lit]
        self.camera_lamps = [l for l, c in zip(lit, seen) if not l.visible_diffuse and c]
        # (unseen: skipped, or, light-sampled, kept in the choice alone: choice_only_lamps)
        self.unseen_lamps = [l.name for l, c in zip(lit, seen) if not l.visible_diffuse and not c
                             and not l.light_sampled]
        self.choice_only_lamps = [l.name for l, c in zip(lit, seen) if not l.visible_diffuse and not c
                                  and l.light_sampled]
        self.triangles = triangles if triangles is not None and len(triangles) else None
        self.num_lamps = len(self.lamps)
        self._num_triangles = num_triangles
        ntri = 0 if self.triangles is None else len(self.triangles)
        self.num_entries = self.num_lamps + ntri + (environment is not None)
        # the light choice's entries: lamps, then emissive triangles, then the environment
        sets = None if light_sets is None else ([light_sets[0](l) for l in self.lamps], light_sets[1])
        self.tree, self.tree_entries = build_tree(self.lamps, self.triangles, self.num_lamps, use_tree, tri_object,
                                                  sets)
        self.tree_member = np.zeros(self.num_entries, bool)     # per entry: a light of the tree
        self.tree_member[self.tree_entries] = True
        self._groups = self._group_table(ntri)
        # each kind an equal share: lamps (without a tree) or suns (with one), the emissive
        # triangles (without a tree) or the tree, the environment; lamps split theirs evenly
        kind = [g[0] for g in self._groups]
        counts = Counter(kind)
        share = 1.0 / max(len(counts), 1)
        self._set_groups(np.asarray([share / counts[k] for k in kind], np.float64))

    def _group_table(self, ntri):
        """[(kind, entries, weights within)]: the groups reweight splits the choice between."""
        groups = [('lamps', np.array([i]), np.ones(1)) for i in range(self.num_lamps) if not self.tree_member[i]]
        if self.tree is not None:
            # the first member holds the group's mass in the cdf (LightChoice: the tree picks)
            within = np.zeros(len(self.tree_entries))
            within[0] = 1.0
            groups.append(('tree', self.tree_entries, within))
        elif ntri:
            power = self.triangles.power
            groups.append(('triangles', self.num_lamps + np.arange(ntri), power / power.sum()))
        if self.environment is not None:
            groups.append(('environment', np.array([self.num_entries - 1]), np.ones(1)))
        return groups

    def _set_groups(self, group_p):
        """Selection probabilities from one per group (_groups' order). A tree member's prob
        is its group's: the tree's own pdf at the point multiplies it (LightChoice)."""
        w = np.zeros(self.num_entries)
        for (kind, entries, within), g in zip(self._groups, group_p):
            w[entries] = g * within
        total = w.sum()
        self.tri_prob = np.zeros(self._num_triangles, F32)   # selection probability per global triangle
        if total > 0:
            p = w / total
            self.cdf = np.cumsum(p)
            self.cdf[-1] = 1.0
            for (kind, entries, _), g in zip(self._groups, group_p):
                if kind == 'tree':
                    p[entries] = g / total
            self.lamp_prob = p[:self.num_lamps].astype(F32)
            ntri = 0 if self.triangles is None else len(self.triangles.index)
            if self.triangles is not None:
                self.tri_prob[self.triangles.index] = p[self.num_lamps:self.num_lamps + ntri]
            self.env_prob = float(p[-1]) if self.environment is not None else 0.0
        else:
            self.cdf = np.zeros(0)
            self.lamp_prob = np.zeros(0, F32)
            self.env_prob = 0.0

    def __bool__(self):
        return self.num_entries > 0

    def reweight(self, P: np.ndarray, rng: np.random.Generator, uniform_mix: float = 0.2, N=None):
        """Split the selection between the groups by what each would give the points P ((3, n)
        float32, e.g. where camera rays land; N: their unit normals, or None) and how badly
        BSDF sampling would find it there: a group's weight is the mean over one light sample
        per point of its unshadowed contribution (luminance of radiance / pdf, times the
        cosine at N, over the pick's probability within the group) times its narrowness (1 -
        the light's solid angle / 2 pi, the solid angle taken as 1 / pdf; 1 for delta
        lights). Under MIS a light as wide as the sky is found well by the cosine-weighted
        bounces, so light samples are better spent on small lights, and a dim lamp beside a
        bright sky should not take half of them (by narrowness alone a 1 W point light beside
        an HDRI took half: 4.9x Cycles' noise). Groups that give the points nothing are
        weighed by narrowness alone when all do. Mixed with uniform_mix of the uniform split,
        so every group keeps a share."""
        groups = len(self._groups)
        n = P.shape[1]
        if groups < 2 or n == 0:
            return
        u1, u2 = rng.random((2, n), np.float32)
        narrow, gives = np.zeros(groups), np.zeros(groups)
        # each lamp a group of its own (no tree): all sampled at once (lamplanes), the same bits
        alone = [g for g, (kind, _, _) in enumerate(self._groups) if kind == 'lamps']
        if alone:
            narrow[alone], gives[alone] = lamp_group_stats(
                [self.lamps[int(self._groups[g][1][0])] for g in alone], P, u1, u2, N)
        for g, (kind, entries, within) in enumerate(self._groups):
            if kind == 'lamps':
                continue
            if kind == 'environment':      # (the renderer's samples: the readable definition
                wi, value, pdf = self.environment.native_sample(u1, u2)   # builds tables of its own)
                pick = np.ones(n)
            else:                       # the tree's or the power-weighted pick at each point
                if kind == 'tree':
                    which, pick = self.tree.sample(np.ascontiguousarray(P, F32), rng.random(n))
                    which = which.astype(np.int64)
                else:
                    which = self.num_lamps + np.minimum(np.searchsorted(np.cumsum(within), rng.random(n)),
                                                        len(within) - 1)
                    pick = within[which - self.num_lamps]
                wi, value, pdf = self._entry_samples(P, which, u1, u2)
            narrow[g] = self.narrowness(pdf)
            lum = np.nan_to_num(np.asarray(value, np.float64).mean(axis=0), nan=0.0, posinf=0.0)
            cos = 1.0 if N is None else np.maximum((np.asarray(N, np.float64) * wi).sum(axis=0), 0.0)
            with np.errstate(divide='ignore', invalid='ignore'):
                gives[g] = float(np.nan_to_num(np.where(pick > 0, lum * cos / pick, 0.0)).mean())
        w = narrow * gives
        if not (np.isfinite(w).all() and w.sum() > 0):
            w = narrow
        if not w.sum() > 0:
            return
        self._set_groups((1.0 - uniform_mix) * w / w.sum() + uniform_mix / groups)

    def _entry_samples(self, P, which, u1, u2):
        """(wi (3, n), value (3, n), solid-angle pdf (n,)) of one light sample per point P[:, i]
        of entry which[i] (a lamp or an emissive triangle)."""
        n = P.shape[1]
        wi, value, pdf = np.zeros((3, n), F32), np.zeros((3, n), F32), np.zeros(n, F32)
        for e in np.unique(which[which < self.num_lamps]):
            at = np.flatnonzero(which == e)
            s = self.lamps[int(e)].sample(P[:, at], u1[at], u2[at])
            wi[:, at], value[:, at], pdf[at] = s.wi, s.value, s.pdf
        tri = np.flatnonzero(which >= self.num_lamps)
        if len(tri):
            s = self.triangles.sample(np.ascontiguousarray(P[:, tri]), which[tri] - self.num_lamps, u1[tri], u2[tri])
            wi[:, tri], value[:, tri], pdf[tri] = s.wi, s.value, s.pdf
        return wi, value, pdf

    @staticmethod
    def narrowness(pdf) -> float:
        """Mean over the samples that reach a point of 1 - 1 / (2 pi pdf), clipped to [0, 1]."""
        pdf = np.asarray(pdf, np.float64)
        valid = pdf > 0
        if not valid.any():
            return 0.0
        with np.errstate(divide='ignore'):
            return float(np.clip(1.0 - 1.0 / (2.0 * np.pi * pdf[valid]), 0.0, 1.0).mean())

    @property
    def seen_by_bsdf(self) -> bool:
        """Whether BSDF rays can collect any light (emissive triangles, visible lamps, world)."""
        return (self.triangles is not None or self.environment is not None or self.unsampled_emitters
                or any(l.seen_by_bsdf for l in self.lamps + self.unsampled_lamps))
