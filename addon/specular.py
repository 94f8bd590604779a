"""The Principled BSDF's layers (and the Glossy and Metallic BSDFs) as a diffuse renderer can
keep them: their albedos per view cosine and averaged over view directions.

In Cycles (svm/closure.h, Principled) a dielectric GGX layer of roughness r (alpha = r^2) lies
over the diffuse base; at a view cosine mu it reflects E(mu) = int f_spec cos dw_i and the base
below is weighted by 1 - max over channels of E(mu) (closure_layering_weight). Its Fresnel is
the generalised Schlick form with the real dielectric curve: F = f0 t + (1 - f0 t) s, with
s = (F(eta) - F0) / (1 - F0), f0 = F0(eta) and t the Specular Tint; Specular IOR Level l moves
F0 to 2 l F0 (eta follows; l = 0: no layer). The metal's Fresnel is F82-tint, the coat's the
dielectric's; with Multiscatter GGX (and always for the coat) Cycles compensates the energy
single scattering loses (microfacet_ggx_preserve_energy). A diffuse material has one albedo, so
the export stacks the layers per view cosine (principled.py) and averages over view directions
weighted by cos (as fresnel.py does for Fresnel nodes): under uniform light an orthographic view
of a sphere then has Cycles' mean (tests/parity/test_specular.py). The albedos are integrated
by quadrature over the half vector (height-correlated Smith G2); they match what Cycles renders
(0.060 at roughness 0.5, IOR 1.5, against the smooth 0.092). Pure numpy, no Blender.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .fresnel import fresnel_dielectric_cos


def _gauss(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


# view cosines (weight 2 mu), the half vector's GGX-distributed polar variable xi and azimuth:
# ~1.3 ms per (roughness, IOR), within 0.2% of a grid 4x as fine each way (Fresnel albedo)
MU, _W_MU = _gauss(32)
_XI, _W_XI = _gauss(48)
_PHI = (np.arange(32) + 0.5) / 32 * 2.0 * np.pi
# the glass's refraction at roughness 1 needs a finer grid (its albedo within 0.05% of one 2x
# as fine each way; 0.25% dark on this one)
_XI_G, _W_XI_G = _gauss(192)
_PHI_G = (np.arange(128) + 0.5) / 128 * 2.0 * np.pi
# a per-view-cosine quantity (..., len(MU)) @ VIEW: its average over view directions weighted by cos
VIEW = 2.0 * MU * _W_MU


def view_table(table, rows, mu) -> np.ndarray:
    """(k,) float32: rows `rows` (k,) of a table of per-view-cosine values (m, len(MU)) read at
    the view cosines mu (k,), linearly between MU's nodes (held beyond the first and last)."""
    mu = np.asarray(mu, np.float64)
    j = np.clip(np.searchsorted(MU, mu), 1, len(MU) - 1)
    t = np.clip((mu - MU[j - 1]) / (MU[j] - MU[j - 1]), 0.0, 1.0)
    return (table[rows, j - 1] * (1.0 - t) + table[rows, j] * t).astype(np.float32)


def f0_from_ior(eta):
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def _half_vectors(alpha: float, beckmann: bool = False, xi=None, phi=None):
    """The microfacet half vectors of the (MU, xi, phi) quadrature (default _XI, _PHI): (mu_o,
    cos theta_h, wo.h, the reflected direction's z), each broadcasting to (len(MU), len(xi),
    len(phi)); h is taken with density D(h) cos(theta_h) (GGX: tan^2 theta_h = alpha^2 xi /
    (1 - xi); Beckmann: -alpha^2 log(1 - xi)), wo = (sin, 0, mu_o)."""
    mo = MU[:, None, None]
    so = np.sqrt(1.0 - mo * mo)
    xi = (_XI if xi is None else xi)[None, :, None]
    t2 = -alpha * alpha * np.log1p(-xi) if beckmann else alpha * alpha * xi / (1.0 - xi)
    ch = 1.0 / np.sqrt(1.0 + t2)
    sh = np.sqrt(t2) * ch
    oh = so * sh * np.cos(_PHI if phi is None else phi) + mo * ch
    return mo, ch, oh, 2.0 * oh * ch - mo


@lru_cache(maxsize=256)
def _ggx_dielectric(alpha: float, eta: float) -> tuple:
    """Per view cosine MU, the GGX reflection albedo without Fresnel (F = 1) and with the
    dielectric Fresnel of eta: (E, EF), each (len(MU),). The half vector h is taken with
    density D(h) cos(theta_h) (tan^2 theta_h = alpha^2 xi / (1 - xi)); per h the reflected
    direction contributes F G2 (wo.h) / (mu_o cos theta_h)."""
    mo, ch, oh, wiz = _half_vectors(alpha)

    def smith_lambda(c):
        c = np.clip(c, 1e-9, 1.0)
        return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - c * c) / (c * c)) - 1.0)

    g2 = 1.0 / (1.0 + smith_lambda(mo) + smith_lambda(wiz))
    per_h = np.where((wiz > 0.0) & (oh > 0.0), g2 * oh / (mo * ch), 0.0)
    w = _W_XI[None, :, None] / len(_PHI)
    e1 = (per_h * w).sum(axis=(1, 2))
    ef = (per_h * fresnel_dielectric_cos(np.clip(oh, 0.0, 1.0), eta) * w).sum(axis=(1, 2))
    return e1, ef


def _ggx_averages(alpha: float, eta: float) -> tuple[float, float]:
    """(E1, EF): _ggx_dielectric's two albedos averaged over view directions (weighted by cos)."""
    e1, ef = _ggx_dielectric(alpha, eta)
    return float(VIEW @ e1), float(VIEW @ ef)


def fresnel_dielectric_fss(eta: float) -> float:
    """Cycles' fit of the dielectric Fresnel averaged over incident directions (weighted by cos;
    bsdf_util.h fresnel_dielectric_Fss, after Kulla and Conty)."""
    if eta < 1.0:
        return 0.997118 + eta * (0.1014 - eta * (0.965241 + eta * 0.130607))
    return (eta - 1.0) / (4.08567 + 1.00071 * eta)


def cycles_ior(ior) -> float:
    """An IOR as Cycles reads it, fmaxf(ior, 1e-5f): NaN (fmaxf returns the number) and
    anything below 1e-5 become 1e-5."""
    ior = float(ior)
    return 1e-5 if np.isnan(ior) else max(ior, 1e-5)


def _layer_setup(roughness, ior, level, tint):
    """(r, f0, eta, f0 x tint (3, 1)) of a Principled specular layer, or None without one
    (Specular IOR Level 0, IOR 1, or a black tint): Specular IOR Level l moves F0 to 2 l F0
    and eta with it (Cycles' ior_from_F0; below 1 where the IOR is)."""
    tint = np.clip(np.nan_to_num(np.asarray(tint, np.float64)[:3]), 0.0, None)
    ior = cycles_ior(ior)                          # front faces: eta = IOR
    f0 = min(f0_from_ior(ior) * 2.0 * max(float(level), 0.0), 1.0 - 1e-6)
    if not f0 > 0.0 or not tint.any():
        return None
    eta = (1.0 + np.sqrt(f0)) / (1.0 - np.sqrt(f0))   # Cycles' ior_from_F0 (level 0.5: the IOR)
    if ior < 1.0:
        eta = 1.0 / eta
    r = min(max(float(roughness), 0.0), 1.0) if np.isfinite(roughness) else 0.0
    return r, f0, float(eta), np.minimum(f0 * tint, 1.0)[:, None]


def _fss(eta, f0, ft):
    """Cycles' average Fresnel of the generalised Schlick with the real dielectric curve
    (bsdf_microfacet_setup_fresnel_generalized_schlick): f0 t + (1 - f0 t) s, s where the
    dielectric's average lies between F0 and 1."""
    s = min(max((fresnel_dielectric_fss(float(eta)) - f0) / (1.0 - f0), 0.0), 1.0)
    return ft + (1.0 - ft) * s


def layer_albedo_mu(roughness: float, ior: float, level: float, tint, multiscatter: bool = True) -> np.ndarray:
    """Per channel and view cosine (3, len(MU)), the specular layer's albedo (see the top);
    zeros without a layer (Specular IOR Level 0, IOR 1, or a black tint). With multiscatter
    (the Principled's Multiscatter GGX; a coat always), Cycles' energy compensation, with the
    generalised Schlick's average Fresnel (bsdf_microfacet_setup_fresnel_generalized_schlick)."""
    setup = _layer_setup(roughness, ior, level, tint)
    if setup is None:
        return np.zeros((3, len(MU)))
    r, f0, eta, ft = setup
    e1, ef = _ggx_dielectric(r * r, eta)
    # s = (F - f0) / (1 - f0) integrates to (EF - f0 E1) / (1 - f0), per view cosine
    es = (ef - f0 * e1) / (1.0 - f0)
    single = ft * e1 + (1.0 - ft) * es
    return _compensated(single, e1, _fss(eta, f0, ft), multiscatter)


@lru_cache(maxsize=256)
def _schlick_s(alpha: float, eta: float) -> np.ndarray:
    """Per view cosine MU, Cycles' ggx_gen_schlick_ior_s table (cycles_precompute.cpp) for
    eta > 1: where the Fresnel of eta lies between F0 and 1, s = (F - F0) / (1 - F0), averaged
    over GGX's visible normals (pdf G1(wo) D (wo.h) / mu_o; a reflection below the horizon
    counts 0). Integrated as _ggx_dielectric, normalised by the quadrature's visible-normal
    total (within 1% of 1 at grazing view)."""
    mo, ch, oh, wiz = _half_vectors(alpha)
    visible = np.where(oh > 0.0, oh / (mo * ch), 0.0) * (_W_XI[None, :, None] / len(_PHI))
    f0 = f0_from_ior(eta)
    s = np.clip((fresnel_dielectric_cos(np.clip(oh, 0.0, 1.0), eta) - f0) / (1.0 - f0), 0.0, 1.0)
    return (np.where(wiz > 0.0, visible * s, 0.0).sum(axis=(1, 2)) / visible.sum(axis=(1, 2)))


def layer_estimate_mu(roughness: float, ior: float, level: float, tint, multiscatter: bool = True) -> np.ndarray:
    """Per channel and view cosine (3, len(MU)), what Cycles takes the specular layer's
    albedo to be when it dims the layers below (bsdf_microfacet_estimate_albedo): f0 t +
    (1 - f0 t) s with s from its table (_schlick_s) read at z = sqrt(|eta - 1| / (eta + 1)),
    i.e. at eta or 1 / eta, a table that assumes a lobe of albedo 1; with multiscatter times
    the energy compensation's darkening (E + Fms (1 - E)). Not the layer's albedo: without
    compensation (GGX) the lobe loses 1 - E (a dim 2.8% too bright at roughness 1 over base
    0.8, had the true albedo dimmed it), and below IOR 1 the true albedo's total internal
    reflection (0.545 at IOR 0.7) dims far more than the table's 0.08."""
    setup = _layer_setup(roughness, ior, level, tint)
    if setup is None:
        return np.zeros((3, len(MU)))
    r, f0, eta, ft = setup
    e1, _ = _ggx_dielectric(r * r, eta)
    est = ft + (1.0 - ft) * _schlick_s(r * r, max(eta, 1.0 / eta))[None, :]
    return _compensated(est * e1, e1, _fss(eta, f0, ft), True) if multiscatter else est


@lru_cache(maxsize=256)
def _glass_lobes(alpha: float, eta: float, beckmann: bool = False) -> tuple:
    """Per view cosine MU, a rough dielectric's (Cycles' glass, GGX or Beckmann) single
    scattering albedos in parts linear in the Fresnel's s = (F(eta) - F0) / (1 - F0) (1 under
    total internal reflection): (R1, RS, T1, TS), each (len(MU),), the reflection with weight
    1 and s, the refraction with weight 1 and s. Per half vector h (density D(h) cos theta_h,
    as _ggx_moments) both lobes contribute G2 (wo.h) / (mu_o cos theta_h) (Cycles' BTDF carries
    eta^2, so its refraction integrates as its reflection), the refraction where eta lets light
    through and it leaves below."""
    mo, ch, oh, _ = _half_vectors(alpha, beckmann, _XI_G, _PHI_G)
    oh = np.clip(oh, -1.0, 1.0)
    wrz = 2.0 * oh * ch - mo
    ct2 = 1.0 - (1.0 - oh * oh) / (eta * eta)
    wtz = (oh / eta - np.sqrt(np.maximum(ct2, 0.0))) * ch - mo / eta

    def smith_lambda(c):
        c = np.clip(np.abs(c), 1e-9, 1.0)
        a2t2 = alpha * alpha * (1.0 - c * c) / (c * c)
        if not beckmann:
            return 0.5 * (np.sqrt(1.0 + a2t2) - 1.0)
        a = 1.0 / np.sqrt(np.maximum(a2t2, 1e-30))
        return np.where(a2t2 < 0.39, 0.0, ((0.396 * a - 1.259) * a + 1.0) / ((2.181 * a + 3.535) * a))

    w = np.where(oh > 0.0, oh / (mo * ch), 0.0) * (_W_XI_G[None, :, None] / len(_PHI_G))
    f0 = f0_from_ior(eta)
    s = np.clip((fresnel_dielectric_cos(np.clip(oh, 0.0, 1.0), eta) - f0) / (1.0 - f0), 0.0, 1.0)
    r = np.where(wrz > 0.0, w / (1.0 + smith_lambda(mo) + smith_lambda(wrz)), 0.0)
    t = np.where((ct2 > 0.0) & (wtz < 0.0), w / (1.0 + smith_lambda(mo) + smith_lambda(wtz)), 0.0)
    return tuple(x.sum(axis=(1, 2)) for x in (r, r * s, t, t * s))


def glass_albedo_mu(roughness: float, ior: float, tint=(1.0, 1.0, 1.0), multiscatter: bool = True,
                    beckmann: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(reflected, transmitted), each per channel and view cosine (3, len(MU)), of Cycles'
    rough glass seen from outside (eta = IOR, as Cycles fmaxf(IOR, 1e-5)): its generalised
    Schlick Fresnel F = f0 t + (1 - f0 t) s (f0 = F0(IOR) x the tint t, the Principled's
    Specular Tint; white for the Glass BSDF) reflects F and lets 1 - F through, per channel.
    GGX and Beckmann (beckmann) scatter once and lose the rest (a white GGX shell of roughness
    1 passes 0.81 in Cycles); Multiscatter GGX divides both by the untinted glass's albedo E
    (microfacet_ggx_preserve_energy's 1 / E from its ggx_glass_E table; its darkening for a
    tinted transmission is not kept)."""
    eta = cycles_ior(ior)
    tint = np.clip(np.nan_to_num(np.asarray(tint, np.float64)[:3]), 0.0, None)
    f0 = min(f0_from_ior(eta), 1.0 - 1e-6)
    ft = np.minimum(f0 * tint, 1.0)[:, None]
    r = min(max(float(roughness), 0.0), 1.0) if np.isfinite(roughness) else 0.0
    r1, rs, t1, ts = _glass_lobes(max(r * r, 1e-4), eta, bool(beckmann) and not multiscatter)
    reflect = ft * r1 + (1.0 - ft) * rs
    through = (1.0 - ft) * (t1 - ts)
    if multiscatter and not beckmann:
        e = f0 * r1 + (1.0 - f0) * rs + (1.0 - f0) * (t1 - ts)
        reflect, through = reflect / e, through / e
    return reflect, through


def layer_albedo(roughness: float, ior: float, level: float, tint, multiscatter: bool = True) -> np.ndarray:
    """Per channel, layer_albedo_mu averaged over view directions."""
    return layer_albedo_mu(roughness, ior, level, tint, multiscatter) @ VIEW


def coat_tint_mu(tint, coat_ior: float) -> np.ndarray:
    """Per channel and view cosine (3, len(MU)), Cycles' Coat Tint absorption of the layers
    below the coat, tint^(1 / cos_t) with cos_t the refracted view cosine in the coat (tint is
    the transmittance at normal incidence)."""
    tint = np.clip(np.asarray(tint, np.float64)[:3], 0.0, None)
    eta = max(float(coat_ior), 1.0)
    cos_t = np.sqrt(1.0 - (1.0 - MU * MU) / (eta * eta))
    return tint[:, None] ** (1.0 / cos_t)[None, :]


def coat_tint_average(tint, coat_ior: float) -> np.ndarray:
    """Per channel, coat_tint_mu averaged over view directions weighted by cos."""
    return coat_tint_mu(tint, coat_ior) @ VIEW


@lru_cache(maxsize=256)
def _ggx_moments(alpha: float, beckmann: bool = False) -> tuple:
    """Per view cosine MU, the microfacet reflection albedo without Fresnel E and its moments
    with the Schlick weights s^5 and cos s^6 (s = 1 - wo.h): (E, S5, S6), each (len(MU),).
    GGX, or with beckmann the Beckmann distribution and Cycles' rational approximation of its
    Smith Lambda (bsdf_microfacet.h)."""
    mo, ch, oh, wiz = _half_vectors(alpha, beckmann)

    def smith_lambda(c):
        c = np.clip(c, 1e-9, 1.0)
        a2t2 = alpha * alpha * (1.0 - c * c) / (c * c)
        if not beckmann:
            return 0.5 * (np.sqrt(1.0 + a2t2) - 1.0)
        a = 1.0 / np.sqrt(np.maximum(a2t2, 1e-30))
        return np.where(a2t2 < 0.39, 0.0, ((0.396 * a - 1.259) * a + 1.0) / ((2.181 * a + 3.535) * a))

    g2 = 1.0 / (1.0 + smith_lambda(mo) + smith_lambda(wiz))
    per_h = np.where((wiz > 0.0) & (oh > 0.0), g2 * oh / (mo * ch), 0.0) * (_W_XI[None, :, None] / len(_PHI))
    s = 1.0 - np.clip(oh, 0.0, 1.0)
    s5 = s ** 5
    return per_h.sum(axis=(1, 2)), (per_h * s5).sum(axis=(1, 2)), (per_h * (1.0 - s) * s5 * s).sum(axis=(1, 2))


def _compensated(single, e, fss, compensate):
    """Per view cosine, the albedo single (channels x mu) with Cycles' multiple-scattering
    energy compensation (microfacet_ggx_preserve_energy) for the average Fresnel fss (channels
    x 1); single-scattering only without compensate."""
    if not compensate:
        return single
    e_avg = float(VIEW @ e)
    fms = fss * e_avg / (1.0 - fss * (1.0 - e_avg))
    return single * (1.0 + fms * (1.0 - e) / e)


def metal_albedo(roughness: float, f0, tint, multiscatter: bool = True, beckmann: bool = False) -> np.ndarray:
    """Per channel, metal_albedo_mu averaged over view directions (weighted by cos)."""
    return metal_albedo_mu(roughness, f0, tint, multiscatter, beckmann) @ VIEW


def metal_albedo_mu(roughness: float, f0, tint, multiscatter: bool = True, beckmann: bool = False) -> np.ndarray:
    """Per channel and view cosine (3, len(MU)), the albedo of Cycles' Principled metal (and
    of the Metallic BSDF in F82 mode): GGX reflection with the F82-tint
    Fresnel (F0 = base colour, tint = Specular Tint / Edge Tint; bsdf_util.h fresnel_f82tint_B
    / fresnel_f82) and, with multiscatter (Multiscatter GGX), the energy compensation of
    microfacet_ggx_preserve_energy: single-scattering albedo x (1 + Fms (1 - E) / E), Fms from
    the average Fresnel as Kulla and Conty's multiple-scattering Fresnel."""
    f0 = np.clip(np.asarray(f0, np.float64)[:3], 0.0, 1.0)[:, None]
    tint = np.clip(np.asarray(tint, np.float64)[:3], 0.0, 1.0)[:, None]
    r = min(max(float(roughness), 0.0), 1.0)
    e, s5, s6 = _ggx_moments(max(r * r, 1e-4), beckmann)
    f = 6.0 / 7.0
    b = (f0 + (1.0 - f0) * f ** 5) * (7.0 / f ** 6) * (1.0 - tint)
    single = f0 * e + (1.0 - f0) * s5 - b * s6
    return _compensated(single, e, f0 + (1.0 - f0) / 21.0 - b / 126.0, multiscatter)


def conductor_f82(n, k) -> tuple[np.ndarray, np.ndarray]:
    """(F0, F82 tint) per channel of the F82-tint Fresnel that meets a conductor's (complex IOR
    n + ik, the Metallic BSDF's Physical Conductor mode) at normal incidence, at cos 1/7 (where
    the F82 tint is defined: F there = Schlick's x tint) and at grazing; in between it stands
    in for the conductor's curve (copper at roughness 0.3: albedo within 0.2% of Cycles' seen
    head-on)."""
    n = np.nan_to_num(np.asarray(n, np.float64)[:3])
    k = np.nan_to_num(np.asarray(k, np.float64)[:3])
    eta = np.maximum(n, 1e-5) + 1j * np.maximum(k, 0.0)

    def fresnel(c):
        cos_t = np.sqrt(1.0 - (1.0 - c * c) / (eta * eta))
        rs = (c - eta * cos_t) / (c + eta * cos_t)
        rp = (eta * c - cos_t) / (eta * c + cos_t)
        return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)
    f0 = np.clip(fresnel(1.0), 0.0, 1.0)
    schlick = f0 + (1.0 - f0) * (6.0 / 7.0) ** 5
    return f0, np.clip(fresnel(1.0 / 7.0) / schlick, 0.0, 1.0)


def glossy_albedo(roughness: float, color, multiscatter: bool = True, beckmann: bool = False) -> np.ndarray:
    """Per channel, the albedo of Cycles' Glossy BSDF averaged over view directions: GGX
    reflection of constant Fresnel = its colour, with the energy compensation for Multiscatter
    GGX (nonlinear in the colour: 0.974 x a colour of 0.8 at roughness 0.5, 0.926 x 0.4) or
    without it for GGX (the colour x the lobe's average albedo, 0.882 at roughness 0.5) and
    Beckmann (beckmann; no compensation in Cycles either). A colour above 1 is its Fresnel as
    it is, as in Cycles (1.5 at roughness 0.5: 1.607; clipped at 1 it had been 1.5)."""
    c = np.clip(np.asarray(color, np.float64)[:3], 0.0, None)[:, None]
    r = min(max(float(roughness), 0.0), 1.0)
    e, _, _ = _ggx_moments(max(r * r, 1e-4), beckmann)
    return np.nan_to_num(_compensated(c * e, e, c, multiscatter) @ VIEW, nan=0.0, posinf=0.0, neginf=0.0)
