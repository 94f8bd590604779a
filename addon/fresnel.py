"""View-dependent factors (the Fresnel and Layer Weight nodes): per shading point from the
incoming direction and the normal, as Cycles' svm_node_fresnel and svm_node_layer_weight
(`fresnel_node`, `layer_weight`: what the integrator evaluates where a chain compiles), and
each output's average over the directions a surface is seen from (where it does not).

Cycles evaluates these per shading point from the angle between the view and the normal
(svm/fresnel.h, fresnel_dielectric_cos), typically to blend a clear coat over a paint with
a Mix Shader. A diffuse material has one albedo per point, so the export takes the average of
the factor over view directions weighted by cos (projected solid angle), 2 int_0^1 f(mu) mu dmu:
the share of a surface's projected area seen at each angle, so an orthographic view of a
sphere has exactly that mean (tests/parity/test_fresnel.py). Front faces only: a mesh is
mostly seen from outside. Pure numpy, no Blender.
"""

from __future__ import annotations

import numpy as np

# Gauss-Legendre nodes on [0, 1] for s, with mu = mu_c + (1 - mu_c) s^2 (see _fresnel_average)
_S, _WS = np.polynomial.legendre.leggauss(128)
_S, _WS = 0.5 * (_S + 1.0), 0.5 * _WS


def fresnel_dielectric_cos(cosi, eta):
    """Cycles' fresnel_dielectric_cos: unpolarised reflectance of a dielectric of relative
    index eta at incidence cosine cosi (1 under total internal reflection)."""
    c = np.abs(cosi)
    g2 = eta * eta - 1.0 + c * c
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide='ignore', invalid='ignore'):
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        f = 0.5 * a * a * (1.0 + b * b)
    return np.where(g2 > 0.0, f, 1.0)


def _fresnel_average(eta):
    """2 int_0^1 F(mu, eta) mu dmu for each eta (an array). Below mu_c = sqrt(1 - eta^2)
    (eta < 1) F is 1; above it F has a square-root edge, which mu = mu_c + (1 - mu_c) s^2
    makes smooth for the quadrature."""
    eta = np.asarray(eta, np.float64)[..., None]
    mu_c = np.sqrt(np.clip(1.0 - eta * eta, 0.0, 1.0))
    mu = mu_c + (1.0 - mu_c) * _S * _S
    dmu = 2.0 * (1.0 - mu_c) * _S
    tail = 2.0 * np.sum(_WS * fresnel_dielectric_cos(mu, eta) * mu * dmu, axis=-1)
    return mu_c[..., 0] ** 2 + tail


# Distinct input values computed one by one; beyond that (an input fed by a float image) the
# average is interpolated from this many points over the inputs' range (a quadrature per texel
# of a 4K image would take gigabytes).
_MAX_DISTINCT = 4096


def _per_value(fn, x):
    """fn over the values of x (an input may be an image, one value per texel)."""
    x = np.asarray(x, np.float64)
    values, inverse = np.unique(x, return_inverse=True)
    if len(values) <= _MAX_DISTINCT:
        return fn(values)[inverse].reshape(x.shape)
    grid = np.linspace(values[0], values[-1], _MAX_DISTINCT)
    return np.interp(x, grid, fn(grid))


def fresnel_node(cosi, ior, backfacing):
    """The Fresnel node's Fac (n,) float32 at points whose incoming direction and normal have
    dot product cosi (n,), IOR ior, met from behind where backfacing (n,) (Cycles inverts the
    IOR there: the ray leaves the medium)."""
    eta = np.maximum(np.asarray(ior, np.float32), np.float32(1e-5))
    eta = np.where(backfacing, np.float32(1.0) / eta, eta)
    return fresnel_dielectric_cos(np.asarray(cosi, np.float32), eta).astype(np.float32)


def layer_weight(cosi, blend, output, backfacing):
    """The Layer Weight node's 'Fresnel' or 'Facing' output (n,) float32 at points whose
    incoming direction and normal have dot product cosi (n,): Fresnel of eta = 1 / max(1 -
    blend, 1e-5) (its inverse where backfacing), Facing 1 - |cosi|^p (p as layer_weight_average;
    blend 0.5 exactly: p = 1, as Cycles skips the power)."""
    cosi, blend = np.asarray(cosi, np.float32), np.asarray(blend, np.float32)
    if output == 'Fresnel':
        eta = np.maximum(np.float32(1.0) - blend, np.float32(1e-5))
        eta = np.where(backfacing, eta, np.float32(1.0) / eta)
        return fresnel_dielectric_cos(cosi, eta).astype(np.float32)
    b = np.clip(blend, np.float32(0.0), np.float32(1.0 - 1e-5))
    p = np.where(blend == np.float32(0.5), np.float32(1.0),
                 np.where(b < 0.5, np.float32(2.0) * b, np.float32(0.5) / (np.float32(1.0) - b)))
    return (np.float32(1.0) - np.power(np.abs(cosi), p)).astype(np.float32)


def fresnel_node_average(ior):
    """The Fresnel node's output averaged over view directions (front faces: eta = IOR)."""
    return _per_value(lambda v: _fresnel_average(np.maximum(v, 1e-5)), ior)


def layer_weight_average(blend, output):
    """The Layer Weight node's 'Fresnel' or 'Facing' output averaged over view directions.
    Fresnel: eta = 1 / max(1 - blend, 1e-5); Facing: 1 - mu^p with p = 2 blend below 0.5 and
    0.5 / (1 - blend) above (blend clamped to [0, 1 - 1e-5]), whose average is p / (p + 2)."""
    if output == 'Fresnel':
        return _per_value(lambda v: _fresnel_average(1.0 / np.maximum(1.0 - v, 1e-5)), blend)
    b = np.clip(np.asarray(blend, np.float64), 0.0, 1.0 - 1e-5)
    p = np.where(b < 0.5, 2.0 * b, 0.5 / (1.0 - b))
    return p / (p + 2.0)
