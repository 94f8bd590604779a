"""Cycles' rough diffuse reflection (Diffuse BSDF Roughness, Principled Diffuse Roughness): its
albedo averaged over view directions, which the material's albedo holds, and the terms the
integrator's per-sample factor over it needs (params).

Cycles (closure/bsdf_oren_nayar.h) renders roughness sigma as Fujii's improved Oren-Nayar with
OpenPBR's energy-preserving multiple-scattering term: for a colour rho, at view cosine mu_o
and light cosine mu_i, rho nl (a + b t + Ems (1 - E(mu_o)) (1 - E(mu_i))), with
a = 1 / (pi + sigma (pi/2 - 2/3)), b = sigma a, E(mu) = a pi + b G(mu) (the single-scattering
albedo), Ems = rho^2 Eavg / (1 - Eavg) / (1 - rho (1 - Eavg)) / pi and Eavg Cycles' fit
a pi + (2 pi - 5.6) / 3 b of E's average. Integrated over light directions and then over view
directions (weighted by cos), the albedo is closed-form in rho given E's exact average Ebar:
rho Ebar + rho pi Ems (1 - Ebar)^2, nonlinear in rho (a colour of 0.8 keeps 0.965 of itself at
sigma 0.5, one of 0.3 only 0.914), so a textured colour goes through it texel by texel.

That albedo is what the material's albedo holds (so the Diffuse passes, emission found by BSDF
rays and everything that reads the albedo stay as they were); the integrator then renders the
real BSDF: Cycles samples it cosine-weighted, so pdfs and MIS weights are Lambert's and each
light sample and each bounce only takes the factor F / D per channel, F = f / (rho / pi) the
BSDF over Lambert's and D the averaged albedo over rho (params here, per material; the rest
native: dacrt.shading.rough_rows, rough_scale, next_event's and shade_bounce's rough,
orennayar.h). A material gets it where its whole albedo is one rough diffuse of one colour
(any Mix Shader weight, beside emission, transparency, holdout or translucency:
export.closure.Closure.rough; a Principled base under no layer); under the Principled's
layers (their dimming varies with the view too), mixed with another reflection or coloured by
an attribute it keeps the averaged albedo, said.
Pure numpy, no Blender.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np


# what the albedo averaged over view directions gives a rough diffuse where it is kept (mixed with
# another reflection, a colour attribute, a Principled base under layers; measured on a plane against
# Cycles 5.0: uniform white world 0.97-1.02x by view angle, exact on average; a zero-angle sun
# at roughness 1: 0.33-0.97x with the sun behind the viewer, 1.1-7.7x facing it, 20-80 degrees
# up; README, rough diffuse)
ROUGH_DIFFUSE_LIGHT = (" (under even light, a world, within 0.5% of Cycles on average and 3% at any view angle;"
                       " under a sun or a small lamp it lacks the view-dependent back-scatter: at roughness 1,"
                       " light and view 45 degrees up, 0.65x Cycles with the light behind the viewer and 1.8x"
                       " facing it; lower, view and light 20-30 degrees up, as far as 0.33x and 7.7x)")


def _g(c):
    """Cycles' bsdf_oren_nayar_G(cos theta)."""
    c = np.asarray(c, np.float64)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    th = np.arccos(np.clip(c, -1.0, 1.0))
    safe = np.maximum(c, 1e-6)
    g = s * (th - 2.0 / 3.0 - s * c) + 2.0 / 3.0 * (s / safe) * (1.0 - s * s * s)
    return np.where(c < 1e-6, (np.pi / 2 - 2.0 / 3.0) - c, g)


@lru_cache(maxsize=64)
def _terms(sigma: float) -> tuple:
    """(Ebar, Eavg, a, b): E's exact cos-weighted average (Gauss-Legendre over mu), Cycles'
    fit of it, and the model's a and b."""
    a = 1.0 / (np.pi + sigma * (np.pi / 2 - 2.0 / 3.0))
    b = sigma * a
    x, w = np.polynomial.legendre.leggauss(64)
    mu, wm = 0.5 * (x + 1.0), 0.5 * w
    ebar = float((2.0 * mu * wm) @ (a * np.pi + b * _g(mu)))
    eavg = a * np.pi + (2.0 * np.pi - 5.6) / 3.0 * b
    return ebar, eavg, a, b


def albedo(rho, sigma: float) -> np.ndarray:
    """Per channel (any shape), the rough diffuse albedo of colour rho averaged over view
    directions; rho itself at sigma 0 (Lambert)."""
    rho = np.asarray(rho, np.float64)
    sigma = min(max(float(sigma), 0.0), 1.0)
    if sigma <= 0.0:
        return rho
    ebar, eavg, _, _ = _terms(sigma)
    r = np.clip(rho, 0.0, 1.0)                     # Cycles saturates the colour in the ms term
    ms = r * r * eavg / (1.0 - eavg) / (1.0 - r * (1.0 - eavg))
    return rho * ebar + rho * ms * (1.0 - ebar) ** 2


class RoughDiffuse:
    """The colour -> albedo map of a rough diffuse of roughness sigma, as a step of the export
    (export.closure.Closure.mapped) and of the fair-material override: exact on a constant and per texel."""

    def __init__(self, sigma):
        self.sigma = min(max(float(sigma), 0.0), 1.0)
        self.key = ('rough diffuse', self.sigma)

    def exact(self, rgb):
        # rounded to float32 as a colour socket stores it: the fair-material override writes
        # this value into the Diffuse colour, and a Mix Shader's factor applied after it must
        # then give the export the same bits both ways
        return albedo(np.asarray(rgb, np.float64)[:3], self.sigma).astype(np.float32).astype(np.float64)

    def __call__(self, x):
        return albedo(x, self.sigma)

    def pass_map(self):
        """None: the Diffuse Color pass keeps the colour (Cycles writes the Oren-Nayar closure's
        weight there and in Denoising Albedo, not this albedo; export.closure.Closure.mapped)."""
        return None

    def line(self):
        """(dim, add): the least-squares line of the map over colours 0..1 (the fair override's
        stand-in for a textured colour)."""
        g = np.linspace(0.0, 1.0, 129)
        k, c = np.polyfit(g, albedo(g, self.sigma), 1)
        return np.full(3, k), np.full(3, c)


def params(sigma: float) -> np.ndarray:
    """(4,) float32 (a, b, Ebar, Eavg) of roughness sigma, what the native rough diffuse table
    takes per material (dacrt.shading.rough_rows); zeros at sigma 0 (Lambert: no factor)."""
    sigma = min(max(float(sigma), 0.0), 1.0) if np.isfinite(sigma) else 0.0
    if sigma <= 0.0:
        return np.zeros(4, np.float32)
    ebar, eavg, a, b = _terms(sigma)
    return np.array([a, b, ebar, eavg], np.float32)
