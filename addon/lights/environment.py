"""The world's Environment Texture as a light: an equirectangular image of radiance around the
scene, seen by rays that miss everything and sampled in proportion to its brightness.

This module is the readable definition the native kernels (dacrt.lamps.EnvironmentMap,
native/cpp/environment.h) are tested against; the integrator renders with those.
- Mapping as Cycles' direction_to_equirectangular (checked against a Cycles panoramic render):
  a direction m in the map's frame has u = 0.5 - atan2(m_y, m_x) / 2 pi, v = 1 - acos(m_z) / pi;
  the image's row 0 is the bottom (the -Z pole). World directions reach the map frame through
  `to_map` (the Mapping node's rotation; orthogonal).
- Lookup 'Linear' (bilinear, texel centres at (j + 0.5) / w) or 'Closest', REPEAT in u and v as
  Cycles' environment lookup; a channel blending in a texel's NaN or infinite value reads 0
  (Cycles' blend is not finite there, and its film drops it). A map given `encoded` (an sRGB
  image, which Cycles keeps in its
  encoding) blends those texels and decodes the blend, then times the strength; its importance
  comes from its decoded texels (the pixels).
- Importance, in proportion to the looked-up radiance's RGB mean (luminance) x sin(theta):
  'Closest' picks a texel by its luminance x the mean sin(theta) over its rows, then a point
  uniform in it; 'Linear' picks a cell between texel centres by its corners' mean luminance x
  mean sin(theta), then samples the corners' bilinear blend within it exactly (pbrt-v4's
  bilinear sampling), so radiance / pdf is constant in a cell up to sin(theta) and colour.
  The solid-angle pdf is p(u, v) / (2 pi^2 sin(theta)). Per-texel constant cells under a
  bilinear image left a one-texel sun's light, spread into its neighbours, to BSDF rays.
Unlike the uniform world (background.py), a map that varies is light-sampled, as Cycles does for
a world shader that varies over directions: a small bright region (a sun in an HDRI) is what
BSDF sampling finds badly.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..texture import EncodedTexels, srgb_to_linear, texture_lookup
from . import envkeep
from .base import F32, LightSample

_TWO_PI2 = 2.0 * np.pi * np.pi


class EnvironmentLight:
    """An environment map (scenedata.Environment) as a light at infinity: seen by camera rays
    (unless the film is transparent) and BSDF rays that miss everything, light-sampled, its
    samples shadowed. A group of its own in LightSet, not a Lamp: its table is no lamp record."""

    def __init__(self, env):
        self._env = env
        self.to_map = np.asarray(env.to_map, np.float64)
        self.interpolation = env.interpolation
        # (an 8-bit image's bytes stay bytes, k / 255: texture.EncodedTexels' scale)
        enc = None if env.encoded is None else np.asarray(env.encoded)
        self.encoded = None if enc is None else np.ascontiguousarray(enc, np.uint8 if enc.dtype == np.uint8 else F32)
        self._native = None

    def _radiance_image(self):
        """(h, w, 3) the texels' radiance (an encoded map's decoded as the native map decodes them)."""
        px = np.asarray(self._env.pixels, F32)[..., :3] if self.encoded is None else \
            srgb_to_linear(self._encoded_texels().texels[..., :3] * self._encoded_texels().scale)
        return np.ascontiguousarray(px * np.asarray(self._env.strength, F32))

    def _encoded_texels(self):
        """The encoded map as texture.EncodedTexels (bytes: scale 1 / 255)."""
        if self.encoded.dtype == np.uint8:
            return EncodedTexels(self.encoded, srgb=True, scale=1.0 / 255.0)
        return EncodedTexels(self.encoded, srgb=True)

    @property
    def native(self):
        """The native environment light (dacrt.lamps.EnvironmentMap) the renderer uses, built
        once; the numpy tables below are built only when the definition itself is asked."""
        if self._native is None:
            if self.encoded is None:
                # the texels as the export holds them (an image's RGBA), the strength folded in
                # natively: the same bits as _radiance_image's product, without its copies
                self._native = envkeep.native_map(self._env, self.to_map, self.interpolation,
                                                  np.asarray(self._env.strength, F32))
            else:
                self._native = envkeep.encoded_map(self.encoded, self.to_map, self.interpolation,
                                                   np.asarray(self._env.strength, F32))
        return self._native

    @property
    def dark(self) -> bool:
        return not self.native.total > 0

    def native_sample(self, u1, u2):
        """The renderer's (native) samples for uniforms u1, u2: (wi (3, n), radiance / pdf
        (3, n), solid-angle pdf (n,)), the same for every point."""
        return self.native.sample(np.asarray(u1, F32), np.asarray(u2, F32))

    # --- the readable definition (tests compare the native kernels with it) -------------------

    @cached_property
    def rgb(self) -> np.ndarray:
        return self._radiance_image()

    @cached_property
    def lum(self) -> np.ndarray:
        """(h, w) float64 RGB mean per texel, a channel not finite read as 0."""
        rgb = self.rgb.astype(np.float64)
        return np.where(np.isfinite(rgb), rgb, 0.0).mean(axis=2)

    @cached_property
    def cell_weight(self) -> np.ndarray:
        """(h, w) float64 selection weight per cell: 'Closest' texel (i, j), 'Linear' the cell
        between texel centres with corners (i, j) .. (i+1, j+1) (REPEAT); its mean luminance
        times the mean of sin(theta) over its rows (module doc)."""
        h, w = self.lum.shape
        edges = np.arange(h + 1) / h if self.interpolation == 'Closest' else (np.arange(h + 1) + 0.5) / h
        F = lambda v: np.cos(np.pi * (1.0 - np.clip(v, 0.0, 1.0))) / np.pi    # integral of sin(theta) dv
        # rows past v = 1 (the last 'Linear' cell) wrap to the bottom
        sin_mean = (F(edges[1:]) - F(edges[:-1]) + F(np.maximum(edges[1:] - 1.0, 0.0)) - F(0.0)) * h
        return self.corner_mean * sin_mean[:, None]

    @cached_property
    def corner_mean(self) -> np.ndarray:
        L = self.lum
        if self.interpolation == 'Closest':
            return L
        return (L + np.roll(L, -1, 1) + np.roll(L, -1, 0) + np.roll(np.roll(L, -1, 0), -1, 1)) / 4.0

    @cached_property
    def cell_pdf(self) -> np.ndarray:
        """(h, w) the pdf over (u, v) of each cell: P(cell) w h ('Linear': its mean over the cell)."""
        total = self.cell_weight.sum()
        return self.cell_weight * (self.cell_weight.size / total) if total > 0 else np.zeros_like(self.cell_weight)

    @cached_property
    def _flat_cdf(self) -> np.ndarray:
        cdf = np.cumsum(self.cell_weight.ravel())
        return cdf / cdf[-1] if cdf[-1] > 0 else cdf

    def uv_of(self, D):
        """(u, v, sin theta) of unit world directions D (3, n) in the map."""
        m = self.to_map @ np.asarray(D, np.float64)
        m /= np.linalg.norm(m, axis=0)
        u = 0.5 - np.arctan2(m[1] + 0.0, m[0] + 0.0) / (2.0 * np.pi)    # -0 as +0, as the native eval
        v = 1.0 - np.arccos(np.clip(m[2], -1.0, 1.0)) / np.pi
        return u, v, np.hypot(m[0], m[1])

    def uv_pdf(self, u, v):
        """The pdf over (u, v): P(cell) w h, times for 'Linear' the corners' bilinear
        luminance over its mean."""
        h, w = self.lum.shape
        scale = self.cell_pdf
        if self.interpolation == 'Closest':
            i = np.minimum((v * h).astype(np.int64), h - 1)
            j = np.minimum((u * w).astype(np.int64), w - 1)
            return scale[i, j]
        x, y = u * w - 0.5, v * h - 0.5
        x0, y0 = np.floor(x), np.floor(y)
        fx, fy = x - x0, y - y0
        j, i = np.mod(x0.astype(np.int64), w), np.mod(y0.astype(np.int64), h)
        j1, i1 = (j + 1) % w, (i + 1) % h
        L = self.lum
        bil = (L[i, j] * (1 - fx) + L[i, j1] * fx) * (1 - fy) + (L[i1, j] * (1 - fx) + L[i1, j1] * fx) * fy
        with np.errstate(divide='ignore', invalid='ignore'):
            return np.where(self.corner_mean[i, j] > 0, scale[i, j] / self.corner_mean[i, j] * bil, 0.0)

    def _pdf(self, u, v, sin_theta):
        with np.errstate(divide='ignore', invalid='ignore'):
            return np.where(sin_theta > 0, self.uv_pdf(u, v) / (_TWO_PI2 * sin_theta), 0.0)

    def radiance(self, u, v):
        """(3, n) the looked-up radiance; a channel that blends in a texel's NaN or infinite
        value reads 0 (Cycles' blend is not finite there, and its film drops it)."""
        if self.encoded is not None:
            rgb = texture_lookup(self._encoded_texels(), u.astype(F32), v.astype(F32),
                                 self.interpolation, 'REPEAT')
            return rgb * np.asarray(self._env.strength, F32)[:, None]
        with np.errstate(invalid='ignore'):
            rgb = texture_lookup(self.rgb, u.astype(F32), v.astype(F32), self.interpolation, 'REPEAT')
        return np.where(np.isfinite(rgb), rgb, F32(0.0))

    def eval_miss(self, D):
        """(indices, radiance (3, k), solid-angle pdf (k,)) of directions D (3, n) (every one)."""
        u, v, s = self.uv_of(D)
        n = np.asarray(D).shape[1]
        return np.arange(n), self.radiance(u, v), self._pdf(u, v, s).astype(F32)

    @staticmethod
    def _sample_linear(u, a, b):
        """x in [0, 1) with density proportional to (1 - x) a + x b, by inverting its cdf."""
        with np.errstate(divide='ignore', invalid='ignore'):
            x = np.where(a == b, u, (np.sqrt((1 - u) * a * a + u * b * b) - a) / (b - a))
        return np.clip(np.nan_to_num(x), 0.0, np.nextafter(1.0, 0.0))

    def sample(self, P, u1, u2) -> LightSample:
        """Directions toward the map from points P (3, n) (the same for every point): u1 picks
        the cell (one cdf over all cells, not the native row-then-column search) and its
        place in the cell's share of the cdf places v, u2 places u; 'Linear' then warps both
        to the cell's bilinear luminance."""
        n = np.asarray(P).shape[1]
        if not self.cell_weight.any():
            return LightSample(np.tile([[0.0], [0.0], [1.0]], n).astype(F32), np.full(n, np.inf, F32),
                               np.zeros((3, n), F32), np.zeros(n, F32))
        h, w = self.lum.shape
        a = np.asarray(u1, np.float64)
        k = np.minimum(np.searchsorted(self._flat_cdf, a, side='right'), h * w - 1)
        i, j = np.divmod(k, w)
        lo = np.where(k > 0, self._flat_cdf[np.maximum(k - 1, 0)], 0.0)
        fv = np.clip((a - lo) / (self._flat_cdf[k] - lo), 0.0, np.nextafter(1.0, 0.0))
        fu = np.asarray(u2, np.float64)
        if self.interpolation == 'Closest':
            u, v = (j + fu) / w, (i + fv) / h
        else:
            L = self.lum
            j1, i1 = (j + 1) % w, (i + 1) % h
            c00, c01, c10, c11 = L[i, j], L[i, j1], L[i1, j], L[i1, j1]
            y = self._sample_linear(fv, c00 + c01, c10 + c11)
            x = self._sample_linear(fu, c00 + (c10 - c00) * y, c01 + (c11 - c01) * y)
            u, v = np.mod((j + 0.5 + x) / w, 1.0), np.mod((i + 0.5 + y) / h, 1.0)
        theta = np.pi * (1.0 - v)
        phi = np.pi * (1.0 - 2.0 * u)
        s = np.sin(theta)
        m = np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)])
        wi = self.to_map.T @ m
        pdf = self._pdf(u, v, s)
        with np.errstate(divide='ignore', invalid='ignore'):
            value = np.where(pdf > 0, self.radiance(u, v) / pdf, 0.0)
        return LightSample(wi.astype(F32), np.full(n, np.inf, F32), value.astype(F32), pdf.astype(F32))
