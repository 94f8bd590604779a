"""The Sky Texture's physical sky models as Cycles evaluates them (Blender 5.0: intern/sky and
kernel/svm/sky.h), and their rendering into an equirectangular radiance image for the world's
environment light. No bpy here: the export layer (export/sky.py) reads the node.

- Multiple Scattering (the 5.0 default; García Liñán's 4-wavelength model with a fitted
  multiple-scattering term) and Single Scattering (the former Nishita, 21 wavelengths):
  Cycles precomputes a 512 x 256 XYZ table per render (rows: elevation through a square-law
  warp that gives the horizon more rows, the ground below; columns: azimuth from the sun,
  mirrored; single scattering's ground is its horizon row faded to black), then per
  direction reads it bilinearly (extend), converts XYZ to scene linear RGB (negatives to 0),
  and adds the sun disc: its radiance at the
  disc's lowest and highest points (the transmittance toward the sun / the disc's solid
  angle), blended by elevation, with limb darkening.
- The tables are computed here as Cycles computes them, vectorised: everything along a view
  ray that depends only on its elevation is computed once per row, only the terms that see
  the sun per texel. The geometry is float64 (Cycles' float32 rounding is noise on top),
  but for the view rays' lengths (near the ground float32 keeps few digits of them: 6% at
  Altitude 0) and the sun disc's solid angle, computed in float32 as Cycles does.
- Preetham and Hosek-Wilkie are not modelled here (the export reports them).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

TABLE_W, TABLE_H = 512, 256                  # Cycles' SkyLoader

# Cycles' fallback XYZ (D65) -> linear Rec.709; the export passes the config's own
XYZ_TO_REC709 = np.array([[3.2404542, -1.5371385, -0.4985314],
                          [-0.9692660, 1.8760108, 0.0415560],
                          [0.0556434, -0.2040259, 1.0572252]])


# ---- Multiple scattering (intern/sky/source/sky_multiple_scattering.cpp) -----------------
_MS_EARTH = 6371.0                            # km
_MS_THICK = 100.0
_MS_ATMOS = _MS_EARTH + _MS_THICK
_MS_STEPS = 64                                # transmittance and in-scattering march steps
_TR_W, _TR_H = 256, 64                        # transmittance table: cos(sun zenith) x altitude
_MS_SUN = np.array([1.679, 1.828, 1.986, 1.307])           # 630, 560, 490, 430 nm
_MS_MOLECULAR = np.array([6.605e-3, 1.067e-2, 1.842e-2, 3.156e-2])
_MS_OZONE_XS = np.array([3.472e-25, 3.914e-25, 1.349e-25, 11.03e-27]) * 334.5   # x mean Dobson
_MS_AEROSOL_ABS = np.array([2.8722e-24, 4.6168e-24, 7.9706e-24, 1.3578e-23])
_MS_AEROSOL_SCA = np.array([1.5908e-22, 1.7711e-22, 2.0942e-22, 2.4033e-22])
_MS_AEROSOL_BASE, _MS_AEROSOL_BG, _MS_AEROSOL_H = 1.3681e20, 2e6, 0.73
_MS_G = 0.8
_MS_GROUND = 0.3
_MS_FIT = 0.02 * np.array([0.217, 0.347, 0.594, 1.0])
_MS_XYZ = np.array([[53.386917738564668023, 22.981337506691024754, 0.0],
                    [43.904844466369358263, 71.347795700053393866, 0.102506867965741307],
                    [1.6137278251608962005, 18.422960591455485011, 31.742921188390805758],
                    [20.762668673810577145, 2.3614213523314368527, 110.48009643252140334]])


def _ms_densities(h, air, aerosol, ozone):
    """(..., 3) aerosol, ozone and air densities at altitudes h km (scaled by the node's
    densities): each coefficient is one of them times a spectrum (_MS_SPECTRA)."""
    log_h = np.log(np.maximum(h, 1e-4))
    aer = (np.exp(-h / _MS_AEROSOL_H) + _MS_AEROSOL_BG / _MS_AEROSOL_BASE) * (_MS_AEROSOL_BASE * aerosol)
    oz = np.exp(-(log_h - 3.22261) ** 2 * 5.55555555 - log_h) * (3.78547397e20 * ozone)
    # h ** 1.16364243 through the log (0 at h = 0, where the log is clamped: 1e-4 ** 1.16 ~ 2e-5)
    mol = np.exp(-0.07771971 * np.where(h > 1e-4, np.exp(1.16364243 * log_h), h ** 1.16364243)) * air
    return np.stack([aer, oz, mol], axis=-1)


# rows: the extinction, molecular and aerosol scattering spectra per unit of each density
_MS_EXTINCTION = np.stack([_MS_AEROSOL_ABS + _MS_AEROSOL_SCA, _MS_OZONE_XS, _MS_MOLECULAR])


def _ms_coefficients(h, air, aerosol, ozone):
    """(extinction, molecular scattering, aerosol scattering), each (..., 4), at altitudes h km."""
    d = _ms_densities(h, air, aerosol, ozone)
    return d @ _MS_EXTINCTION, d[..., 2:3] * _MS_MOLECULAR, d[..., 0:1] * _MS_AEROSOL_SCA


def _ray_sphere(b, c):
    """Cycles' ray_sphere_intersection from b = dot(pos, dir), c = |pos|^2 - r^2 (unit dir):
    the exit distance from inside, the near hit from outside, -1 for none."""
    d = b * b - c
    root = np.sqrt(np.maximum(d, 0.0))
    t = np.where(d >= b * b, -b + root, -b - root)
    return np.where(((c > 0) & (b > 0)) | (d < 0), -1.0, t)


def _ms_transmittance(cos_theta, h_norm, air, aerosol, ozone):
    """(..., 4) transmittance from altitude h_norm x 100 km toward a sun at cos(zenith), marched."""
    cos_theta, h_norm = np.broadcast_arrays(np.asarray(cos_theta, float), np.asarray(h_norm, float))
    r0 = _MS_EARTH + h_norm * _MS_THICK
    t_d = _ray_sphere(r0 * cos_theta, r0 * r0 - _MS_ATMOS ** 2)
    dt = t_d / _MS_STEPS
    t = (np.arange(_MS_STEPS) + 0.5) * dt[..., None]                       # (..., steps)
    sin_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0))[..., None]
    radius = np.hypot(sin_theta * t, r0[..., None] + cos_theta[..., None] * t)
    # the densities in float32, as Cycles (1M points for the table: half the time)
    depth = _ms_densities(np.maximum(radius - _MS_EARTH, 0.0).astype(np.float32), air, aerosol, ozone)
    depth = depth.sum(-2, dtype=np.float64)
    return np.exp(-(depth @ _MS_EXTINCTION) * dt[..., None])


class _TransmittanceTable:
    """The 256 x 64 transmittance table and Cycles' bilinear reads of it (clamped)."""

    def __init__(self, air, aerosol, ozone):
        cos = np.arange(_TR_W) / (_TR_W - 1) * 2.0 - 1.0
        h = np.arange(_TR_H) / (_TR_H - 1)
        self.lut = _ms_transmittance(cos[None, :], h[:, None], air, aerosol, ozone)   # (H, W, 4)
        self.flat = self.lut.reshape(-1, 4)

    def __call__(self, cos_theta, h_norm):
        x = (_TR_W - 1) * np.clip(cos_theta * 0.5 + 0.5, 0.0, 1.0)
        y = (_TR_H - 1) * np.clip(h_norm, 0.0, 1.0)
        x1, y1 = x.astype(np.intp), y.astype(np.intp)
        x2, y2 = np.minimum(x1 + 1, _TR_W - 1), np.minimum(y1 + 1, _TR_H - 1)
        fx, fy = (x - x1)[..., None], (y - y1)[..., None]
        f = self.flat
        bottom = f[y1 * _TR_W + x1] * (1 - fx) + f[y1 * _TR_W + x2] * fx
        top = f[y2 * _TR_W + x1] * (1 - fx) + f[y2 * _TR_W + x2] * fx
        return bottom * (1 - fy) + top * fy

    def at_ground(self, cos_theta):
        x = (_TR_W - 1) * np.clip(cos_theta * 0.5 + 0.5, 0.0, 1.0)
        x1 = x.astype(np.intp)
        fx = (x - x1)[..., None]
        return self.lut[0, x1] * (1 - fx) + self.lut[0, np.minimum(x1 + 1, _TR_W - 1)] * fx

    def to_zenith(self, h_norm):
        y = (_TR_H - 1) * np.clip(h_norm, 0.0, 1.0)
        y1 = y.astype(np.intp)
        fy = (y - y1)[..., None]
        col = self.lut[:, -1]
        return col[y1] * (1 - fy) + col[np.minimum(y1 + 1, _TR_H - 1)] * fy


def _warp_elevation(v):
    """The table rows' elevation at texture coordinate v: a signed square of 2v - 1, x pi/2."""
    l = 2.0 * v - 1.0
    return np.copysign(l * l, l) * (np.pi / 2)


def _view_ray_lengths(altitude):
    """(r0, (TABLE_H,)): the view point's distance from the centre (km) and each table row's view ray length to the ground or out of the atmosphere, in
    float32 as Cycles computes it (ray_sphere_intersection from its row's elevation): below the
    horizon it is -b - sqrt(b^2 - c) with c = r0^2 - R^2, which float32 rounds to a multiple of
    4 km^2 (r0^2 ~ 4e7): 12 where it is 12.74 at Altitude 0 (1 m, r0 itself rounded to
    6371.00098), so Cycles' ground paths, and the ground's light, are 6% shorter and dimmer
    than float64's; +-0.3% at 100 m."""
    f32 = np.float32
    r0 = f32(_MS_EARTH) + f32(np.clip(f32(altitude), f32(1.0), f32(99999.0))) / f32(1000.0)
    l = (np.arange(TABLE_H, dtype=f32) + f32(0.5)) / f32(TABLE_H) * f32(2.0) - f32(1.0)
    elev = np.copysign(l * l, l) * f32(np.pi / 2)
    b = r0 * np.sin(elev.astype(np.float64)).astype(f32)

    def hit(radius):
        c = r0 * r0 - f32(radius) * f32(radius)
        d = b * b - c
        root = np.sqrt(np.maximum(d, f32(0)))
        t = np.where(d >= b * b, -b + root, -b - root)
        return np.where(((c > 0) & (b > 0)) | (d < 0), f32(-1.0), t)

    ground = hit(_MS_EARTH)
    return float(r0), np.where(ground < 0, hit(_MS_ATMOS), ground).astype(np.float64)


# Below this optical depth along a row's view ray Cycles' float32 sum of its 64 steps moves its
# light by more than ~10^-4: each step's transmittance is 1 - k 2^-24 and its in-scattering
# S - S x step is rounded to S's float32 step, one part in 2^24 of S / extinction per step
_SHORT_DEPTH = _MS_STEPS * 2.0 ** -24 * 1e4


def _short_rows(dt, ext):
    """(rows,) bool: the rows whose optical depth is small enough that Cycles' float32
    arithmetic moves their light (the ground seen from a low Altitude: a 1 m path at 1 m,
    where a step's depth is ~25 x 2^-24 and each channel's light up to 5% off the exact
    integral's; 0.1% at 100 m)."""
    return (dt[:, None] * ext.sum(axis=1)).min(axis=1) < _SHORT_DEPTH


def _cycles_distances(r0, dt, rows):
    """(len(rows), steps) distances from the centre of the steps of table rows `rows` as
    get_inscattering computes them in float32, |origin + dir t|: at 1 m over the ground they
    are a few multiples of 0.00049 km (a float32 step near 6371), which Cycles' altitudes,
    densities and the ground's solid angle follow."""
    f32 = np.float32
    l = (rows.astype(f32) + f32(0.5)) / f32(TABLE_H) * f32(2.0) - f32(1.0)
    elev = np.copysign(l * l, l) * f32(np.pi / 2)
    dz = np.sin(elev.astype(np.float64)).astype(f32)
    dxy = np.cos(elev.astype(np.float64)).astype(f32)
    t = (np.arange(_MS_STEPS, dtype=f32) + f32(0.5)) * dt.astype(f32)[:, None]
    z = f32(r0) + dz[:, None] * t
    xy = dxy[:, None] * t
    return np.sqrt(xy * xy + z * z).astype(np.float64)


def _cycles_solid_angle_of_earth(dist):
    """The Earth's solid angle from `dist` km as lookup_multiscattering computes it in float32:
    2 pi (1 - sqrt(1 - (R / dist)^2)), whose 1 - (R / dist)^2 keeps one or two digits at 1 m."""
    f32 = np.float32
    q = f32(_MS_EARTH) / dist.astype(f32)
    return (f32(2 * np.pi) * (f32(1) - np.sqrt(np.maximum(f32(1) - q * q, f32(0))))).astype(np.float64)


def _step_integral_float32(to_sun, ms, phases, mol_sca, aer_sca, ext, dt):
    """(rows, az, 4) in-scattered light of short rows (_short_rows) summed as Cycles sums it in
    float32: S = sun (molecular (phase T + ms) + aerosol (phase T + ms)), each step adding
    transmittance x (S - S step) / extinction with step = expf(-dt extinction), correctly
    rounded as glibc's expf (numpy's float32 exp is 1 ulp off half the time there, 4% of a
    1 m step's light). to_sun, ms: (rows, az, steps, 4); phases (rows, az, 2); the rest per
    (rows, steps, 4) and (rows,)."""
    f32 = np.float32
    ext32 = ext.astype(f32)
    step = np.exp((-dt.astype(f32)[:, None, None] * ext32).astype(np.float64)).astype(f32)
    before = np.cumprod(np.concatenate([np.ones_like(step[:, :1]), step[:, :-1]], axis=1), axis=1)
    mol, aer = mol_sca.astype(f32)[:, None], aer_sca.astype(f32)[:, None]
    sun = _MS_SUN.astype(f32)
    to_sun, ms, phases = to_sun.astype(f32), ms.astype(f32), phases.astype(f32)
    s = sun * (mol * (phases[..., 0, None, None] * to_sun + ms) + aer * (phases[..., 1, None, None] * to_sun + ms))
    s_int = (s - s * step[:, None]) / np.maximum(ext32, f32(1e-7))[:, None]
    return (before[:, None] * s_int).sum(axis=2, dtype=np.float64)


def multiple_scattering_table(sun_elevation, altitude, air, aerosol, ozone):
    """(256, 512, 3) XYZ radiance table of the multiple-scattering sky (row 0: straight down),
    as SKY_multiple_scattering_precompute_texture; altitude in metres."""
    tr = _TransmittanceTable(air, aerosol, ozone)
    cz = np.cos(np.pi / 2 - sun_elevation)
    sx, sz = -np.sqrt(max(1.0 - cz * cz, 0.0)), cz                 # sun in the x-z plane
    half = TABLE_W // 2
    az = 2.0 * np.pi * (np.arange(half) + 0.5) / TABLE_W
    elev = _warp_elevation((np.arange(TABLE_H) + 0.5) / TABLE_H)
    ce, se = np.cos(elev), np.sin(elev)
    r0, t_d = _view_ray_lengths(altitude)                             # (rows,)
    dt = t_d / _MS_STEPS
    # per row and step: what depends on the ray's elevation only
    t = (np.arange(_MS_STEPS) + 0.5) * dt[:, None]                    # (rows, steps)
    horiz, vert = ce[:, None] * t, r0 + se[:, None] * t
    dist = np.hypot(horiz, vert)
    ext = _ms_coefficients(np.maximum(dist - _MS_EARTH, 0.0), air, aerosol, ozone)[0]
    short = _short_rows(dt, ext)
    dist[short] = _cycles_distances(r0, dt[short], np.flatnonzero(short))
    h = np.maximum(dist - _MS_EARTH, 0.0)
    h_norm = h / _MS_THICK
    ext, mol_sca, aer_sca = _ms_coefficients(h, air, aerosol, ozone)  # (rows, steps, 4)
    step_tr = np.exp(-dt[:, None, None] * ext)
    before = np.cumprod(np.concatenate([np.ones_like(step_tr[:, :1]), step_tr[:, :-1]], axis=1), axis=1)
    weight = before * (1.0 - step_tr) / np.maximum(ext, 1e-7)        # Hillaire's step integral
    omega = 2.0 * np.pi * (1.0 - np.sqrt(np.maximum(1.0 - (_MS_EARTH / dist) ** 2, 0.0)))
    omega[short] = _cycles_solid_angle_of_earth(dist[short])
    ground_to_sample = tr.to_zenith(np.zeros(1)) / tr.to_zenith(h_norm)
    k_ground = (omega / (4.0 * np.pi) * (_MS_GROUND / np.pi))[..., None] * ground_to_sample
    # the sample's cos(sun zenith) = a cos(azimuth) + b, the sun having no y component
    a, b = horiz * sx / dist, vert * sz / dist
    cos_view = -(ce[:, None] * np.cos(az)[None, :] * sx + se[:, None] * sz)   # dot(-ray, sun)
    mol_phase = 3.0 / (16.0 * np.pi) * (1.0 + cos_view ** 2)
    den = 1.0 + _MS_G ** 2 + 2.0 * _MS_G * cos_view
    aer_phase = (1.0 - _MS_G ** 2) / (4.0 * np.pi * den * np.sqrt(den))
    # Per point only what depends on the sample's cos(sun zenith) cs varies: the transmittance
    # to the sun (the table read at cs and the step's altitude: the table is blended at each
    # (row, step)'s altitude first, then one gather reads a texel and its step to the next
    # column), the ground's light (the table's ground row at cs, x cs) and the fit's logistic
    # in cs. float32 from here, as Cycles
    f32 = np.float32
    lut = tr.lut.astype(f32)
    cells = np.concatenate([lut, np.diff(lut, axis=1, append=lut[:, -1:])], axis=-1)   # (64, 256, 8)
    ground = cells[0]
    y = (_TR_H - 1) * np.clip(h_norm, 0.0, 1.0)
    y1 = y.astype(np.intp)
    y2 = np.minimum(y1 + 1, _TR_H - 1)
    fy = (y - y1).astype(f32)[..., None, None]
    cos_az = np.cos(az).astype(f32)
    w_sun = np.stack([weight * mol_sca, weight * aer_sca], axis=2).astype(f32)         # (rows, steps, 2, 4)
    w_all = (weight * (mol_sca + aer_sca)).astype(f32)
    w_ground = w_all * k_ground.astype(f32)
    phases = np.stack([mol_phase, aer_phase], axis=-1).astype(f32)                     # (rows, az, 2)
    fit = _MS_FIT.astype(f32)
    xyz = np.zeros((TABLE_H, half, 3))
    rows = 8
    for r in range(0, TABLE_H, rows):                 # blocks of rows bound the memory (~40 MB)
        sl = slice(r, r + rows)
        n = len(range(TABLE_H)[sl])
        blend = cells[y1[sl]] + fy[sl] * (cells[y2[sl]] - cells[y1[sl]])                # (r, steps, 256, 8)
        cs = a[sl, None, :].astype(f32) * cos_az[None, :, None] + b[sl, None, :].astype(f32)   # (r, az, steps)
        x = (_TR_W - 1) * np.clip(cs * f32(0.5) + f32(0.5), f32(0), f32(1))
        x1 = x.astype(np.intp)
        fx = (x - x1)[..., None]
        q = blend.reshape(-1, 8)[(np.arange(n * _MS_STEPS).reshape(n, 1, _MS_STEPS) * _TR_W) + x1]
        to_sun = q[..., :4] + fx * q[..., 4:]
        g = ground[x1]
        lit_ground = (g[..., :4] + fx * g[..., 4:]) * cs[..., None]
        logistic = f32(1) / (f32(1) + f32(5) * np.exp(f32(-17.92) * cs))
        # sums over the steps as batched matrix products (per row and channel)
        by_sun = np.matmul(to_sun.transpose(0, 3, 1, 2), w_sun[sl].transpose(0, 3, 1, 2))      # (r, c, az, 2)
        by_ground = np.matmul(lit_ground.transpose(0, 3, 1, 2), w_ground[sl].transpose(0, 2, 1)[..., None])
        light = (np.einsum('rcak,rak->rac', by_sun, phases[sl]) + by_ground[..., 0].transpose(0, 2, 1)
                 + np.matmul(logistic, w_all[sl]) * fit)
        light = light * _MS_SUN
        rows_short = np.flatnonzero(short[sl])
        if len(rows_short):
            k = r + rows_short
            ms = logistic[rows_short, ..., None] * fit + lit_ground[rows_short] * k_ground[k, None].astype(f32)
            light[rows_short] = _step_integral_float32(
                to_sun[rows_short], ms, phases[k], mol_sca[k], aer_sca[k], ext[k], dt[k])
        xyz[sl] = light @ _MS_XYZ
    return np.concatenate([xyz, xyz[:, ::-1]], axis=1).astype(np.float32)


def _cycles_solid_angle(diameter):
    """The disc's solid angle as intern/sky's precompute_sun divides its irradiance by it, in
    float32: 2 pi (1 - cosf(diameter / 2)). Near 1 a float32 cos moves in steps of 5.96e-8, so
    for a small disc this is far from the disc's own (x1.74 at 0.03 degrees, x0.94 at 0.1,
    x1.02 at 0.2, x1.001 at the default 0.545), and Cycles' sun is that much dimmer or brighter
    (its light measured to follow it; a float64 solid angle had rendered a 0.03 degree sun 1.77x
    Cycles'). The float32 cos is rounded from float64's, as glibc's cosf rounds its double
    polynomial (half angles from 2^-12, Cycles' least diameter being 0.0005)."""
    f32 = np.float32
    half = f32(max(f32(diameter), f32(0.0005))) / f32(2)
    return float(f32(2.0 * np.pi) * (f32(1) - f32(np.cos(np.float64(half)))))


def multiple_scattering_sun(sun_elevation, diameter, altitude, air, aerosol, ozone):
    """(bottom, top) XYZ radiance of the sun disc at its lowest and highest points."""
    alt = np.clip(altitude, 1.0, 99999.0) / 1000.0
    solid = _cycles_solid_angle(diameter)
    elev = np.array([sun_elevation - diameter / 2, sun_elevation + diameter / 2])
    tr = _ms_transmittance(np.cos(np.pi / 2 - elev), np.full(2, alt / _MS_THICK), air, aerosol, ozone)
    return (_MS_SUN * tr / solid) @ _MS_XYZ


# ---- Single scattering (intern/sky/source/sky_single_scattering.cpp) ---------------------
_SS_RAYLEIGH_H, _SS_MIE_H, _SS_MIE, _SS_G = 8e3, 1.2e3, 2e-5, 0.76
_SS_EARTH, _SS_ATMOS = 6360e3, 6420e3        # m
_SS_STEPS = 32
_SS_IRRADIANCE = np.array([
    1.45756829855592995315, 1.56596305559738380175, 1.65148449067670455293, 1.71496242737209314555,
    1.75797983805020541226, 1.78256407885924539336, 1.79095108475838560302, 1.78541550133410664714,
    1.76815554864306845317, 1.74122069647250410362, 1.70647127164943679389, 1.66556087452739887134,
    1.61993437242451854274, 1.57083597368892080581, 1.51932335059305478886, 1.46628494965214395407,
    1.41245852740172450623, 1.35844961970384092709, 1.30474913844739281998, 1.25174963272610817455,
    1.19975998755420620867])
_SS_RAYLEIGH = np.array([
    0.00005424820087636473, 0.00004418549866505454, 0.00003635151910165377, 0.00003017929012024763,
    0.00002526320226989157, 0.00002130859310621843, 0.00001809838025320633, 0.00001547057129129042,
    0.00001330284977336850, 0.00001150184784075764, 0.00000999557429990163, 0.00000872799973630707,
    0.00000765513700977967, 0.00000674217203751443, 0.00000596134125832052, 0.00000529034598065810,
    0.00000471115687557433, 0.00000420910481110487, 0.00000377218381260133, 0.00000339051255477280,
    0.00000305591531679811])
_SS_OZONE = np.array([
    0.00000000325126849861, 0.00000000585395365047, 0.00000001977191155085, 0.00000007309568762914,
    0.00000020084561514287, 0.00000040383958096161, 0.00000063551335912363, 0.00000096707041180970,
    0.00000154797400424410, 0.00000209038647223331, 0.00000246128056164565, 0.00000273551299461512,
    0.00000215125863128643, 0.00000159051840791988, 0.00000112356197979857, 0.00000073527551487574,
    0.00000046450130357806, 0.00000033096079921048, 0.00000022512612292678, 0.00000014879129266490,
    0.00000016828623364192])
_SS_CMF = np.array([  # CIE 1931 x, y, z at 380..780 nm in 20 nm steps
    [0.00136800000, 0.00003900000, 0.00645000100], [0.01431000000, 0.00039600000, 0.06785001000],
    [0.13438000000, 0.00400000000, 0.64560000000], [0.34828000000, 0.02300000000, 1.74706000000],
    [0.29080000000, 0.06000000000, 1.66920000000], [0.09564000000, 0.13902000000, 0.81295010000],
    [0.00490000000, 0.32300000000, 0.27200000000], [0.06327000000, 0.71000000000, 0.07824999000],
    [0.29040000000, 0.95400000000, 0.02030000000], [0.59450000000, 0.99500000000, 0.00390000000],
    [0.91630000000, 0.87000000000, 0.00165000100], [1.06220000000, 0.63100000000, 0.00080000000],
    [0.85444990000, 0.38100000000, 0.00019000000], [0.44790000000, 0.17500000000, 0.00002000000],
    [0.16490000000, 0.06100000000, 0.00000000000], [0.04677000000, 0.01700000000, 0.00000000000],
    [0.01135916000, 0.00410200000, 0.00000000000], [0.00289932700, 0.00104700000, 0.00000000000],
    [0.00069007860, 0.00024920000, 0.00000000000], [0.00016615050, 0.00006000000, 0.00000000000],
    [0.00004150994, 0.00001499000, 0.00000000000]]) * 20.0          # x the 20 nm step
# Gauss-Laguerre nodes and weights (exp(x) folded in) for the optical depth toward the sun
_SS_NODES = np.array([0.006811185292, 0.03614807107, 0.09004346519, 0.1706680068, 0.2818362161,
                      0.4303406404, 0.6296271457, 0.9145252695])
_SS_WEIGHTS = np.array([0.01750893642, 0.04135477391, 0.06678839063, 0.09507698807, 0.1283416365,
                        0.1707430204, 0.2327233347, 0.3562490486])


def _ss_density(h):
    """(..., 3) Rayleigh, Mie and ozone densities at heights h m."""
    return np.stack([np.exp(-h / _SS_RAYLEIGH_H), np.exp(-h / _SS_MIE_H),
                     np.maximum(0.0, 1.0 - np.abs(h - 25000.0) / 15000.0)], axis=-1)


def _ss_optical_depth(radius, cos_dir):
    """(..., 3) optical depth (unscaled densities x metres) from a point at `radius` along a ray
    at cos_dir to its zenith, out to the atmosphere's edge, by Cycles' quadrature."""
    b = 2.0 * radius * cos_dir
    length = (-b + np.sqrt(b * b - 4.0 * (radius * radius - _SS_ATMOS ** 2))) / 2.0
    s = _SS_NODES * length[..., None]
    r = np.sqrt(radius[..., None] ** 2 + 2.0 * s * (radius * cos_dir)[..., None] + s * s)
    return np.einsum('...nk,n->...k', _ss_density(r - _SS_EARTH), _SS_WEIGHTS) * length[..., None]


def single_scattering_table(sun_elevation, altitude, air, aerosol, ozone):
    """(256, 512, 3) XYZ table of the single-scattering sky, as
    SKY_single_scattering_precompute_texture (altitude in metres): the upper half from the
    horizon row (128) up, the lower half that horizon row faded to black (_faded_ground)."""
    alt = np.clip(altitude, 1.0, 59999.0)
    half_w, half_h = TABLE_W // 2, TABLE_H // 2
    out = np.zeros((TABLE_H, half_w, 3))
    ys = np.arange(half_h, TABLE_H)
    lat = np.pi / 2 * (ys / half_h - 1.0) ** 2                 # (this table's rows are not centred)
    lon = 2.0 * np.pi / TABLE_W * np.arange(half_w) - np.pi
    sun = np.array([np.cos(sun_elevation), 0.0, np.sin(sun_elevation)])
    r0 = _SS_EARTH + alt
    scale = np.array([air, aerosol, ozone])
    sl, cl = np.sin(lat), np.cos(lat)
    b = 2.0 * r0 * sl
    length = (-b + np.sqrt(b * b - 4.0 * (r0 * r0 - _SS_ATMOS ** 2))) / 2.0         # (rows,)
    seg = length / _SS_STEPS
    t = (np.arange(_SS_STEPS) + 0.5) * seg[:, None]                                  # (rows, steps)
    horiz, vert = cl[:, None] * t, r0 + sl[:, None] * t
    radius = np.hypot(horiz, vert)
    density = scale * _ss_density(radius - _SS_EARTH)                               # (rows, steps, 3)
    depth = np.cumsum(density, axis=1) * seg[:, None, None]        # view-ray depth through each step
    mu = (cl[:, None] * np.cos(lon)[None, :]) * sun[0] + sl[:, None] * sun[2]        # (rows, lon)
    ray_phase = 3.0 / (16.0 * np.pi) * (1.0 + mu * mu)
    mie_phase = (3.0 * (1.0 - _SS_G ** 2) * (1.0 + mu * mu)) / (
        8.0 * np.pi * (2.0 + _SS_G ** 2) * np.power(1.0 + _SS_G ** 2 - 2.0 * _SS_G * mu, 1.5))
    coef = np.stack([_SS_RAYLEIGH, np.full(21, 1.11 * _SS_MIE), _SS_OZONE])         # (3, 21)
    for i in range(len(ys)):
        # the sample point's position relative to the sun: P . sun / |P| per (lon, step)
        p_dot_sun = horiz[i][None, :] * np.cos(lon)[:, None] * sun[0] + vert[i][None, :] * sun[2]
        rad = np.broadcast_to(radius[i][None, :], p_dot_sun.shape)
        cos_sun = p_dot_sun / rad
        lit = ~((sun[2] < 0) & ((2 * p_dot_sun) ** 2 - 4 * (rad * rad - _SS_EARTH ** 2) >= 0))
        total = depth[i][None] + scale * _ss_optical_depth(rad, cos_sun)             # (lon, steps, 3)
        atten = np.exp(-(total @ coef).astype(np.float32))     # (lon, steps, 21); float32, as Cycles
        # each step scatters Rayleigh (density x phase x spectrum) plus Mie (grey): summed over
        # the steps apart, the phases (per longitude) and spectra applied after
        w = (lit * seg[i]).astype(np.float32)
        rayleigh = np.einsum('lsw,ls->lw', atten, w * density[i][None, :, 0].astype(np.float32))
        mie = np.einsum('lsw,ls->lw', atten, w * density[i][None, :, 1].astype(np.float32))
        spectrum = (ray_phase[i][:, None] * rayleigh * _SS_RAYLEIGH + mie_phase[i][:, None] * mie * _SS_MIE) \
            * _SS_IRRADIANCE
        out[ys[i]] = spectrum @ _SS_CMF
    table = np.concatenate([out, out[:, ::-1]], axis=1).astype(np.float32)
    table[:half_h] = _faded_ground(table[half_h], half_h)
    return table


def _faded_ground(horizon, half_h):
    """(half_h, width, 3) the single-scattering table's lower rows: the horizon row x
    (1 - 2.5 z)^3, z the sine of the row's (mirrored) warped elevation, black from z 0.4
    (-23.6 degrees), in float32 as intern/sky fills them. Cycles 5.0.1 reads the ground from
    these rows as it reads Multiple Scattering's (the warp undone, bilinear): the kernel's
    own fade of the row at y 0.508 by the view's z, which DACRT had used, rendered the ground
    2-25% brighter than Cycles (the further below the horizon, the brighter)."""
    f32 = np.float32
    y = np.arange(half_h, dtype=f32)
    z = np.sin(f32(np.pi / 2) * (y / f32(half_h) - f32(1.0)) ** 2)
    fade = np.where(z < f32(0.4), (f32(1.0) - z * f32(2.5)) ** 3, f32(0.0)).astype(f32)
    return horizon[None] * fade[:, None, None]


def single_scattering_sun(sun_elevation, diameter, altitude, air, aerosol):
    """(bottom, top) XYZ radiance of the sun disc (black below the horizon; no ozone, as Cycles)."""
    alt = np.clip(altitude, 1.0, 59999.0)
    half = diameter / 2
    elev = np.maximum(np.array([sun_elevation - half, sun_elevation + half]), 0.0)
    if not elev[1] > 0:
        return np.zeros((2, 3))
    solid = _cycles_solid_angle(diameter)
    depth = _ss_optical_depth(np.full(2, _SS_EARTH + alt), np.sin(elev))
    tau = np.outer(depth[:, 0] * air, _SS_RAYLEIGH) + np.outer(depth[:, 1] * aerosol, np.full(21, 1.11 * _SS_MIE))
    return (_SS_IRRADIANCE * np.exp(-tau) / solid) @ _SS_CMF


# ---- Cycles' evaluation of a direction (kernel/svm/sky.h) --------------------------------
@dataclass(frozen=True)
class Sky:
    """A Sky Texture's settings as Cycles holds them after simplify_settings: elevation in
    [-pi/2, pi/2], rotation the kernel's (2 pi - the node's, wrapped), sizes in radians."""
    multiple: bool
    sun_elevation: float
    sun_rotation: float
    sun_disc: bool = True
    sun_size: float = 0.009512
    sun_intensity: float = 1.0
    altitude: float = 100.0
    air: float = 1.0
    aerosol: float = 1.0
    ozone: float = 1.0

    @staticmethod
    def from_node_values(multiple, sun_elevation, sun_rotation, **kw):
        """The settings of a node's values, wrapped as Cycles' SkyTextureNode::simplify_settings."""
        e, rot = np.fmod(float(sun_elevation), 2 * np.pi), float(sun_rotation)
        if abs(e) >= np.pi:
            e -= np.copysign(2.0, e) * np.pi
        if e >= np.pi / 2 or e <= -np.pi / 2:
            e = np.copysign(np.pi, e) - e
            rot += np.pi
        rot = np.fmod(rot, 2 * np.pi)
        if rot < 0:
            rot += 2 * np.pi
        return Sky(bool(multiple), float(e), float(2 * np.pi - rot), **kw)

    @property
    def diameter(self):
        return max(self.sun_size, 0.0005)           # Cycles' get_sun_size

    def table(self):
        return _table(self.multiple, self.sun_elevation, self.altitude, self.air, self.aerosol, self.ozone)

    def sun_pixels(self):
        if self.multiple:
            return multiple_scattering_sun(self.sun_elevation, self.diameter, self.altitude, self.air,
                                           self.aerosol, self.ozone)
        return single_scattering_sun(self.sun_elevation, self.diameter, self.altitude, self.air, self.aerosol)

    def sun_direction(self):
        th, ph = self.sun_elevation - np.pi / 2, self.sun_rotation - np.pi / 2
        return np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])

    def earth_angle(self):
        """Below this elevation the ground hides the sun (SKY_earth_intersection_angle, negated)."""
        return -(np.pi / 2 - np.arcsin(_MS_EARTH / (_MS_EARTH + self.altitude / 1000.0)))


@lru_cache(maxsize=8)
def _table(multiple, sun_elevation, altitude, air, aerosol, ozone):
    """The XYZ table, cached per parameter set (a render of several views or frames reuses it)."""
    fn = multiple_scattering_table if multiple else single_scattering_table
    table = fn(sun_elevation, altitude, air, aerosol, ozone)
    table.setflags(write=False)
    return table


def _table_lookup(table, x, y):
    """Cycles' bilinear image read with extend: (..., 3) at texture coordinates x, y."""
    h, w = table.shape[:2]
    px, py = x * w - 0.5, y * h - 0.5
    ix, iy = np.floor(px), np.floor(py)
    tx, ty = (px - ix)[..., None], (py - iy)[..., None]
    ix, iy = ix.astype(np.intp), iy.astype(np.intp)
    x0, x1 = np.clip(ix, 0, w - 1), np.clip(ix + 1, 0, w - 1)
    y0, y1 = np.clip(iy, 0, h - 1), np.clip(iy + 1, 0, h - 1)
    return ((table[y0, x0] * (1 - tx) + table[y0, x1] * tx) * (1 - ty)
            + (table[y1, x0] * (1 - tx) + table[y1, x1] * tx) * ty)


def _row_coordinate(elevation):
    """Table y of directions at `elevation`: the row warp undone (both types; the single-
    scattering table's lower half holds its faded ground)."""
    return np.sqrt(np.abs(elevation) / (np.pi / 2)) * np.where(elevation < 0, -0.5, 0.5) + 0.5


def _column_coordinate(sky, phi):
    """Table x of directions of azimuth atan2(y, x) = phi (the sun at x = 0.5)."""
    return np.mod((-phi - np.pi / 2 + sky.sun_rotation) / (2 * np.pi), 1.0)


def _sun_xyz(sky, dirs, elevation, pixels):
    """(..., 3) XYZ radiance of the sun disc x its intensity in directions `dirs` (0 outside)."""
    if not sky.sun_disc:
        return np.zeros(dirs.shape[:-1] + (3,))
    sun = sky.sun_direction()
    angle = 2.0 * np.arctan2(np.linalg.norm(dirs - sun, axis=-1), np.linalg.norm(dirs + sun, axis=-1))
    half = sky.diameter / 2
    inside = (angle < half) & (elevation > sky.earth_angle())
    y = ((elevation - sky.sun_elevation) / sky.diameter + 0.5)[..., None]
    xyz = pixels[0] + y * (pixels[1] - pixels[0])
    limb = 1.0 - 0.6 * (1.0 - np.sqrt(np.maximum(1.0 - (angle / half) ** 2, 0.0)))
    return np.where(inside[..., None], xyz * limb[..., None], 0.0) * sky.sun_intensity


def radiance(sky, dirs, xyz_to_rgb=XYZ_TO_REC709):
    """(..., 3) scene linear RGB of the sky in unit directions `dirs` (..., 3), as Cycles'
    sky_radiance: sun and sky each converted to RGB with negatives cut, then added."""
    dirs = np.asarray(dirs, np.float64)
    m = np.asarray(xyz_to_rgb, np.float64).T
    elevation = np.pi / 2 - np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))
    phi = np.arctan2(dirs[..., 1], dirs[..., 0])
    y = _row_coordinate(elevation)
    xyz = _table_lookup(sky.table(), _column_coordinate(sky, phi), y)
    sun = _sun_xyz(sky, dirs, elevation, sky.sun_pixels())
    return np.maximum(xyz @ m, 0.0) + np.maximum(sun @ m, 0.0)


def _equirect_dirs(u, v):
    """Directions at equirectangular coordinates (u, v) as the environment light maps them
    (lights/environment.py: u = 0.5 - atan2(y, x) / 2 pi, v = 1 - acos(z) / pi)."""
    theta, phi = (1.0 - v) * np.pi, (0.5 - u) * 2 * np.pi
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def equirect(sky, width=2048, xyz_to_rgb=XYZ_TO_REC709, sun_samples=16, chain=None, height=None):
    """(height, width, 3) float32 equirectangular radiance image of the sky (row 0 at the
    bottom, the environment light's layout; height width / 2 unless given). The sky is read at texel centres: a texel's
    column fixes its azimuth and its row its elevation, so the table is blended per row, then
    per column. Texels the sun disc touches hold its integral over them / their solid angle
    (_add_sun; sun_samples^2 points per texel for a large disc), so the image carries the
    disc's whole light (2048 texels around: ~3 across the default sun).
    chain: colour nodes after the sky, fn((n, 3) RGB) -> (n, 3), applied to each texel and to
    each of the disc's points before their mean."""
    height = width // 2 if height is None else int(height)
    m = np.asarray(xyz_to_rgb, np.float64).T
    # to RGB before the blends (linear, so the same up to rounding): 3 x 3 products on the
    # table's 131K texels instead of the map's 2-4M; the blends in float32 (the map's type)
    table = sky.table().astype(np.float64) @ m
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    elevation = np.pi / 2 - (1.0 - v) * np.pi
    phi = np.angle(np.exp(1j * (0.5 - u) * 2 * np.pi))            # wrapped as atan2 returns it
    rows_y = _row_coordinate(elevation)
    by_row = _rows_of_table(table, rows_y)
    # By the horizon the table's warped rows are far finer than the map's (0.0014 degrees at
    # the horizon, 0.07 three rows away), and at a low Altitude the sky stays bright down to
    # the horizon's dip, ~0.03 degrees under it, over a dark ground: the two rows that meet at
    # the horizon hold their mean over their span of elevation, so the map keeps that band's
    # light (read at its centre, the row under the horizon missed it: a render's row holding
    # the horizon 0.955x Cycles, dense air). Rows further off keep their centre's value, which
    # resolves the step at a higher Altitude's dip (averaged, the render's rows of 0.094
    # degrees there had been 0.88x Cycles)
    near = np.flatnonzero(np.abs(elevation) < np.pi / height)        # the two rows by the horizon
    if len(near):
        n = _ROW_POINTS * max(1, 2048 // height)          # elevations 0.0014 degrees apart or less
        sub = (near[:, None] + (np.arange(n) + 0.5) / n) / height
        el_sub = np.pi / 2 - (1.0 - sub) * np.pi
        y_sub = _row_coordinate(el_sub)
        weight = np.cos(el_sub)[..., None, None]                        # solid angle
        mean = (_rows_of_table(table, y_sub.ravel()).reshape(weight.shape[:2] + table.shape[1:])
                * weight).sum(axis=1) / np.cos(el_sub).sum(axis=1)[:, None, None]
        by_row[near] = mean.astype(np.float32)
    px = _column_coordinate(sky, phi) * TABLE_W - 0.5
    ix = np.floor(px)
    tx = (px - ix)[None, :, None].astype(np.float32)
    ix = ix.astype(np.intp)
    # (C order: _add_sun writes the disc through a flat view)
    img = np.ascontiguousarray(np.take(by_row, np.clip(ix, 0, TABLE_W - 1), axis=1))
    img *= 1 - tx
    img += by_row[:, np.clip(ix + 1, 0, TABLE_W - 1)] * tx
    np.maximum(img, 0.0, out=img)
    done = np.zeros((height, width), bool)
    if sky.sun_disc and sky.sun_intensity > 0:
        done = _add_sun(sky, img, width, height, m, sun_samples, chain)
    if chain is not None:
        img[~done] = chain(img[~done])
    return img.astype(np.float32)


_ROW_POINTS = 64                  # elevations per averaged row of a 2048-row map (0.0014 degrees apart)


def _rows_of_table(table, y):
    """(len(y), TABLE_W, 3) float32: the table blended between its rows at table coordinates y
    (Cycles' bilinear read, the row part)."""
    py = np.asarray(y) * TABLE_H - 0.5
    iy = np.floor(py)
    ty = (py - iy)[:, None, None]
    iy = iy.astype(np.intp)
    return (table[np.clip(iy, 0, TABLE_H - 1)] * (1 - ty)
            + table[np.clip(iy + 1, 0, TABLE_H - 1)] * ty).astype(np.float32)


def _add_sun(sky, img, width, height, m, n, chain=None):
    """Adds the sun disc's light to the texels it touches, each texel getting the disc's
    integral over it divided by its solid angle, so the map carries the disc's whole light at
    any elevation and size; with a chain, each point's sky + sun goes through it. A disc up to
    _SMALL_DISC texels across is integrated around the sun (_deposit_disc), a larger one per
    texel (_grid_disc). Returns the (height, width) mask of the texels it set."""
    if sky.diameter <= _SMALL_DISC * np.pi / height:
        return _deposit_disc(sky, img, width, height, m, chain)
    return _grid_disc(sky, img, width, height, m, n, chain)


_SMALL_DISC = 4          # texels across: below this the disc's points are placed around the sun
_DISC_POINTS = 512       # per side of the stratified grid over the disc (cos of the angle x azimuth)
# The environment light blends the map bilinearly with REPEAT in v (lights/environment.py): above
# a polar row's centre it blends toward the opposite pole's row, so that row's value covers, by
# the tents' integral x sin theta, 25/24 of its own solid angle on its side (and 1/24 at the
# other pole; interior rows exactly theirs). The disc's share of the polar rows is scaled by
# 24/25 so the light the renderer draws from the sun's side is the disc's (a sun at the zenith
# had lit the scene 1.5% bright with the map itself exact)
_POLAR_ROW = 24.0 / 25.0


def _polar_rows(rows, height):
    return np.where((rows == 0) | (rows == height - 1), _POLAR_ROW, 1.0)


def _disc_points(sky, k=_DISC_POINTS):
    """(directions (k * k, 3), their solid angles (k * k,)) stratified over the disc's cone,
    uniform in solid angle about the sun: the points of a midpoint rule for its integral."""
    sun = sky.sun_direction()
    half = sky.diameter / 2
    one_minus_cos = 2.0 * np.sin(half / 2) ** 2          # 1 - cos(half) without cancellation
    t = one_minus_cos * (np.arange(k) + 0.5) / k         # 1 - cos(angle from the sun)
    cos_a, sin_a = 1.0 - t, np.sqrt(t * (2.0 - t))
    psi = 2.0 * np.pi * (np.arange(k) + 0.5) / k
    a = np.cross(sun, [1.0, 0.0, 0.0] if abs(sun[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(sun, a)
    ring = np.cos(psi)[:, None] * a + np.sin(psi)[:, None] * b                       # (k, 3)
    dirs = cos_a[:, None, None] * sun + sin_a[:, None, None] * ring[None, :, :]       # (k, k, 3)
    return dirs.reshape(-1, 3), np.full(k * k, 2.0 * np.pi * one_minus_cos / (k * k))


def _sun_rgb(sky, dirs, m, pixels):
    elevation = np.pi / 2 - np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))
    return np.maximum(_sun_xyz(sky, dirs, elevation, pixels) @ m, 0.0)


def _row_solid_angles(width, height):
    """(height,) solid angle of one texel in each row (row 0 at the bottom): 2 pi / width x the
    row's span in z, as 2 sin(mean theta) sin(half its span) (no cancellation at the poles)."""
    lo, hi = (1.0 - (np.arange(height) + 1) / height) * np.pi, (1.0 - np.arange(height) / height) * np.pi
    return 2.0 * np.pi / width * 2.0 * np.sin((lo + hi) / 2) * np.sin((hi - lo) / 2)


def _deposit_disc(sky, img, width, height, m, chain):
    """A small disc: its stratified points each add their radiance x solid angle to the texel
    they fall in, divided by the texel's solid angle. The image then holds the disc's integral
    whatever its size, its elevation (near the pole it spans every column) or where it falls
    within a texel; a grid of points per texel had caught 0.91-1.07x of a sub-texel disc and
    1.12x of one at the zenith (weighting the rows' points alike, not by their solid angle)."""
    dirs, w = _disc_points(sky)
    light = _sun_rgb(sky, dirs, m, sky.sun_pixels())
    row = np.minimum((height * (1.0 - np.arccos(np.clip(dirs[:, 2], -1.0, 1.0)) / np.pi)).astype(np.intp),
                     height - 1)
    col = np.mod(np.floor((0.5 - np.arctan2(dirs[:, 1], dirs[:, 0]) / (2 * np.pi)) * width).astype(np.intp), width)
    texel = row * width + col
    flat = img.reshape(-1, 3)
    if chain is not None:
        # a texel is the mean of the chain over its solid angle: the sky's result, plus each
        # point's change of it weighted by the point's share of the texel
        sky_at = flat[texel]
        light = chain(sky_at + light) - chain(sky_at)
    acc = np.zeros((width * height, 3))
    np.add.at(acc, texel, light * w[:, None])
    hit = np.unique(texel)
    added = acc[hit] * (_polar_rows(hit // width, height) / _row_solid_angles(width, height)[hit // width])[:, None]
    flat[hit] = (flat[hit] if chain is None else chain(flat[hit])) + added
    done = np.zeros(width * height, bool)
    done[hit] = True
    return done.reshape(height, width)


def _grid_disc(sky, img, width, height, m, n, chain=None):
    """A larger disc: each texel it can touch gets its mean over n x n points uniform in solid
    angle (in azimuth and z: uniform in the row's height would weight a polar row's points
    alike where their solid angles differ, by sin theta), fewer for a large disc, then every
    texel is scaled by the disc's integral over the points' (the rim's texels catch a varying
    share of it). With a chain, each point's sky + sun goes through it before the mean."""
    sun = sky.sun_direction()
    half = sky.diameter / 2
    theta_s = np.arccos(np.clip(sun[2], -1.0, 1.0))
    lo, hi = max(theta_s - half, 0.0), min(theta_s + half, np.pi)
    rows = np.arange(max(int(np.floor((1.0 - hi / np.pi) * height)) - 1, 0),
                     min(int(np.ceil((1.0 - lo / np.pi) * height)) + 1, height))
    s_min = min(np.sin(lo), np.sin(hi))         # the disc's widest azimuth span is at its polar end
    if s_min <= np.sin(half) * 1.001:
        cols = np.arange(width)
    else:
        u_s = 0.5 - np.arctan2(sun[1], sun[0]) / (2 * np.pi)
        du = np.arcsin(np.sin(half) / s_min) / (2 * np.pi)
        cols = np.unique(np.mod(np.arange(int(np.floor((u_s - du) * width)) - 1,
                                          int(np.ceil((u_s + du) * width)) + 1), width))
    done = np.zeros((height, width), bool)
    if not len(rows):
        return done
    n = int(np.clip(np.sqrt(2e6 / (len(rows) * len(cols))), 1, n))
    off = (np.arange(n) + 0.5) / n
    uu = (cols[:, None] + off[None, :]) / width                          # (cols, n)
    z_lo, z_hi = -np.cos(rows / height * np.pi), -np.cos((rows + 1) / height * np.pi)
    vv_all = 1.0 - np.arccos(np.clip(z_lo[:, None] + (z_hi - z_lo)[:, None] * off[None, :], -1.0, 1.0)) / np.pi
    pixels = sky.sun_pixels()
    step = max(int(2e6 // (len(cols) * n * n)), 1)        # a disc of tens of degrees: by blocks of rows

    def points(r):
        dirs = _equirect_dirs(uu[None, :, None, :], vv_all[r:r + step][:, None, :, None])   # (rows, cols, n, n, 3)
        return _sun_rgb(sky, dirs, m, pixels)

    at = (rows[:, None], cols[None, :])
    means = np.concatenate([points(r).mean(axis=(2, 3)) for r in range(0, len(rows), step)])
    in_map = np.einsum('rcx,r->x', means, _row_solid_angles(width, height)[rows])
    dirs, w = _disc_points(sky)
    exact = w @ _sun_rgb(sky, dirs, m, pixels)
    scale = np.where(in_map > 0, exact / np.where(in_map > 0, in_map, 1.0), 1.0)
    polar = _polar_rows(rows, height)[:, None, None]
    if chain is None:
        img[at] += means * scale * polar
    else:
        for r in range(0, len(rows), step):
            block = (rows[r:r + step, None], cols[None, :])
            p = img[block][:, :, None, None, :] + points(r) * scale * polar[r:r + step, :, :, None, None]
            img[block] = chain(p.reshape(-1, 3)).reshape(p.shape).mean(axis=(2, 3))
    done[at] = True
    return done
