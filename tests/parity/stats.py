"""Statistical comparison of two renderers' images, from several independently seeded renders
of each (numpy only; no Blender).

Input: per-seed images a (Ma, H, W, C) and b (Mb, H, W, C). Each seed's image is one draw of
that renderer's pixel estimator, so per pixel and channel the seed mean estimates the expected
value and the spread over seeds its variance, whatever the sampler (Cycles' scrambled Sobol,
DACRT's random numbers) and however pixels are correlated within one image.

Per pixel and channel, a two-sample Welch t-test: t = (mean_b - mean_a) / sqrt(va + vb + vf)
with va = var_a / Ma, vb = var_b / Mb (unbiased sample variances over seeds), vf a known
float-rounding term ((FLOAT_REL * |mean|)^2, so that pixels both renderers see as exactly
constant, e.g. the sky, compare with a relative tolerance instead of dividing by zero), and
Welch-Satterthwaite degrees of freedom (vf counts as known, infinite dof). The p-value comes
from Student's t distribution, not the normal one: at the Sidak level of a 64x48 image
(~8e-7), a z-test on variances estimated from 8 seeds rejects ~2000x too often, from 32
seeds ~30x.

All H*W*C tests form one family: Sidak's per-test level alpha = 1 - (1 - family_alpha)^(1/n)
(mitsuba-blender's tests/fixtures does the same per pixel). A pixel passes when all its
channels pass. The same test runs on the means of k x k pixel tiles (their own Sidak family):
a tile mean has ~k times less noise, so a bias spread over a region (a light's falloff, a cone
edge) shows there long before single pixels can tell it from noise.

Verdict (`Comparison.passed`): every channel's image mean agrees within `mean_tol`, and at
least `min_pass` of the pixels and of the tiles pass.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FLOAT_REL = 1e-4     # relative tolerance for pixels without any variance (float32 rounding)
_CF_ITERATIONS = 300
_TINY = 1e-300


# ------------------------------------------------------------------------------------------
# Student's t distribution


def _log_beta(a, b):
    lgamma = np.vectorize(math.lgamma, otypes=[np.float64])
    return lgamma(a) + lgamma(b) - lgamma(a + b)


def _betacf(a, b, x):
    """Continued fraction of the incomplete beta function (modified Lentz), vectorised;
    converges fast for x < (a + 1) / (a + b + 2)."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = np.ones_like(x)
    d = 1.0 - qab * x / qap
    d = np.where(np.abs(d) < _TINY, _TINY, d)
    d = 1.0 / d
    h = d.copy()
    for m in range(1, _CF_ITERATIONS + 1):
        m2 = 2 * m
        for aa in (m * (b - m) * x / ((qam + m2) * (a + m2)),
                   -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = np.where(np.abs(d) < _TINY, _TINY, d)
            c = 1.0 + aa / c
            c = np.where(np.abs(c) < _TINY, _TINY, c)
            d = 1.0 / d
            delta = d * c
            h *= delta
        if np.all(np.abs(delta - 1.0) < 1e-15):
            break
    return h


def betainc(a, b, x):
    """Regularized incomplete beta function I_x(a, b) for a, b > 0, 0 <= x <= 1 (arrays)."""
    a, b, x = np.broadcast_arrays(*(np.asarray(v, np.float64) for v in (a, b, x)))
    out = np.empty(x.shape)
    out[x <= 0] = 0.0
    out[x >= 1] = 1.0
    inner = (x > 0) & (x < 1)
    if not inner.any():
        return out
    a, b, x = a[inner], b[inner], x[inner]
    log_front = a * np.log(x) + b * np.log1p(-x) - _log_beta(a, b)
    direct = x < (a + 1.0) / (a + b + 2.0)
    res = np.empty(x.shape)
    if direct.any():
        i = direct
        res[i] = np.exp(log_front[i]) * _betacf(a[i], b[i], x[i]) / a[i]
    if (~direct).any():
        i = ~direct
        res[i] = 1.0 - np.exp(log_front[i]) * _betacf(b[i], a[i], 1.0 - x[i]) / b[i]
    out[inner] = res
    return out


def t_two_sided_p(t, dof):
    """Two-sided p-value P(|T| >= |t|) of Student's t with `dof` degrees of freedom (any
    positive real, np.inf for the normal limit)."""
    t, dof = np.broadcast_arrays(np.abs(np.asarray(t, np.float64)), np.asarray(dof, np.float64))
    p = np.empty(t.shape)
    normal = ~np.isfinite(dof) | (dof > 1e7)
    if normal.any():
        erfc = np.vectorize(math.erfc, otypes=[np.float64])
        p[normal] = erfc(t[normal] / math.sqrt(2.0))
    student = ~normal
    if student.any():
        tt, nu = t[student], dof[student]
        p[student] = betainc(nu / 2.0, np.full_like(nu, 0.5), nu / (nu + tt * tt))
    p[np.isinf(t)] = 0.0
    return p


def t_critical(alpha, dof):
    """|t| at which t_two_sided_p equals alpha (bisection in t, vectorised over dof)."""
    dof = np.asarray(dof, np.float64)
    lo, hi = np.zeros(dof.shape), np.full(dof.shape, 1.0)
    while True:              # bracket: grow hi until p(hi) < alpha
        small = t_two_sided_p(hi, dof) > alpha
        if not small.any():
            break
        hi = np.where(small, hi * 4.0, hi)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        above = t_two_sided_p(mid, dof) > alpha
        lo, hi = np.where(above, mid, lo), np.where(above, hi, mid)
    return 0.5 * (lo + hi)


def sidak(family_alpha, tests):
    """Per-test level keeping the chance of any false rejection among `tests` independent
    tests at family_alpha."""
    return -math.expm1(math.log1p(-family_alpha) / tests)


# ------------------------------------------------------------------------------------------
# Comparison


@dataclass
class Welch:
    """Element-wise Welch t-test of two stacks of draws (M, ...) -> arrays of shape (...)."""
    mean_a: np.ndarray
    mean_b: np.ndarray
    sigma: np.ndarray            # standard error of mean_b - mean_a (incl. the float term)
    dof: np.ndarray              # Welch-Satterthwaite degrees of freedom
    p: np.ndarray                # two-sided p-value

    @property
    def diff(self):
        return self.mean_b - self.mean_a

    def detectable(self, alpha):
        """Relative bias |diff| / |mean_a| at which each element would just fail at alpha;
        the median over elements that vary is the test's power on this data."""
        noisy = self.dof < np.inf
        ref = np.abs(self.mean_a)
        keep = noisy & (ref > 0)
        if not keep.any():
            return float('nan')
        dof, where = np.unique(np.round(self.dof[keep], 1), return_inverse=True)  # few distinct
        crit = t_critical(alpha, dof)[where.ravel()]
        return float(np.median(crit * self.sigma[keep] / ref[keep]))


def welch(a, b):
    """Welch t-test per element of draws a (Ma, ...) against b (Mb, ...)."""
    ma, mb = a.shape[0], b.shape[0]
    mean_a, mean_b = a.mean(axis=0), b.mean(axis=0)
    va = a.var(axis=0, ddof=1) / ma
    vb = b.var(axis=0, ddof=1) / mb
    vf = (FLOAT_REL * np.maximum(np.abs(mean_a), np.abs(mean_b))) ** 2
    var = va + vb + vf
    diff = mean_b - mean_a
    with np.errstate(divide='ignore', invalid='ignore'):
        t = np.where(var > 0, np.abs(diff) / np.sqrt(var), np.where(diff == 0, 0.0, np.inf))
        denom = va * va / (ma - 1) + vb * vb / (mb - 1)
        dof = np.where(denom > 0, var * var / denom, np.inf)
    return Welch(mean_a, mean_b, np.sqrt(var), dof, t_two_sided_p(t, dof))


def interior(mask):
    """(H, W) bool: the pixels whose 3x3 neighbourhood lies all in mask (the rows and columns
    wrap, as np.roll's), e.g. an object's pixels away from its silhouette."""
    inside = mask
    for ax in (0, 1):
        inside = inside & np.roll(inside, 1, ax) & np.roll(inside, -1, ax)
    return inside


def block_means(images, block):
    """(M, H, W, C) -> (M, H // block, W // block, C) means of block x block pixel tiles
    (a partial last row or column of tiles is dropped)."""
    m, h, w, c = images.shape
    hb, wb = h // block, w // block
    tiles = images[:, :hb * block, :wb * block].reshape(m, hb, block, wb, block, c)
    return tiles.mean(axis=(2, 4))


@dataclass
class Comparison:
    ratio: np.ndarray            # (C,) image mean per channel, b / a
    mean_a: np.ndarray           # (C,) image mean per channel, a (the reference)
    mean_z: np.ndarray           # (C,) z of the image-mean difference over seed-to-seed noise
    pixels: Welch                # (H, W, C)
    pixel_alpha: float           # per-test Sidak level over H*W*C tests
    pixel_pass: np.ndarray       # (H, W) all channels of the pixel pass
    blocks: Welch | None         # (H/k, W/k, C) the same test on k x k pixel tile means
    block_alpha: float
    block_pass: np.ndarray | None
    block: int
    mean_tol: float
    min_pass: float

    @property
    def pixel_pass_fraction(self) -> float:
        return float(self.pixel_pass.mean())

    @property
    def block_pass_fraction(self) -> float:
        return float(self.block_pass.mean()) if self.block_pass is not None else 1.0

    @property
    def means_agree(self) -> bool:
        return bool(np.all(np.abs(self.ratio - 1.0) <= self.mean_tol))

    @property
    def pixels_agree(self) -> bool:
        return self.pixel_pass_fraction >= self.min_pass

    @property
    def blocks_agree(self) -> bool:
        return self.block_pass_fraction >= self.min_pass

    @property
    def passed(self) -> bool:
        return self.means_agree and self.pixels_agree and self.blocks_agree

    def summary(self, names=("Cycles", "DACRT")) -> str:
        ch = "RGBA"
        ratios = ", ".join(f"{ch[i]} {r:.4f} (z {z:+.1f})"
                           for i, (r, z) in enumerate(zip(self.ratio, self.mean_z)))
        lines = [f"channel mean ratio {names[1]}/{names[0]}: {ratios}"
                 f"{'' if self.means_agree else f'  <- beyond {100 * self.mean_tol:g}%'}",
                 self._level("pixels", self.pixels, self.pixel_pass, self.pixel_alpha, 1)]
        if self.blocks is not None:
            lines.append(self._level(f"{self.block}x{self.block} blocks", self.blocks,
                                     self.block_pass, self.block_alpha, self.block))
        return "\n".join(lines)

    def _level(self, what, test, ok, alpha, scale):
        rgb = slice(0, min(3, test.p.shape[-1]))
        colour = Welch(test.mean_a[..., rgb], test.mean_b[..., rgb], test.sigma[..., rgb],
                       test.dof[..., rgb], test.p[..., rgb])
        text = (f"{what} passing: {100 * ok.mean():.2f}% ({int((~ok).sum())} of {ok.size} fail, "
                f"need >= {100 * self.min_pass:g}%; per-test alpha {alpha:.1e}; median detectable "
                f"bias {100 * colour.detectable(alpha):.1f}%)")
        if (~ok).any():
            ys, xs = np.nonzero(~ok)
            with np.errstate(divide='ignore', invalid='ignore'):
                ratio = np.where(test.mean_a != 0, test.mean_b / test.mean_a, np.nan)
            worst = np.argsort(test.p[ys, xs].min(axis=1))[:6]
            text += (f"\n  failing {what}: x {xs.min() * scale}..{(xs.max() + 1) * scale - 1}, "
                     f"y {ys.min() * scale}..{(ys.max() + 1) * scale - 1} (pixels, y up from the "
                     f"bottom); worst (x, y: ratio per channel): " + "; ".join(
                         f"{xs[i] * scale}, {ys[i] * scale}: "
                         + "/".join(f"{r:.3g}" for r in ratio[ys[i], xs[i]]) for i in worst))
        return text


def compare(a, b, family_alpha=0.01, min_pass=0.99, mean_tol=0.01, block=4):
    """Compare per-seed images a (Ma, H, W, C), the reference, with b (Mb, H, W, C).

    Gates: channel means within mean_tol; >= min_pass of the pixels pass the Sidak-corrected
    Welch test; and (block > 1) >= min_pass of the block x block tiles pass the same test on
    tile means, which is ~block times more sensitive to a bias spread over a region."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if a.ndim != 4 or b.ndim != 4 or a.shape[1:] != b.shape[1:]:
        raise ValueError(f"need (seeds, H, W, C) stacks of the same image size, got {a.shape} "
                         f"and {b.shape}")
    if a.shape[0] < 2 or b.shape[0] < 2:
        raise ValueError(f"need at least 2 seeds per renderer for a variance, got "
                         f"{a.shape[0]} and {b.shape[0]}")
    for name, x in (("a", a), ("b", b)):
        bad = ~np.isfinite(x)
        if bad.any():
            raise ValueError(f"images {name} contain {int(bad.sum())} NaN or infinite values")

    pixels = welch(a, b)
    pixel_alpha = sidak(family_alpha, pixels.p.size)
    pixel_pass = (pixels.p > pixel_alpha).all(axis=-1)

    blocks, block_alpha, block_pass = None, 0.0, None
    if block > 1 and a.shape[1] >= block and a.shape[2] >= block:
        blocks = welch(block_means(a, block), block_means(b, block))
        block_alpha = sidak(family_alpha, blocks.p.size)
        block_pass = (blocks.p > block_alpha).all(axis=-1)

    img_a, img_b = a.mean(axis=(1, 2)), b.mean(axis=(1, 2))          # (M, C) per-seed means
    chan_a, chan_b = img_a.mean(axis=0), img_b.mean(axis=0)
    se = np.sqrt(img_a.var(axis=0, ddof=1) / a.shape[0] + img_b.var(axis=0, ddof=1) / b.shape[0])
    with np.errstate(divide='ignore', invalid='ignore'):
        ratio = np.where(chan_a != 0, chan_b / chan_a, np.where(chan_b == 0, 1.0, np.inf))
        mean_z = np.where(se > 0, (chan_b - chan_a) / se, 0.0)
    return Comparison(ratio=ratio, mean_a=chan_a, mean_z=mean_z, pixels=pixels,
                      pixel_alpha=pixel_alpha, pixel_pass=pixel_pass, blocks=blocks,
                      block_alpha=block_alpha, block_pass=block_pass, block=block,
                      mean_tol=mean_tol, min_pass=min_pass)
