"""The sheen lobes' albedos (addon/sheen.py) against independent references: the velvet's
against a float64 Monte Carlo estimate of the integral of Cycles' Ashikhmin velvet BRDF over
uniformly sampled light directions (not the module's quadrature grid), and the microfiber fit's
known shape (a few percent at normal view, most at grazing, growing with roughness). Cycles
itself is the reference in tests/parity/test_sheen.py."""
import numpy as np
import pytest

from addon import sheen
from addon.specular import MU, VIEW


def _velvet_mc(sigma, mu, n=2_000_000, seed=3):
    """E(mu) = int 0.25 D G / mu dw over the hemisphere of light directions, uniform sampling."""
    rng = np.random.default_rng(seed)
    z, phi = rng.random(n), 2 * np.pi * rng.random(n)
    r = np.sqrt(1 - z * z)
    light = np.stack([r * np.cos(phi), r * np.sin(phi), z])
    view = np.array([np.sqrt(1 - mu * mu), 0.0, mu])[:, None]
    h = light + view
    h /= np.linalg.norm(h, axis=0)
    nh, hv = h[2], np.abs((h * view).sum(0))
    ok = (np.abs(nh) < 1 - 1e-5) & (hv > 1e-5)
    ratio = np.maximum(nh / hv, 1e-5)
    g = np.minimum(1, np.minimum(2 * ratio * mu, 2 * ratio * z))
    s2 = np.where(ok, 1 - nh * nh, 1.0)
    d = np.exp(-(nh * nh / s2) / sigma ** 2) / (np.pi * sigma ** 2 * s2 * s2)
    return np.where(ok, 0.25 * d * g / mu, 0.0).mean() * 2 * np.pi


@pytest.mark.parametrize('sigma', [0.1, 0.4, 1.0])
@pytest.mark.parametrize('k', [3, 16, 28])
def test_velvet_albedo_matches_monte_carlo(sigma, k):
    got = sheen.velvet_albedo_mu(sigma)[k]
    ref = _velvet_mc(sigma, MU[k])
    assert got == pytest.approx(ref, rel=0.01, abs=1e-7), (sigma, MU[k], got, ref)


def test_velvet_roughness_is_clamped_as_cycles():
    # Cycles: sigma = max(saturate(roughness), 0.01)
    np.testing.assert_array_equal(sheen.velvet_albedo_mu(0.0), sheen.velvet_albedo_mu(0.01))
    np.testing.assert_array_equal(sheen.velvet_albedo_mu(3.0), sheen.velvet_albedo_mu(1.0))


def test_microfiber_albedo_shape():
    for r in (0.1, 0.5, 1.0):
        e = sheen.microfiber_albedo_mu(r)
        assert np.all((e >= 0) & (e <= 1))
        assert e[0] > e[-1]                  # brighter at grazing than at normal view
    averages = [sheen.albedo('MICROFIBER', r) for r in (0.05, 0.2, 0.5, 1.0)]
    assert np.all(np.diff(averages) > 0), averages
    assert 0.05 < averages[2] < 0.15 and 0.35 < averages[3] < 0.55, averages


def test_average_is_cos_weighted():
    e = sheen.velvet_albedo_mu(0.4)
    assert sheen.albedo('ASHIKHMIN', 0.4) == pytest.approx(float(e @ VIEW))
    assert VIEW.sum() == pytest.approx(1.0)
