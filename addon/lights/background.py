"""The world background as a light: uniform radiance from every direction; rays that miss all
geometry see it.

Light sampling leaves it out (`light_sampled`), as Cycles does for a world shader that does not
vary over directions (no portals): scene/light.cpp enables the background light only when
`has_portal || (use_mis && shader->has_surface_spatial_varying)`. For uniform radiance the
cosine-weighted bounce already draws directions in proportion to what they add (cos/pi), so BSDF
rays collect the world with weight 1, and every light sample goes to the other lights. (Sampling
it too, even at 10% of the light samples, made the outdoor benchmark 1.5x noisier than Cycles.)
`sample` (uniform over the sphere, pdf 1/(4 pi)) and the native record stay for the tests and
kernels that define them."""
from __future__ import annotations

import numpy as np

from ..sampling import uniform_sphere
from .base import F32, KIND_BACKGROUND, Lamp, LightSample, make_record, outer

INV_4PI = F32(1.0 / (4.0 * np.pi))


class BackgroundLight(Lamp):
    at_infinity = True
    light_sampled = False

    def __init__(self, color):
        super().__init__(color=color)
        self.emit = np.asarray(color, F32)

    def record(self):
        return make_record(KIND_BACKGROUND, 0, emit=self.emit, pdf=INV_4PI)

    def sample(self, P, u1, u2):
        n = P.shape[1]
        return LightSample(uniform_sphere(u1, u2), np.full(n, np.inf, F32),
                           outer(self.emit / INV_4PI, np.ones(n, F32)), np.full(n, INV_4PI, F32))

    def eval_miss(self, D):
        n = D.shape[1]
        return np.arange(n), outer(self.emit, np.ones(n, F32)), np.full(n, INV_4PI, F32)
