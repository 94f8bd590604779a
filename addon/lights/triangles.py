"""Emissive triangles as lights: chosen by power (area x mean radiance), sampled uniformly by
solid angle where a triangle is large for its distance and by area elsewhere (as Cycles'
kernel/light/triangle.h), emitting the material's emission from both sides (Cycles'
emissive_simple_eval). The per-sample geometry runs in the native kernel
dacrt.shading.sample_triangles (native/cpp/trianglelight.h)."""
from __future__ import annotations

import dacrt
import numpy as np

from .base import F32, LightSample


class EmissiveTriangles:
    """geo: (15, M) float32 rows v0, v1-v0, v2-v0, unit geometric normal, self-intersection
    offset step of the front side; area (M,); emission (3, M) radiance per triangle;
    eligible (M,) triangles that may act as lights."""

    def __init__(self, geo, area, emission, eligible, power_emission=None):
        lum = emission.astype(np.float64).mean(axis=0)      # float32 would overflow near 3e38
        self.index = np.flatnonzero(eligible & (lum > 0) & (area > 0))
        # power_emission (3, M): what weighs the choice where `emission` is not the radiance
        # (an image's emission: 1 here, its average there)
        if power_emission is not None:
            lum = power_emission.astype(np.float64).mean(axis=0)
        self.power = (area[self.index] * lum[self.index] * 2.0 * np.pi).astype(np.float64)
        self.geo = np.ascontiguousarray(geo[:, self.index])
        self.area = area[self.index].astype(F32)
        self.emission = np.ascontiguousarray(emission[:, self.index], F32)
        # one emitter material (the common case) needs no per-sample gather
        same = len(self.index) and np.all(self.emission == self.emission[:, :1])
        self.uniform_emission = self.emission[:, 0].copy() if same else None

    def __len__(self):
        return len(self.index)

    def sample(self, P, which, u1, u2):
        """Points on triangles self.index[which] seen from the surface points P (3,n).

        The shadow ray must end at a point pushed off the emitter toward P (LightSample.target)
        instead of racing the emitter itself to the same t. Radiance and pdf use the exact points."""
        wi, dist, pdf, target = dacrt.shading.sample_triangles(self.geo, self.area, which, P, u1, u2)
        # an emission near float32's limit over a small pdf overflows to inf: the film drops
        # such samples and says so, so numpy's console warning would only be noise
        with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
            scale = np.where(pdf > 0, F32(1.0) / pdf, F32(0.0))
            if self.uniform_emission is not None:
                value = self.uniform_emission[:, None] * scale
            else:
                value = np.take(self.emission, which, axis=1)
                value *= scale
        return LightSample(wi, dist, value, pdf, target)
