"""A rough diffuse (Cycles' improved Oren-Nayar with OpenPBR's energy-preserving multiple
scattering) as the view-dependent BSDF Cycles renders (addon/roughdiffuse.py, native
orennayar.h), not its albedo averaged over view directions: the factor the integrator applies
(over the averaged albedo the throughput holds) against a float64 implementation of Cycles'
bsdf_oren_nayar.h; a plane under a sun rendered at tilted views against it; and energy: under
a uniform white world a sphere (every view cosine, cos-weighted, as an orthographic camera
sees them) still gives the averaged albedo."""
import dacrt
import numpy as np
import pytest

from addon import roughdiffuse
from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, icosphere, light, material, quad, render, rotation_x


def cycles_eon(rho, sigma, n, wi, wo):
    """Cycles 5.0 bsdf_oren_nayar.h, float64: eval (f x cos) / (rho cos / pi), per channel
    (3, k) of colours rho (3, k) at directions (3, k)."""
    def G(c):
        s = np.sqrt(np.maximum(1 - c * c, 0))
        th = np.arccos(np.clip(c, -1, 1))
        with np.errstate(divide='ignore', invalid='ignore'):
            g = s * (th - 2 / 3 - s * c) + 2 / 3 * (s / c) * (1 - s ** 3)
        return np.where(c < 1e-6, (np.pi / 2 - 2 / 3) - c, g)
    sigma = np.clip(sigma, 0, 1)
    a = 1 / (np.pi + sigma * (np.pi / 2 - 2 / 3))
    b = sigma * a
    r = np.clip(rho, 0, 1)
    eavg = a * np.pi + (2 * np.pi - 5.6) / 3 * b
    ems = r * r * (eavg / (1 - eavg)) / (1 - r * (1 - eavg)) / np.pi
    nl = np.maximum((n * wi).sum(0), 0)
    nv = np.maximum((n * wo).sum(0), 0)
    t = (wi * wo).sum(0) - nl * nv
    t = np.where(t > 0, t / (np.maximum(nl, nv) + 1e-300), t)
    ev, el = a * np.pi + b * G(nv), a * np.pi + b * G(nl)
    intensity = a + b * t + ems * (1 - ev) * (1 - el)
    return intensity * np.pi


def factor(sigma, rho, wo, n, wi):
    """(3, k) float64: the factor the integrator applies (dacrt.shading.rough_rows and
    rough_scale, as a bounce takes it; next_event's light samples share rough_diffuse_scale)
    at k points of roughness sigma (k,), colour rho (3, k), view wo, normal n, light wi."""
    k = len(sigma)
    P = np.stack([roughdiffuse.params(s) for s in sigma], 1)
    f32 = lambda x: np.ascontiguousarray(x, np.float32)          # noqa: E731
    rows = dacrt.shading.rough_rows(P, np.arange(k, dtype=np.int32), f32(rho), f32(-wo), f32(n))
    thr = np.ones((3, k), np.float32)
    dacrt.shading.rough_scale(rows, f32(wi), f32(n), thr)
    return thr.astype(np.float64)


def _unit(x):
    return x / np.linalg.norm(x, axis=0)


def _hemisphere(rng, k, n):
    d = _unit(rng.normal(size=(3, k)))
    return np.where((d * n).sum(0) < 0, -d, d)


def test_factor_against_cycles_formula():
    """The factor x the averaged albedo's D (albedo / rho) is Cycles' f / f_Lambert, for random
    normals, view and light directions (grazing included), roughness and colours."""
    rng = np.random.default_rng(3)
    k = 4000
    n = _unit(rng.normal(size=(3, k)))
    wo, wi = _hemisphere(rng, k, n), _hemisphere(rng, k, n)
    wi[:, :50] = _unit(wi[:, :50] - 0.999 * n[:, :50] * (wi[:, :50] * n[:, :50]).sum(0))   # grazing light
    sigma = rng.choice([0.05, 0.5, 1.0], size=k)
    rho = rng.uniform(0, 1, size=(3, k))
    rho[:, :20] = 0.0
    got = factor(sigma, rho, wo, n, wi)
    d = np.stack([roughdiffuse.albedo(rho[:, j], sigma[j]) / np.where(rho[:, j] > 0, rho[:, j], 1)
                  for j in range(k)], 1)
    d[:, :20] = np.array([roughdiffuse._terms(s)[0] for s in sigma[:20]])
    want = cycles_eon(rho, sigma, n, wi, wo)
    assert np.abs(got * d - want).max() < 2e-4 * want.max(), np.abs(got * d - want).max()
    # and Lambert's points take none
    assert (factor(np.zeros(k), rho, wo, n, wi) == 1.0).all()


@pytest.mark.parametrize('sigma', [0.3, 1.0])
def test_factor_keeps_the_averaged_albedo(sigma):
    """Integrated over cosine-sampled light directions and cos-weighted view directions the
    factor is 1: the BSDF's albedo is what the material's averaged albedo holds (quadrature)."""
    x, w = np.polynomial.legendre.leggauss(48)
    mu, wm = 0.5 * (x + 1), 0.5 * w
    phi = np.linspace(0, 2 * np.pi, 96, endpoint=False)
    for rho in (0.2, 0.9):
        total = 0.0
        for mo, wmo in zip(mu, wm):
            wo = np.array([np.sqrt(1 - mo * mo), 0.0, mo])
            M, P = np.meshgrid(mu, phi, indexing='ij')
            wi = np.stack([np.sqrt(1 - M * M) * np.cos(P), np.sqrt(1 - M * M) * np.sin(P), M]).reshape(3, -1)
            k = wi.shape[1]
            n = np.tile([[0.0], [0.0], [1.0]], (1, k))
            f = factor(np.full(k, sigma), np.full((3, k), rho), np.tile(wo[:, None], (1, k)), n, wi)[0].reshape(M.shape)
            # cosine-weighted over wi: pdf cos / pi, so the mean of f over (mu^2, phi)
            inner = (f * (2 * mu * wm)[:, None]).sum() / len(phi)
            total += 2 * mo * wmo * inner
        assert total == pytest.approx(1.0, abs=2e-3), (rho, total)


def _rough(rho, sigma, **kw):
    return material('rough', roughdiffuse.albedo(rho, sigma).astype(np.float32), rough_sigma=sigma,
                    pass_color=np.asarray(rho, np.float32), **kw)


@pytest.mark.parametrize('view, sun, sigma', [(45, (45, 0), 1.0), (45, (45, 180), 1.0), (25, (30, 180), 0.5),
                                             (60, (20, 0), 0.5)])
def test_plane_under_a_sun(view, sun, sigma):
    """A plane under a sharp sun seen by an orthographic camera `view` degrees up: every pixel
    is E rho / pi F cos (direct light only). sun = (elevation, azimuth from the camera's
    side)."""
    rho = np.array([0.8, 0.5, 0.3])
    v, t = quad((0, 0, 0), 1000.0, 1000.0)
    e = np.radians(view)
    cam = rotation_x(np.pi / 2 - e)
    cam[:3, 3] = (0, -5 * np.cos(e), 5 * np.sin(e))
    camera = sd.Camera('ORTHO', cam, (-0.05, 0.05, -0.05, 0.05), 0.0, 1e-3, 100.0, 6, 6)
    s, az = np.radians(sun[0]), np.radians(sun[1])
    to_sun = np.array([np.sin(az) * np.cos(s), -np.cos(az) * np.cos(s), np.sin(s)])
    # a sun shines along its -Z: the rotation taking -Z to -to_sun
    zaxis = to_sun
    xaxis = np.cross([0.0, 0.0, 1.0], zaxis)
    xaxis /= np.linalg.norm(xaxis)
    m = np.eye(4)
    m[:3, :3] = np.stack([xaxis, np.cross(zaxis, xaxis), zaxis], 1)
    scene = sd.SceneData(camera, geometry([(v, t, 1, ALL_VIS)]), [material('default'), _rough(rho, sigma)],
                         [light('SUN', 2.0, m)], np.zeros(3, np.float32),
                         sd.Settings(samples=4, max_bounces=0, filter_type='BOX'))
    img = render(scene).film.combined()[..., :3].reshape(-1, 3).mean(0)
    n = np.array([[0.0], [0.0], [1.0]])
    wo = np.array([[0.0], [-np.cos(e)], [np.sin(e)]])
    want = 2.0 * rho / np.pi * cycles_eon(rho[:, None], sigma, n, to_sun[:, None], wo)[:, 0] * np.sin(s)
    assert img == pytest.approx(want, rel=3e-3)


def test_white_world_gives_the_averaged_albedo():
    """Energy: a rough sphere under a uniform white world, seen by an orthographic camera (its
    pixels hold every view cosine, cos-weighted), direct light only: its mean over the disk is
    the averaged albedo (before: the same, the albedo alone; the factor must not change it)."""
    rho, sigma = np.array([0.9, 0.5, 0.2]), 1.0
    vs, ts = icosphere(radius=1.0, subdiv=4)
    m = np.eye(4)
    m[:3, 3] = (0, 0, 5)
    camera = sd.Camera('ORTHO', m, (-1.1, 1.1, -1.1, 1.1), 0.0, 1e-3, 100.0, 40, 40)
    scene = sd.SceneData(camera, geometry([(vs, ts, 1, ALL_VIS)]), [material('default'), _rough(rho, sigma)], [],
                         np.ones(3, np.float32),
                         sd.Settings(samples=64, max_bounces=0, filter_type='BOX', film_transparent=True))
    rgba = render(scene).film.combined().reshape(-1, 4).astype(np.float64)
    mean = rgba[:, :3].sum(0) / rgba[:, 3].sum()
    assert mean == pytest.approx(roughdiffuse.albedo(rho, sigma), rel=0.01)


@pytest.mark.parametrize('area_light', [True, False])
def test_fused_vertices_take_the_factor(monkeypatch, area_light):
    """A Cornell box whose walls are rough (two of them Lambertian, mixed scenes take the
    factor only where it is rough): the fused native pass (shade_bounce) gives the general
    steps' bits, and the factor changes the image (against the walls' averaged albedo)."""
    import addon.integrator as integrator_module
    from .scenes import cornell_box

    def box(rough):
        s = cornell_box(40, 30, 16, 4, area_light=area_light)
        for i in (1, 3):
            m = s.materials[i]
            rho = m.base_color.astype(np.float64)
            m.base_color = roughdiffuse.albedo(rho, 0.8).astype(np.float32)
            if rough:
                m.rough_sigma, m.pass_color = 0.8, rho.astype(np.float32)
        return s
    calls = []
    fused_pass = dacrt.shading.shade_bounce
    monkeypatch.setattr(dacrt.shading, 'shade_bounce', lambda *a, **k: calls.append(k.get('rough')) or
                        fused_pass(*a, **k))
    fused = render(box(True)).film.combined()
    assert calls and all(c is not None for c in calls)
    averaged = render(box(False)).film.combined()
    monkeypatch.setattr(integrator_module, 'FUSED_BOUNCE', False)
    general = render(box(True)).film.combined()
    assert np.array_equal(fused, general)
    assert not np.array_equal(fused, averaged)
