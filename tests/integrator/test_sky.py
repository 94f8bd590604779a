"""The Sky Texture's models (addon/sky.py) against straightforward per-ray transcriptions of
Blender's intern/sky (one ray, one step at a time, as the C++ loops run), and the environment
image made from them against the per-direction evaluation: the sky at texel centres, the sun
disc's light (its integral over the sphere) and Cycles' wrapping of the sun's angles."""
import math

import numpy as np
import pytest

from addon import sky as model

E15 = math.radians(15.0)


def _ms_ray(tr, x, y, sun_elevation, altitude=100.0, air=1.0, aerosol=1.0, ozone=1.0, float32=False):
    """XYZ of texel (x, y) of the multiple-scattering table, as get_inscattering marches it;
    float32: its positions and its sum of steps in float32 as Cycles (expf correctly rounded)."""
    u, v = (x + 0.5) / model.TABLE_W, (y + 0.5) / model.TABLE_H
    az, l = 2 * math.pi * u, 2 * v - 1
    el = math.copysign(l * l, l) * math.pi / 2
    d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    f32 = np.float32
    z = f32(model._MS_EARTH) + f32(min(max(altitude, 1.0), 99999.0)) / f32(1000.0)     # clamped as Cycles
    o = np.array([0.0, 0.0, float(z)])
    cz = math.cos(math.pi / 2 - sun_elevation)
    sun = np.array([-math.sqrt(1 - cz * cz), 0.0, cz])

    def hit(r):
        # in float32, as Cycles' ray_sphere_intersection (sky_math.h): near the ground
        # c = |o|^2 - r^2 keeps a few of its digits (12 for 12.74 km^2 at 1 m)
        l32 = f32(y + 0.5) / f32(model.TABLE_H) * f32(2.0) - f32(1.0)
        dz = f32(math.sin(float(f32(math.copysign(float(l32 * l32), float(l32))) * f32(math.pi / 2))))
        b, c = z * dz, z * z - f32(r) * f32(r)
        if (c > 0 and b > 0) or b * b - c < 0:
            return -1.0
        return float(-b + np.sqrt(b * b - c) if b * b - c >= b * b else -b - np.sqrt(b * b - c))
    ground = hit(model._MS_EARTH)
    t_d = hit(model._MS_ATMOS) if ground < 0 else ground
    mu = -d @ sun
    mol_phase = 3 / (16 * math.pi) * (1 + mu * mu)
    den = 1 + 0.64 + 1.6 * mu
    aer_phase = (1 - 0.64) / (4 * math.pi * den * math.sqrt(den))
    dt = t_d / 64
    L, T = np.zeros(4), np.ones(4)
    if float32:
        L, T = L.astype(f32), T.astype(f32)
        l32 = f32(y + 0.5) / f32(model.TABLE_H) * f32(2.0) - f32(1.0)
        el32 = f32(math.copysign(float(l32 * l32), float(l32))) * f32(math.pi / 2)
        d32 = np.array([f32(math.cos(float(el32))) * f32(math.cos(az)), f32(math.cos(float(el32))) * f32(math.sin(az)),
                        f32(math.sin(float(el32)))], f32)
    for i in range(64):
        p = o + d * (i + 0.5) * dt
        if float32:
            p = np.array([0.0, 0.0, z], f32) + d32 * ((f32(i) + f32(0.5)) * f32(dt))
            p = p.astype(np.float64)
            dist = float(np.sqrt(f32(f32(f32(p[0] * p[0]) + f32(p[1] * p[1])) + f32(p[2] * p[2]))))
        else:
            dist = np.linalg.norm(p)
        h = max(dist - model._MS_EARTH, 0.0)
        cs = (p / dist) @ sun
        ext, mol, aer = (c[0] for c in model._ms_coefficients(np.array([h]), air, aerosol, ozone))
        to_sun = tr(np.array([cs]), np.array([h / 100]))[0]
        if float32:
            q = f32(model._MS_EARTH) / f32(dist)
            omega = float(f32(2 * math.pi) * (f32(1) - np.sqrt(max(f32(1) - q * q, f32(0)))))
        else:
            omega = 2 * math.pi * (1 - math.sqrt(1 - (model._MS_EARTH / dist) ** 2))
        g2s = tr.to_zenith(np.zeros(1))[0] / tr.to_zenith(np.array([h / 100]))[0]
        ms = model._MS_FIT / (1 + 5 * math.exp(-17.92 * cs)) \
            + omega / (4 * math.pi) * 0.3 / math.pi * tr.at_ground(np.array([cs]))[0] * g2s * cs
        S = model._MS_SUN * (mol * (mol_phase * to_sun + ms) + aer * (aer_phase * to_sun + ms))
        if float32:
            S, ext = S.astype(f32), ext.astype(f32)
            step = np.exp((-f32(dt) * ext).astype(np.float64)).astype(f32)
            L += T * (S - S * step) / np.maximum(ext, f32(1e-7))
            T *= step
            continue
        step = np.exp(-dt * ext)
        L += T * (S - S * step) / np.maximum(ext, 1e-7)
        T *= step
    return L @ model._MS_XYZ


def test_multiple_scattering_table_is_the_per_ray_march():
    tr = model._TransmittanceTable(1.0, 1.0, 1.0)
    # one entry of the transmittance table, marched step by step
    cos, h = 0.3, 10 / 63
    r0 = model._MS_EARTH + h * 100
    sin = math.sqrt(1 - cos * cos)
    b, c = r0 * cos, r0 * r0 - model._MS_ATMOS ** 2
    t_d = -b + math.sqrt(b * b - c)
    depth = np.zeros(4)
    for i in range(64):
        t = (i + 0.5) * t_d / 64
        alt = max(math.hypot(sin * t, r0 + cos * t) - model._MS_EARTH, 0.0)
        depth += model._ms_coefficients(np.array([alt]), 1.0, 1.0, 1.0)[0][0] * t_d / 64
    x = round((cos * 0.5 + 0.5) * 255)
    cos = x / 255 * 2 - 1
    np.testing.assert_allclose(tr.lut[10, x], model._ms_transmittance(cos, h, 1, 1, 1), rtol=1e-12)
    table = model.multiple_scattering_table(E15, 100.0, 1.0, 1.0, 1.0)
    for x, y in ((0, 200), (100, 130), (255, 128), (37, 127), (200, 60), (10, 255)):
        ref = _ms_ray(tr, x, y, E15)
        np.testing.assert_allclose(table[y, x], ref, rtol=2e-4, atol=1e-6 * np.abs(ref).max())
        np.testing.assert_array_equal(table[y, x], table[y, model.TABLE_W - 1 - x])     # mirrored


@pytest.mark.parametrize('altitude', (0.0, 5.0))
def test_multiple_scattering_ground_rows_sum_their_steps_in_float32(altitude):
    """From a low Altitude the ground rows' view rays are metres long and Cycles' float32 sum
    of their steps moves each channel's light by up to ~10% (test_sky_ground_float32 in the
    parity tests): those rows are the float32 march's (a float64 sum was 0.93-1.07x it)."""
    dens = (1.0, 1.0, 1.0) if altitude == 0.0 else (2.0, 0.5, 1.0)
    tr = model._TransmittanceTable(*dens)
    table = model.multiple_scattering_table(E15, altitude, *dens)
    for x, y in ((0, 0), (100, 3), (255, 20), (37, 60), (200, 100)):
        ref = _ms_ray(tr, x, y, E15, altitude, *dens, float32=True)
        np.testing.assert_allclose(table[y, x], ref, rtol=3e-4)


def _ss_ray(x, y, sun_elevation, altitude=100.0, dens=(1.0, 1.0, 1.0)):
    """XYZ of texel (x, y) of the single-scattering table, as single_scattering loops it."""
    lat = math.pi / 2 * (y / 128 - 1) ** 2
    lon = 2 * math.pi / 512 * x - math.pi
    d = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    sun = np.array([math.cos(sun_elevation), 0.0, math.sin(sun_elevation)])
    o = np.array([0.0, 0.0, model._SS_EARTH + altitude])

    def exit_length(p, w):
        b, c = 2 * (w @ p), p @ p - model._SS_ATMOS ** 2
        return (-b + math.sqrt(b * b - 4 * c)) / 2

    def density(p):
        h = np.linalg.norm(p) - model._SS_EARTH
        return np.array([math.exp(-h / 8e3), math.exp(-h / 1.2e3), max(0.0, 1 - abs(h - 25e3) / 15e3)])
    seg = exit_length(o, d) / 32
    mu = d @ sun
    phase = np.array([3 / (16 * math.pi) * (1 + mu * mu),
                      3 * (1 - 0.5776) * (1 + mu * mu) / (8 * math.pi * 2.5776 * (1.5776 - 1.52 * mu) ** 1.5)])
    depth, spectrum = np.zeros(3), np.zeros(21)
    scale = np.array(dens)
    for i in range(32):
        p = o + (i + 0.5) * seg * d
        rho = scale * density(p)
        depth += seg * rho
        length = exit_length(p, sun)
        light = scale * sum(w * density(p + n * length * sun) for n, w in zip(model._SS_NODES, model._SS_WEIGHTS)) \
            * length
        total = depth + light
        for wl in range(21):
            att = math.exp(-(total @ [model._SS_RAYLEIGH[wl], 1.11 * model._SS_MIE, model._SS_OZONE[wl]]))
            spectrum[wl] += att * (phase[0] * rho[0] * model._SS_RAYLEIGH[wl] + phase[1] * rho[1] * model._SS_MIE) \
                * model._SS_IRRADIANCE[wl] * seg
    return spectrum @ model._SS_CMF


def test_single_scattering_table_is_the_per_ray_march():
    table = model.single_scattering_table(E15, 100.0, 1.0, 1.0, 1.0)
    # the lower half: the horizon row x (1 - 2.5 z)^3, z the sine of the row's mirrored
    # elevation, black from z 0.4 (it had been black, its ground faded per view direction)
    for y in (0, 40, 62, 63, 90, 127):
        z = math.sin(math.pi / 2 * (y / 128 - 1) ** 2)
        fade = (1 - 2.5 * z) ** 3 if z < 0.4 else 0.0
        np.testing.assert_allclose(table[y], table[128] * fade, rtol=5e-5)    # (float32)
    assert not table[:63].any() and table[63:128].all()
    for x, y in ((0, 200), (100, 130), (255, 129), (37, 255), (255, 160), (20, 128)):
        ref = _ss_ray(x, y, E15)
        np.testing.assert_allclose(table[y, x], ref, rtol=2e-5)
        # the other half mirrors the computed one (column 256 is 255's, not the sun's own azimuth)
        np.testing.assert_array_equal(table[y, x], table[y, model.TABLE_W - 1 - x])


@pytest.mark.parametrize('multiple', (True, False))
def test_equirect_is_the_sky_at_texel_centres(multiple):
    """Rows away from the horizon hold the sky at their texels' centres; those within
    the two rows that meet at the horizon their mean over the row's span
    (test_equirect_keeps_the_horizons_light)."""
    sky = model.Sky.from_node_values(multiple, E15, 0.7, sun_disc=False)
    img = model.equirect(sky, 256)
    h, w = img.shape[:2]
    u = ((np.arange(w) + 0.5) / w)[None, :]
    v = (np.arange(h) + 0.5) / h
    centre = np.abs((v - 0.5) * np.pi) >= np.pi / h
    dirs = model._equirect_dirs(u, v[centre][:, None])
    np.testing.assert_allclose(img[centre], model.radiance(sky, dirs), rtol=1e-5, atol=1e-6)
    for r in np.flatnonzero(~centre):                   # 2000 elevations across the row, sin theta weighted
        sub = (r + (np.arange(2000) + 0.5) / 2000) / h
        rad = model.radiance(sky, model._equirect_dirs(u, sub[:, None]))
        weight = np.sin((1.0 - sub) * np.pi)[:, None, None]
        np.testing.assert_allclose(img[r], (rad * weight).sum(axis=0) / weight.sum(), rtol=2e-4, atol=1e-6)


def test_equirect_keeps_the_horizons_light():
    """Dense air, a low sun, Altitude 0: the sky stays bright down to the horizon's dip
    (~0.03 degrees below) over a ground 30x darker, a step far finer than the map's rows of
    0.088 degrees that Cycles' warped table resolves (0.0014 degrees at the horizon). The map,
    blended between rows as the environment light blends it, must hold the light of the band
    +-1 degree about the horizon: read at texel centres it had lost 2% of it (a render's row
    holding the horizon 0.955-0.968x Cycles, the row under it 0.70x)."""
    sky = model.Sky.from_node_values(True, 0.11, 1.0, sun_disc=False, altitude=0.0,
                                      air=4.17, aerosol=1.47, ozone=4.97)
    h, w = 2048, 16
    img = model.equirect(sky, w, height=h).astype(np.float64)
    centres = (np.arange(h) + 0.5) / h * np.pi - np.pi / 2         # row elevations
    el = np.linspace(-np.radians(1.0), np.radians(1.0), 200001)
    for col in (0, 5, 11):
        phi = (0.5 - (col + 0.5) / w) * 2 * np.pi                  # the texel column's azimuth
        dirs = np.stack([np.cos(el) * np.cos(phi), np.cos(el) * np.sin(phi), np.sin(el)], -1)
        exact = model.radiance(sky, dirs).sum(axis=0)
        blended = np.stack([np.interp(el, centres, img[:, col, k]) for k in range(3)], -1).sum(axis=0)
        np.testing.assert_allclose(blended, exact, rtol=3e-3)


@pytest.mark.parametrize('multiple', (True, False))
def test_equirect_carries_the_sun_discs_light(multiple):
    """The disc's light in the image (its texels x their solid angles, the sky taken away)
    equals its integral over the disc, by a fine quadrature of the per-direction radiance."""
    with_disc = model.Sky.from_node_values(multiple, math.radians(40), 1.1, sun_size=math.radians(1.5))
    without = model.Sky.from_node_values(multiple, math.radians(40), 1.1, sun_size=math.radians(1.5), sun_disc=False)
    w = 1024
    h = w // 2
    diff = model.equirect(with_disc, w).astype(np.float64) - model.equirect(without, w)
    theta = (1 - (np.arange(h) + 0.5) / h) * math.pi
    texel = (2 * math.pi / w) * (np.cos(theta - math.pi / h / 2) - np.cos(theta + math.pi / h / 2))
    in_image = (diff * texel[:, None, None]).sum((0, 1))
    # quadrature on a polar grid around the sun
    sun = with_disc.sun_direction()
    half = with_disc.diameter / 2
    a = np.cross(sun, [0.0, 0.0, 1.0])
    a /= np.linalg.norm(a)
    b = np.cross(sun, a)
    r = (np.arange(400) + 0.5) / 400 * half
    phi = (np.arange(400) + 0.5) / 400 * 2 * math.pi
    R, P = np.meshgrid(r, phi, indexing='ij')
    dirs = np.cos(R)[..., None] * sun + np.sin(R)[..., None] * (np.cos(P)[..., None] * a + np.sin(P)[..., None] * b)
    sun_only = model.radiance(with_disc, dirs) - model.radiance(without, dirs)
    exact = (sun_only * (np.sin(R) * (half / 400) * (2 * math.pi / 400))[..., None]).sum((0, 1))
    np.testing.assert_allclose(in_image, exact, rtol=2e-3)


def test_sun_angles_wrap_as_cycles():
    over = model.Sky.from_node_values(True, math.radians(100), math.radians(10))
    plain = model.Sky.from_node_values(True, math.radians(80), math.radians(190))
    assert over.sun_elevation == pytest.approx(plain.sun_elevation)
    assert over.sun_rotation == pytest.approx(plain.sun_rotation)
    # rotation 0 puts the sun toward +Y, 90 degrees toward +X (as Cycles renders it)
    np.testing.assert_allclose(model.Sky.from_node_values(True, 0.0, 0.0).sun_direction(), [0, 1, 0], atol=1e-7)
    np.testing.assert_allclose(model.Sky.from_node_values(True, 0.0, math.pi / 2).sun_direction(), [1, 0, 0],
                               atol=1e-7)


def test_hosek_wilkie_coefficients_are_the_published_ones():
    """The dataset's first and last entries as sky_hosek_data.h prints them, and a sky at a
    turbidity between the tables blends its neighbours linearly."""
    from addon import skyanalytic
    from addon.skyhosek_data import CONFIGS, RADIANCES
    np.testing.assert_array_equal(CONFIGS[0, 0, 0, 0, :3], [-1.117001, -0.1867262, -11.13505])
    np.testing.assert_array_equal(RADIANCES[0, 1, 9], [0.8574294, 1.865155, -2.364707, 4.337793, 50.92831, 25.23432])
    np.testing.assert_array_equal(RADIANCES[2, 1, 9], [0.8640731, 0.9858301, 1.854956, -6.798097, 59.36468, 31.10255])
    sun = (0.2, 0.4, 0.7)
    lo, hi, mid = (skyanalytic.Analytic.hosek_wilkie(sun, t, 0.3) for t in (3.0, 4.0, 3.25))
    np.testing.assert_allclose(mid.radiances, 0.75 * np.array(lo.radiances) + 0.25 * np.array(hi.radiances))
    np.testing.assert_allclose(mid.configs, 0.75 * np.array(lo.configs) + 0.25 * np.array(hi.configs))


def test_preetham_zenith_is_its_zenith_luminance():
    """Preetham's Y at the zenith is the model's zenith luminance (x 0.06, as Cycles scales it)."""
    from addon import skyanalytic
    T, theta = 2.5, 0.6
    sky = skyanalytic.Analytic.preetham((math.sin(theta), 0.0, math.cos(theta)), T)
    chi = (4 / 9 - T / 120) * (math.pi - 2 * theta)
    zenith_Y = ((4.0453 * T - 4.9710) * math.tan(chi) - 0.2155 * T + 2.4192) * 0.06
    rgb_to_xyz = np.linalg.inv(model.XYZ_TO_REC709)
    Y = (rgb_to_xyz @ skyanalytic.radiance(sky, np.array([0.0, 0.0, 1.0]), model.XYZ_TO_REC709))[1]
    assert Y == pytest.approx(zenith_Y, rel=1e-9)


@pytest.mark.parametrize('kind', ('hosek', 'preetham'))
@pytest.mark.parametrize('sun', ((0.3, 0.5, 0.8), (0.8, -0.3, 0.25), (0.0, 0.0, 1.0), (1.0, 0.0, -0.1)))
def test_closed_form_map_is_its_texel_centres_radiance(kind, sun):
    """skyanalytic.equirect (its per-row terms taken once per row) is, bit for bit, radiance()
    of each texel centre's direction, as the map had been made: the full maps' sizes (1024 x
    2048 Hosek-Wilkie, 1024 x 512 Preetham) and an odd one."""
    from addon import skyanalytic
    sky = skyanalytic.Analytic.hosek_wilkie(sun, 4.2, 0.3) if kind == 'hosek' else \
        skyanalytic.Analytic.preetham(sun, 4.2)
    m = np.array(model.XYZ_TO_REC709)
    for width, height in ((1024, 2048 if kind == 'hosek' else 512), (97, 31)):
        theta = (1.0 - (np.arange(height) + 0.5) / height) * np.pi
        phi = (0.5 - (np.arange(width) + 0.5) / width) * 2 * np.pi
        st = np.sin(theta)[:, None]
        dirs = np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1)
        expected = skyanalytic.radiance(sky, dirs, m).astype(np.float32)
        got = skyanalytic.equirect(sky, width, m, height)
        assert got.dtype == np.float32 and got.shape == (height, width, 3)
        assert np.array_equal(got, expected), np.abs(got - expected).max()
