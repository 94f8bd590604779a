"""Cycles' sheen (the Sheen BSDF node and the Principled BSDF's sheen layer) as a diffuse
renderer keeps it: its albedo per view cosine (specular.MU) and averaged over view directions.

A sheen lobe reflects little: a few percent of its colour at normal view, more towards grazing.
The Velvet of bmw27's floor (roughness 0.4, mixed with a Glossy) reflects 0.132 of its colour
averaged over view directions, so taken as a diffuse surface of its colour it was 7.6x too
bright. Cycles has two distributions:

- Microfiber (the default; closure/bsdf_sheen.h): Zeltner, Burley and Chiang's "Practical
  Multiple-Scattering Sheen Using Linearly Transformed Cosines" (2022). The lobe is a normalised
  LTC weighted by the model's directional albedo, which Cycles reads from a table of (view
  cosine, roughness clamped to 1e-3..1). Here the albedo is the paper's Gaussian fit of that
  table (as used by MaterialX and OpenPBR).
- Ashikhmin (closure/bsdf_ashikhmin_velvet.h): the velvet microfacet BRDF, D = exp(-cot^2 / s^2)
  / (pi s^2 sin^4) of the half vector (s = max(roughness, 0.01)), G = min(1, 2 cos_nh cos_n. /
  cos_h.), reflecting D G / (4 cos_view) per unit solid angle of light. It has no closed-form
  albedo, so it is integrated here over light directions (Gauss-Legendre in the light's cosine,
  a uniform azimuth grid).

In a Principled BSDF the sheen is the top layer: it adds weight x tint x E(mu) and dims what is
below (the coat, the specular layer, the base, and the emission) by 1 - max over channels of
that (svm/closure.h, closure_layering_weight). Pure numpy, no Blender.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .specular import MU, VIEW

DISTRIBUTIONS = ('MICROFIBER', 'ASHIKHMIN')


def microfiber_albedo_mu(roughness: float) -> np.ndarray:
    """Directional albedo of the microfiber sheen per view cosine MU (len(MU),)."""
    y = min(max(float(roughness), 1e-3), 1.0) if np.isfinite(roughness) else 0.5
    x = MU
    s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y))
    m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y)
    o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y))
    return np.clip(np.exp(-0.5 * ((x - m) / s) ** 2) / (s * np.sqrt(2.0 * np.pi)) + o, 0.0, 1.0)


# light cosines (Gauss-Legendre on 0..1) and azimuths relative to the view (0..pi, the lobe is
# mirror-symmetric about the view's plane): within 0.3% of a grid twice as fine at s = 0.05
_LIGHT_MU, _LIGHT_W = np.polynomial.legendre.leggauss(128)
_LIGHT_MU, _LIGHT_W = 0.5 * (_LIGHT_MU + 1.0), 0.5 * _LIGHT_W
_LIGHT_PHI = (np.arange(128) + 0.5) / 128 * np.pi


@lru_cache(maxsize=64)
def _velvet_albedo_mu(sigma: float) -> np.ndarray:
    inv_s2 = 1.0 / (sigma * sigma)
    vo = MU[:, None, None]                     # view (sin_o, 0, mu_o)
    li = _LIGHT_MU[None, :, None]               # light (sin_i cos phi, sin_i sin phi, mu_i)
    so, si = np.sqrt(1.0 - vo * vo), np.sqrt(1.0 - li * li)
    cp = np.cos(_LIGHT_PHI)[None, None, :]
    hx, hy, hz = so + si * cp, si * np.sin(_LIGHT_PHI)[None, None, :], vo + li
    hlen = np.sqrt(hx * hx + hy * hy + hz * hz)
    cos_nh = hz / hlen
    cos_hv = (so * hx + vo * hz) / hlen         # = cos of the light with h
    ok = (np.abs(cos_nh) < 1.0 - 1e-5) & (cos_hv > 1e-5)
    cos_hv = np.where(ok, cos_hv, 1.0)
    sin2 = np.where(ok, 1.0 - cos_nh * cos_nh, 1.0)
    ratio = np.maximum(cos_nh / cos_hv, 1e-5)
    g = np.minimum(1.0, np.minimum(2.0 * ratio * vo, 2.0 * ratio * li))
    d = np.exp(-(cos_nh * cos_nh / sin2) * inv_s2) * inv_s2 / np.pi / (sin2 * sin2)
    f = np.where(ok, 0.25 * d * g / vo, 0.0)
    # over light directions: d(omega) = d(mu_i) d(phi), the azimuth's two mirrored halves
    return 2.0 * (f * (_LIGHT_W[None, :, None] * (np.pi / len(_LIGHT_PHI)))).sum(axis=(1, 2))


def velvet_albedo_mu(roughness: float) -> np.ndarray:
    """Directional albedo of the Ashikhmin velvet per view cosine MU (len(MU),)."""
    r = min(max(float(roughness), 0.0), 1.0) if np.isfinite(roughness) else 0.5
    return _velvet_albedo_mu(max(r, 0.01))


def albedo_mu(distribution: str, roughness: float) -> np.ndarray:
    """The sheen's directional albedo per view cosine for Cycles' distribution name."""
    if distribution == 'ASHIKHMIN':
        return velvet_albedo_mu(roughness)
    return microfiber_albedo_mu(roughness)


def albedo(distribution: str, roughness: float) -> float:
    """albedo_mu averaged over view directions (weighted by cos)."""
    return float(albedo_mu(distribution, roughness) @ VIEW)
