"""Sun (distant) light (Cycles kernel/light/distant.h).

strength is the irradiance E (W/m^2) at normal incidence. angle 0: a delta direction. angle > 0:
uniform radiance L = E / (pi sin^2(angle/2)) inside the cone of half-angle angle/2 around the
object's +Z (light travels along -Z); unnormalised, L = strength. An IES profile (a sun with
an angle) multiplies it per direction it travels, in the sun's object space, as Cycles' IES
Texture reads it there (a delta sun's is one factor: export/lights.py).
"""
from __future__ import annotations

import numpy as np

from ..sampling import dot, to_world, uniform_cone
from .base import F32, KIND_SUN, Lamp, LightSample, col, make_record, matvec, outer
from .ies import ies_direction


class SunLight(Lamp):
    at_infinity = True

    def __init__(self, light):
        super().__init__(light)
        z = np.asarray(light.matrix, np.float64)[:3, 2]
        length = np.linalg.norm(z)
        if not length > 0:
            raise ValueError(f"sun light {light.name!r}: object transform has no Z axis")
        self.to_sun = (z / length).astype(F32)
        half = 0.5 * float(light.angle)
        if not (0.0 <= half <= 0.5 * np.pi + 1e-6):     # 180 degrees in float32 exceeds pi
            raise ValueError(f"sun light {light.name!r}: angle {light.angle!r} must be in [0, pi]")
        half = min(half, 0.5 * np.pi)
        self.delta = half == 0.0
        self.omc = F32(2.0 * np.sin(0.5 * half) ** 2)     # 1 - cos(half)
        self.cos_half = F32(1.0) - self.omc
        if self.delta:
            self.emit = self.color.astype(F32)                     # irradiance
        else:
            fac = 1.0 / (np.pi * np.sin(half) ** 2) if self.normalize else 1.0
            self.emit = (self.color * fac).astype(F32)             # radiance
        self.pdf = F32(np.inf if self.delta else 1.0 / (2.0 * np.pi * float(self.omc)))
        # (point.py's: directions world -> object as a normal, M^T of the rotation and scale)
        self.ies = getattr(light, 'ies', None)
        if self.ies is not None and self.delta:
            raise ValueError(f"sun light {light.name!r}: an IES profile needs an angle > 0 (a delta sun's is a factor)")
        m = np.asarray(light.matrix, np.float64)
        self.ies_m3 = m[:3, :3].T.astype(F32) if self.ies is not None else None

    def record(self):
        # shape 0: delta (its infinite pdf is implied, records stay finite), 1: cone
        extra = {} if self.ies is None else dict(ies=self._ies_id(), ies_m3=self.ies_m3)
        return make_record(KIND_SUN, 0 if self.delta else 1, emit=self.emit, pos=self.to_sun, cos_half=self.cos_half,
                           omc=self.omc, pdf=0.0 if self.delta else self.pdf, **extra)

    def _profile(self, wi):
        """(k,) the IES profile along -wi (wi: (3, k) toward the sun), 1 without one."""
        if self.ies is None:
            return np.ones(wi.shape[1], F32)
        return ies_direction(self.ies, matvec(self.ies_m3, -np.asarray(wi, F32))).astype(F32)

    def sample(self, P, u1, u2):
        n = P.shape[1]
        dist = np.full(n, np.inf, F32)
        ones = np.ones(n, F32)
        if self.delta:
            wi = np.empty((3, n), F32)
            wi[:] = col(self.to_sun)
            return LightSample(wi, dist, outer(self.emit, ones), np.full(n, np.inf, F32))
        local, _ = uniform_cone(u1, u2, self.omc)
        wi = to_world(local, self.to_sun)
        return LightSample(wi, dist, outer(self.emit / self.pdf, self._profile(wi)), np.full(n, self.pdf, F32))

    def eval_miss(self, D):
        if self.delta:
            return super().eval_miss(D)
        idx = np.flatnonzero(dot(D, self.to_sun) >= self.cos_half)
        k = len(idx)
        return idx, outer(self.emit, self._profile(D[:, idx])), np.full(k, self.pdf, F32)
