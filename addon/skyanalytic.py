"""The Sky Texture's closed-form skies as Cycles evaluates them (Blender 5.0: the precompute in
scene/shader_nodes.cpp, the per-direction kernel in kernel/svm/sky.h): Preetham (Perez
functions of the zenith angle and the angle to the sun, in xyY) and Hosek-Wilkie (their fitted
9-coefficient function in XYZ, coefficients blended from skyhosek_data by turbidity, ground
albedo and the sun's elevation). Neither has a sun disc. Directions below the horizon read the
horizon's zenith angle (both clamp it to pi/2 - 0.001), so the ground mirrors the horizon. No
bpy here: the export layer (export/sky.py) reads the node."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skyhosek_data import CONFIGS, RADIANCES


def _sun_angles(direction):
    """(theta, phi) of the node's Sun Direction as Cycles' sky_spherical_coordinates (phi from +Y)."""
    d = np.asarray(direction, np.float64)
    n = np.linalg.norm(d)
    d = d / n if n > 0 else np.array([0.0, 0.0, 1.0])
    return float(np.arccos(np.clip(d[2], -1.0, 1.0))), float(np.arctan2(d[0], d[1]))


def _perez(lam, theta, gamma):
    return (1.0 + lam[0] * np.exp(lam[1] / np.cos(theta))) * \
        (1.0 + lam[2] * np.exp(lam[3] * gamma) + lam[4] * np.cos(gamma) ** 2)


@dataclass(frozen=True)
class Analytic:
    """A Preetham or Hosek-Wilkie sky: the sun's angles and per-channel (Y, x, y) or (X, Y, Z)
    coefficients and radiances, as Cycles precomputes them."""
    hosek: bool
    sun_theta: float
    sun_phi: float
    configs: tuple            # 3 x 9
    radiances: tuple          # 3

    @staticmethod
    def preetham(sun_direction, turbidity):
        theta, phi = _sun_angles(sun_direction)
        T = float(turbidity)
        chi = (4.0 / 9.0 - T / 120.0) * (np.pi - 2.0 * theta)
        zenith_Y = ((4.0453 * T - 4.9710) * np.tan(chi) - 0.2155 * T + 2.4192) * 0.06
        t1, t2, t3 = theta, theta ** 2, theta ** 3
        zenith_x = ((0.00166 * t3 - 0.00375 * t2 + 0.00209 * t1) * T * T
                    + (-0.02903 * t3 + 0.06377 * t2 - 0.03202 * t1 + 0.00394) * T
                    + (0.11693 * t3 - 0.21196 * t2 + 0.06052 * t1 + 0.25886))
        zenith_y = ((0.00275 * t3 - 0.00610 * t2 + 0.00317 * t1) * T * T
                    + (-0.04214 * t3 + 0.08970 * t2 - 0.04153 * t1 + 0.00516) * T
                    + (0.15346 * t3 - 0.26756 * t2 + 0.06670 * t1 + 0.26688))
        perez_Y = (0.1787 * T - 1.4630, -0.3554 * T + 0.4275, -0.0227 * T + 5.3251, 0.1206 * T - 2.5771,
                   -0.0670 * T + 0.3703)
        perez_x = (-0.0193 * T - 0.2592, -0.0665 * T + 0.0008, -0.0004 * T + 0.2125, -0.0641 * T - 0.8989,
                   -0.0033 * T + 0.0452)
        perez_y = (-0.0167 * T - 0.2608, -0.0950 * T + 0.0092, -0.0079 * T + 0.2102, -0.0441 * T - 1.6537,
                   -0.0109 * T + 0.0529)
        # the zenith values divided by the Perez function at the zenith, as Cycles stores them
        radiances = tuple(float(z / _perez(p, 0.0, theta))
                          for z, p in ((zenith_Y, perez_Y), (zenith_x, perez_x), (zenith_y, perez_y)))
        return Analytic(False, theta, phi, (perez_Y, perez_x, perez_y), radiances)

    @staticmethod
    def hosek_wilkie(sun_direction, turbidity, ground_albedo):
        theta, phi = _sun_angles(sun_direction)
        theta = min(max(theta, 0.0), np.pi / 2)
        # Cycles clamps to [0, 10]; below 1 its tables would be read before their start
        T = min(max(float(turbidity), 1.0), 10.0)
        albedo = float(ground_albedo)
        s = (((np.pi / 2 - theta) / (np.pi / 2)) ** (1.0 / 3.0))
        bern = np.array([(1 - s) ** 5, 5 * (1 - s) ** 4 * s, 10 * (1 - s) ** 3 * s ** 2, 10 * (1 - s) ** 2 * s ** 3,
                         5 * (1 - s) * s ** 4, s ** 5])
        ti = int(T)
        rem = T - ti
        weights = [((0, ti - 1), (1 - albedo) * (1 - rem)), ((1, ti - 1), albedo * (1 - rem))]
        if ti < 10:
            weights += [((0, ti), (1 - albedo) * rem), ((1, ti), albedo * rem)]
        configs = sum(w * np.einsum('k,ckn->cn', bern, CONFIGS[:, a, t]) for (a, t), w in weights)
        radiances = sum(w * RADIANCES[:, a, t] @ bern for (a, t), w in weights)
        return Analytic(True, theta, phi, tuple(map(tuple, configs)), tuple(map(float, radiances)))


def _xyY_to_xyz(x, y, Y):
    """Cycles' xyY_to_xyz: X and Z 0 where y is 0 (Z also where Y is)."""
    safe = np.where(y != 0, y, 1.0)
    X = np.where(y != 0, x / safe * Y, 0.0)
    Z = np.where((y != 0) & (Y != 0), (1.0 - x - y) / safe * Y, 0.0)
    return np.stack([X, Y, Z], axis=-1)


def _hosek(config, theta, gamma, cg):
    c = config
    ct = np.cos(theta)
    mie = (1.0 + cg * cg) / np.power(1.0 + c[8] * c[8] - 2.0 * c[8] * cg, 1.5)
    return (1.0 + c[0] * np.exp(c[1] / (ct + 0.01))) * \
        (c[2] + c[3] * np.exp(c[4] * gamma) + c[5] * cg * cg + c[6] * mie + c[7] * np.sqrt(ct))


def radiance(sky, dirs, xyz_to_rgb):
    """(..., 3) scene linear RGB of the sky in unit directions (..., 3), as Cycles' kernel."""
    dirs = np.asarray(dirs, np.float64)
    theta = np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))
    phi = np.pi / 2 - np.arctan2(dirs[..., 1], dirs[..., 0])
    return _radiance_at(sky, theta, phi, xyz_to_rgb)


def _radiance_at(sky, theta, phi, xyz_to_rgb):
    """radiance() at zenith angles theta and azimuths phi that broadcast together: a map's
    theta is a column (one per row), so what depends on it alone is computed once per row; each
    value is the same operation on the same operands as per direction, so the same bits."""
    cos_gamma = (np.sin(theta) * np.sin(sky.sun_theta) * np.cos(sky.sun_phi - phi)
                 + np.cos(theta) * np.cos(sky.sun_theta))
    gamma = np.arccos(np.clip(cos_gamma, -1.0, 1.0))
    theta = np.minimum(theta, np.pi / 2 - 0.001)
    m = np.asarray(xyz_to_rgb, np.float64).T
    if sky.hosek:
        cg = np.cos(gamma)
        xyz = np.stack([_hosek(sky.configs[c], theta, gamma, cg) * sky.radiances[c] for c in range(3)], axis=-1)
        return np.maximum(xyz @ m, 0.0) * (2.0 * np.pi / 683.0)
    Y, x, y = (sky.radiances[c] * _perez(sky.configs[c], theta, gamma) for c in range(3))
    return np.maximum(_xyY_to_xyz(x, y, Y) @ m, 0.0)


def equirect(sky, width, xyz_to_rgb, height=None):
    """(height, width, 3) float32 equirectangular image of the sky at texel centres (row 0 at
    the bottom, as the environment light maps it; height width / 2 unless given): radiance() of
    each texel centre's direction, its zenith angle taken once per row (a Hosek-Wilkie map's
    ~0.4 s of CPU per sky had been mostly per-texel repeats of per-row terms)."""
    height = width // 2 if height is None else int(height)
    theta = (1.0 - (np.arange(height) + 0.5) / height) * np.pi
    phi = (0.5 - (np.arange(width) + 0.5) / width) * 2 * np.pi
    st = np.sin(theta)[:, None]
    # the directions' z is cos(theta) along a row: its arccos once per row
    row_theta = np.arccos(np.clip(np.cos(theta), -1.0, 1.0))[:, None]
    azimuth = np.pi / 2 - np.arctan2(st * np.sin(phi), st * np.cos(phi))
    return _radiance_at(sky, row_theta, azimuth, xyz_to_rgb).astype(np.float32)
