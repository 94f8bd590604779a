"""The world's Environment Texture as a light: an equirectangular image of radiance around the
scene, seen by rays that miss everything and sampled in proportion to its brightness.

This module is the readable definition the native kernels (dacrt.lamps.EnvironmentMap,
native/cpp/environment.h) are tested against; the integrator renders with those.
- Mapping as Cycles' direction_to_equirectangular (checked against a Cycles panoramic render):
  a direction m in the map's frame has u = 0.5 - atan2(m_y, m_x) / 2 pi, v = 1 - acos(m_z) / pi;
  the image's row 0 is the bottom (the -Z pole). World directions reach the map frame through
  `to_map` (the Mapping node's rotation; orthogonal).
- Lookup 'Linear' (bilinear, texel centres at (j + 0.5) / w) or 'Closest', REPEAT in u and v as
  Cycles' environment lookup.
- Importance: texel (i, j) is chosen with probability proportional to the average over it of
  the looked-up radiance's RGB mean (for bilinear lookup the (1, 6, 1) / 8 blend with its
  neighbours in u and v, exactly) times sin(theta) at its row's centre (its solid angle), and a
  point uniform in it; the solid-angle pdf is p_ij w h / (2 pi^2 sin(theta)). Cycles builds its
  background map from the same kind of per-texel evaluation. Without the blend, three quarters
  of a one-texel sun (spread into its neighbours by the bilinear filter) were left to BSDF rays.
Unlike the uniform world (background.py), a map that varies is light-sampled, as Cycles does for
a world shader that varies over directions: a small bright region (a sun in an HDRI) is what
BSDF sampling finds badly.
"""
from __future__ import annotations

import numpy as np

from ..texture import texture_lookup
from .base import F32, LightSample

_TWO_PI2 = 2.0 * np.pi * np.pi


class EnvironmentLight:
    """An environment map (scenedata.Environment) as a light at infinity."""
    name = 'World'
    at_infinity = True
    light_sampled = True
    delta = False
    use_mis = cast_shadow = visible_camera = visible_diffuse = True

    def __init__(self, env):
        rgb = np.asarray(env.pixels, np.float32)[..., :3] * np.asarray(env.strength, np.float32)
        self.rgb = np.ascontiguousarray(rgb, np.float32)
        self.to_map = np.asarray(env.to_map, np.float64)
        self.interpolation = env.interpolation
        h, w = self.rgb.shape[:2]
        theta = np.pi * (1.0 - (np.arange(h) + 0.5) / h)
        mean = self.rgb.astype(np.float64).mean(axis=2)
        if self.interpolation != 'Closest':
            # the bilinear image's average over each texel: (1, 6, 1) / 8 in u and v (REPEAT)
            for axis in (0, 1):
                mean = (np.roll(mean, 1, axis) + 6.0 * mean + np.roll(mean, -1, axis)) / 8.0
        weight = mean * np.sin(theta)[:, None]
        self.total = float(weight.sum())
        self.texel_pdf = weight * (w * h / self.total) if self.total > 0 else np.zeros_like(weight)
        self._flat_cdf = np.cumsum(weight.ravel()) / self.total if self.total > 0 else None
        self._native = None

    @property
    def dark(self) -> bool:
        return not self.total > 0

    @property
    def seen_by_camera(self) -> bool:
        return True

    @property
    def seen_by_bsdf(self) -> bool:
        return True

    @property
    def native(self):
        """The native environment light (dacrt.lamps.EnvironmentMap), built once."""
        if self._native is None:
            import dacrt
            self._native = dacrt.lamps.environment_map(self.rgb, self.to_map, self.interpolation)
        return self._native

    def _uv(self, D):
        m = self.to_map @ np.asarray(D, np.float64)
        m /= np.linalg.norm(m, axis=0)
        u = 0.5 - np.arctan2(m[1], m[0]) / (2.0 * np.pi)
        v = 1.0 - np.arccos(np.clip(m[2], -1.0, 1.0)) / np.pi
        return u, v, np.hypot(m[0], m[1])

    def _pdf(self, u, v, sin_theta):
        h, w = self.texel_pdf.shape
        i = np.minimum((v * h).astype(np.int64), h - 1)
        j = np.minimum((u * w).astype(np.int64), w - 1)
        with np.errstate(divide='ignore', invalid='ignore'):
            return np.where(sin_theta > 0, self.texel_pdf[i, j] / (_TWO_PI2 * sin_theta), 0.0)

    def radiance(self, u, v):
        return texture_lookup(self.rgb, u.astype(F32), v.astype(F32), self.interpolation, 'REPEAT')

    def eval_miss(self, D):
        """(indices, radiance (3, k), solid-angle pdf (k,)) of directions D (3, n) (every one)."""
        u, v, s = self._uv(D)
        n = np.asarray(D).shape[1]
        return np.arange(n), self.radiance(u, v), self._pdf(u, v, s).astype(F32)

    def sample(self, P, u1, u2) -> LightSample:
        """Directions toward the map from points P (3, n) (the same for every point): u1 picks
        the texel (one cdf over all texels, not the native row-then-column search) and its
        place in the texel's share places v, u2 places u."""
        n = np.asarray(P).shape[1]
        if self.dark:
            return LightSample(np.tile([[0.0], [0.0], [1.0]], n).astype(F32), np.full(n, np.inf, F32),
                               np.zeros((3, n), F32), np.zeros(n, F32))
        h, w = self.texel_pdf.shape
        a = np.asarray(u1, np.float64)
        k = np.minimum(np.searchsorted(self._flat_cdf, a, side='right'), h * w - 1)
        i, j = np.divmod(k, w)
        # u1's place inside its texel's share of the cdf places v, u2 places u
        lo = np.where(k > 0, self._flat_cdf[np.maximum(k - 1, 0)], 0.0)
        fv = np.clip((a - lo) / (self._flat_cdf[k] - lo), 0.0, np.nextafter(1.0, 0.0))
        u = (j + np.asarray(u2, np.float64)) / w
        v = (i + fv) / h
        theta = np.pi * (1.0 - v)
        phi = np.pi * (1.0 - 2.0 * u)
        s = np.sin(theta)
        m = np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)])
        wi = self.to_map.T @ m
        with np.errstate(divide='ignore', invalid='ignore'):
            pdf = np.where(s > 0, self.texel_pdf[i, j] / (_TWO_PI2 * s), 0.0)
        with np.errstate(divide='ignore', invalid='ignore'):
            value = np.where(pdf > 0, self.radiance(u, v) / pdf, 0.0)
        return LightSample(wi.astype(F32), np.full(n, np.inf, F32), value.astype(F32), pdf.astype(F32))
