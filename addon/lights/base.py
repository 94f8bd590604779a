"""What every light offers the integrator: a sample toward a shading point and, for lights that
rays can see, the radiance and pdf where a ray meets them.

Conventions (Cycles' units, reference blender-cycles.md section 2.2); vectors are (3, n) float32:
- `sample(P, u1, u2)` returns a LightSample for surface points P (the integrator starts the
  shadow ray from an offset origin): unit direction wi toward the light, shadow-ray length dist,
  value = radiance / pdf (RGB, zero where the light cannot reach P), and the solid-angle pdf
  (np.inf for delta lights, which MIS must not weight down). The light *selection* probability
  is not included; LightSet handles it.
- `intersect(O, D, tmax)` (finite lights) and `eval_miss(D)` (lights at infinity) return
  (indices of the rays that see the light, radiance (3,k), solid-angle pdf (k,)).
Lights are not geometry: they never occlude, and a ray that meets one keeps going (as in Cycles).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

F32 = np.float32
EMPTY_IDX = np.zeros(0, np.int64)


@dataclass
class LightSample:
    wi: np.ndarray       # (3,n) unit direction from the shading point to the light
    dist: np.ndarray     # (n,) shadow ray length (inf for lights at infinity)
    value: np.ndarray    # (3,n) radiance / pdf
    pdf: np.ndarray      # (n,) solid-angle pdf (inf: delta light)
    target: np.ndarray | None = None   # (3,n) point the shadow ray must end at (lights that are
                                       # geometry); None: the ray runs dist along wi


def luminance(rgb) -> float:
    """Scalar power measure of an RGB triple (the mean: any positive channel counts)."""
    return float(np.mean(np.asarray(rgb, np.float64)))


def outer(color: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(3,) colour times (n,) scalars -> (3,n)."""
    return color[:, None] * scale


class Lamp(ABC):
    """Shared settings of a Blender light (object visibility, MIS, shadows)."""
    delta = False           # a point or direction: only light sampling can find it
    at_infinity = False     # seen by rays that miss all geometry (sun, world)

    def __init__(self, light=None, color=None):
        if light is not None:
            self.name = light.name
            self.color = np.asarray(light.strength, np.float64)
            self.use_mis = bool(light.use_mis)
            self.cast_shadow = bool(light.cast_shadow)
            self.visible_camera = bool(getattr(light, 'visible_camera', True))
            self.visible_diffuse = bool(getattr(light, 'visible_diffuse', True))
            self.normalize = bool(light.normalize)
        else:
            self.name = 'World'
            self.color = np.asarray(color, np.float64)
            self.use_mis = self.cast_shadow = self.visible_camera = self.visible_diffuse = True
            self.normalize = True

    @property
    def seen_by_camera(self) -> bool:
        return self.visible_camera and not self.delta

    @property
    def seen_by_bsdf(self) -> bool:
        """BSDF rays collect this light (with MIS); lights without MIS are NEE-only, as in Cycles."""
        return self.visible_diffuse and self.use_mis and not self.delta

    @property
    def dark(self) -> bool:
        """No emission at all: the lamp is skipped."""
        return luminance(self.color) <= 0

    @abstractmethod
    def sample(self, P, u1, u2) -> LightSample:
        """Sample a direction toward the light from each shading point."""

    def intersect(self, O, D, tmax):
        return EMPTY_IDX, np.zeros((3, 0), F32), np.zeros(0, F32)

    def eval_miss(self, D):
        return EMPTY_IDX, np.zeros((3, 0), F32), np.zeros(0, F32)
