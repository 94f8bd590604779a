"""Lights in Cycles' units, and the choice of one light per shading point for next-event estimation.

Owns the translation of SceneData lights, the world and emissive triangles into samplers
(one light type per module, like Cycles' kernel/light/), and the discrete distribution that
picks one of them per shading point. As Cycles does without its light tree: every lamp (the
world counts as one) is equally likely, emissive triangles are chosen by power (area x mean
radiance), and when both exist each group gets half. Lamps in different units (a sun's
irradiance, a point's watts) are never compared. The selection probability of every light is
known, so a BSDF ray that meets a light can be weighted against light sampling (MIS).
Lamps with diffuse ray visibility off take no part in that choice (camera rays may see them).
"""
from __future__ import annotations

import numpy as np

from .area import AreaLight
from .background import BackgroundLight
from .base import F32, Lamp, LightSample
from .point import PointLight, SpotLight
from .sun import SunLight
from .triangles import EmissiveTriangles

__all__ = ['LightSet', 'LightSample', 'Lamp', 'BackgroundLight', 'EmissiveTriangles', 'make_lamp']

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


class LightSet:
    """All light sources of a frame and the choice of one per shading point (see module doc)."""

    def __init__(self, lamps, triangles: EmissiveTriangles | None, num_triangles: int):
        lit = [l for l in lamps if not l.dark]
        self.skipped_lamps = [l.name for l in lamps if l.dark]
        # Cycles excludes a light with diffuse ray visibility off from diffuse surfaces
        # altogether (light sampling and BSDF hits): only camera rays may still see it.
        self.lamps = [l for l in lit if l.visible_diffuse]
        self.camera_lamps = [l for l in lit if not l.visible_diffuse and l.seen_by_camera]
        self.unseen_lamps = [l.name for l in lit if not l.visible_diffuse and not l.seen_by_camera]
        self.triangles = triangles if triangles is not None and len(triangles) else None
        lamp_w = np.ones(len(self.lamps)) / max(len(self.lamps), 1)
        tri_w = self.triangles.power / self.triangles.power.sum() if self.triangles is not None else np.zeros(0)
        share = 0.5 if len(lamp_w) and len(tri_w) else 1.0
        w = np.concatenate([lamp_w * share, tri_w * share])
        total = w.sum()
        self.num_lamps = len(self.lamps)
        self.num_entries = len(w)
        self.tri_prob = np.zeros(num_triangles, F32)      # selection probability per global triangle
        if total > 0:
            p = w / total
            self.cdf = np.cumsum(p)
            self.cdf[-1] = 1.0
            self.lamp_prob = p[:self.num_lamps].astype(F32)
            if self.triangles is not None:
                self.tri_prob[self.triangles.index] = p[self.num_lamps:]
        else:
            self.cdf = np.zeros(0)
            self.lamp_prob = np.zeros(0, F32)

    def __bool__(self):
        return self.num_entries > 0

    @property
    def seen_by_bsdf(self) -> bool:
        """Whether BSDF rays can collect any light (emissive triangles, visible lamps, world)."""
        return self.triangles is not None or any(l.seen_by_bsdf for l in self.lamps)

    def select(self, u: np.ndarray) -> np.ndarray:
        """Entry per uniform: 0..num_lamps-1 are lamps, num_lamps + j is triangles.index[j]."""
        e = np.searchsorted(self.cdf, u, side='right')
        return np.minimum(e, self.num_entries - 1).astype(np.int32)
