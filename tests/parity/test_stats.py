"""The statistical test of stats.py on synthetic data (no Blender): Student's t p-values
against closed forms, calibration of the Welch test, and the verdict of `compare` on images
drawn from identical and from biased distributions, at the parity suite's own sizes
(32 seeds each, 64x48 RGBA)."""
import math

import numpy as np
import pytest

from . import stats

SEEDS, H, W = 32, 48, 64


def cauchy_p(t):                      # Student's t, 1 dof
    return 1 - 2 / math.pi * math.atan(t)


def t2_p(t):                          # 2 dof
    return 1 - t / math.sqrt(2 + t * t)


def t3_p(t):                          # 3 dof
    u = t / math.sqrt(3)
    return 1 - 2 / math.pi * (math.atan(u) + u / (1 + u * u))


@pytest.mark.parametrize("dof, exact", [(1, cauchy_p), (2, t2_p), (3, t3_p)])
def test_t_p_values_match_closed_forms(dof, exact):
    t = np.array([0.0, 0.3, 1.0, 2.5, 7.0, 40.0, 1e3])
    got = stats.t_two_sided_p(t, np.full(t.shape, float(dof)))
    want = np.array([exact(x) for x in t])
    assert np.allclose(got, want, rtol=1e-9, atol=1e-15)


def test_t_p_values_tend_to_normal_and_far_tail_is_accurate():
    t = np.array([0.5, 2.0, 5.0, 6.0])
    normal = np.array([math.erfc(x / math.sqrt(2)) for x in t])
    assert np.allclose(stats.t_two_sided_p(t, np.inf), normal, rtol=1e-12)
    assert np.allclose(stats.t_two_sided_p(t, 1e6), normal, rtol=1e-4)
    # far tail (where the Sidak level sits) with few dof: heavier than the normal tail
    assert stats.t_two_sided_p(6.0, 7.0) > 100 * math.erfc(6.0 / math.sqrt(2))
    # I_x(a, 1) = x^a is a closed form of the incomplete beta for any real a
    a = np.array([0.5, 3.7, 15.5])
    x = np.array([0.2, 0.5, 0.9])
    assert np.allclose(stats.betainc(a, np.ones(3), x), x ** a, rtol=1e-12)
    # symmetry I_x(a, b) = 1 - I_{1-x}(b, a), exercising both continued-fraction branches
    assert np.allclose(stats.betainc(2.5, 0.5, 0.3), 1 - stats.betainc(0.5, 2.5, 0.7), rtol=1e-12)


def test_t_critical_inverts_the_p_value():
    assert stats.t_critical(0.05, np.array([1.0, 10.0, np.inf])) == pytest.approx(
        [12.7062047, 2.2281389, 1.9599640], rel=1e-6)
    dof = np.array([5.0, 31.0, 62.0, np.inf])
    crit = stats.t_critical(8e-7, dof)
    assert np.allclose(stats.t_two_sided_p(crit, dof), 8e-7, rtol=1e-6)


def test_sidak_level():
    assert stats.sidak(0.01, 1) == pytest.approx(0.01)
    alpha = stats.sidak(0.01, 12288)
    assert (1 - alpha) ** 12288 == pytest.approx(0.99, rel=1e-12)
    assert alpha == pytest.approx(0.01 / 12288, rel=0.01)


def test_welch_is_calibrated_with_few_seeds_and_unequal_variances():
    """At a plain 1% level, the share of rejections under the null is ~1%, even with 6 and
    10 draws of very different spread (a z-test on those variances would reject far more)."""
    rng = np.random.default_rng(1)
    n = 100_000
    a = rng.normal(1.0, 0.05, (6, n))
    b = rng.normal(1.0, 0.20, (10, n))
    p = stats.welch(a, b).p
    assert 0.0085 < np.mean(p < 0.01) < 0.0115
    assert 0.085 < np.mean(p < 0.1) < 0.115
    # the same data shifted by 4 standard errors is rejected most of the time
    se = math.sqrt(0.05 ** 2 / 6 + 0.2 ** 2 / 10)
    assert np.mean(stats.welch(a, b + 4 * se).p < 0.01) > 0.6


# ------------------------------------------------------------------------------------------
# Synthetic renders: per seed, each pixel is the mean of `spp` skewed (exponential) samples
# around a smooth "scene" image, like a path tracer's pixel estimate.

def scene_image(rng):
    y, x = np.mgrid[0:H, 0:W] / np.array([H, W])[:, None, None]
    base = 0.3 + 1.5 * np.exp(-((x - 0.6) ** 2 + (y - 0.4) ** 2) * 6)
    img = np.stack([base * 0.9, base * 0.7, base * 0.5, np.ones_like(base)], axis=-1)
    img[:8, :, :3] = (0.25, 0.4, 0.7)         # a constant "sky": no variance at all
    return img


def draw(rng, image, seeds=SEEDS, spp=32, noise=1.0):
    """(seeds, H, W, 4): pixel = image x mean of spp Exp(1)-distributed samples (relative
    noise `noise`/sqrt(spp) per seed); rows 0..7 and alpha stay exact."""
    gamma = rng.gamma(spp / noise ** 2, noise ** 2 / spp, size=(seeds, H, W, 1))
    out = image[None] * gamma
    out[:, :8] = image[None, :8]
    out[..., 3] = image[..., 3]
    return out.astype(np.float32)


@pytest.mark.parametrize("seed", range(5))
def test_identical_distributions_pass(seed):
    rng = np.random.default_rng(seed)
    image = scene_image(rng)
    result = stats.compare(draw(rng, image), draw(rng, image))
    assert result.passed, result.summary()
    assert result.pixel_pass_fraction > 0.998
    assert np.allclose(result.ratio, 1.0, atol=0.005)


def test_identical_means_with_different_noise_pass():
    """DACRT and Cycles sample differently: same expectation, 3x the spread still passes."""
    rng = np.random.default_rng(7)
    image = scene_image(rng)
    result = stats.compare(draw(rng, image, noise=0.5), draw(rng, image, noise=1.5, seeds=16))
    assert result.passed, result.summary()


def test_heavy_tailed_identical_distributions_pass():
    """Fireflies: per-seed pixel means of 32 lognormal(sigma 1.2) samples, both sides."""
    rng = np.random.default_rng(3)
    image = scene_image(rng)

    def fireflies():
        s = rng.lognormal(-0.72, 1.2, size=(SEEDS, 32, H, W, 1)).mean(axis=1)
        out = image[None] * s
        out[:, :8] = image[None, :8]
        out[..., 3] = 1.0
        return out
    result = stats.compare(fireflies(), fireflies())
    assert result.passed, result.summary()


def test_global_two_percent_bias_fails():
    rng = np.random.default_rng(11)
    image = scene_image(rng)
    biased = image.copy()
    biased[..., :3] *= 1.02
    result = stats.compare(draw(rng, image), draw(rng, biased))
    assert not result.passed
    assert not result.means_agree
    assert np.all(np.abs(result.ratio[:3] - 1.02) < 0.005)


def test_single_channel_two_percent_bias_fails():
    rng = np.random.default_rng(12)
    image = scene_image(rng)
    biased = image.copy()
    biased[..., 2] *= 0.98                      # blue 2% low: a colour (light colour) error
    result = stats.compare(draw(rng, image), draw(rng, biased))
    assert not result.passed and not result.means_agree
    assert abs(result.ratio[0] - 1) < 0.005 and abs(result.ratio[2] - 0.98) < 0.005


def test_regional_two_percent_bias_fails_on_pixels_while_means_agree():
    """A 2% bias on a quarter of the image (means move 0.5%, within the 1% gate) is caught by
    the per-pixel test when pixels are precise enough (here 0.3% per seed)."""
    rng = np.random.default_rng(13)
    image = scene_image(rng)
    biased = image.copy()
    biased[24:, 32:, :3] *= 1.02
    result = stats.compare(draw(rng, image, noise=0.017), draw(rng, biased, noise=0.017))
    assert result.means_agree
    assert not result.pixels_agree and not result.passed
    fails = ~result.pixel_pass
    assert fails[24:, 32:].mean() > 0.5 and fails[:24].mean() == 0 and fails[:, :32].mean() == 0


def test_regional_bias_below_pixel_power_is_caught_by_blocks():
    """At a noise level where a 3% regional bias hides in single pixels, the 4x4 tile test
    (4x less noise per tile) catches it."""
    rng = np.random.default_rng(14)
    image = scene_image(rng)
    biased = image.copy()
    biased[24:, 32:, :3] *= 1.03
    result = stats.compare(draw(rng, image, noise=0.3), draw(rng, biased, noise=0.3))
    assert result.means_agree and result.pixels_agree
    assert not result.blocks_agree and not result.passed


def test_exactly_constant_pixels_compare_with_a_tolerance():
    rng = np.random.default_rng(5)
    image = scene_image(rng)
    a, b = draw(rng, image), draw(rng, image)
    b[:, :8, :, :3] *= 1 + 1e-6              # float rounding: passes
    assert stats.compare(a, b).passed
    b[:, :8, :, :3] *= 1.01                  # a 1% different sky without noise: every pixel fails
    result = stats.compare(a, b)
    assert not result.pixel_pass[:8].any() and result.pixel_pass[8:].all()
    assert not result.passed


def test_rejects_unusable_input():
    ok = np.ones((4, 3, 3, 4))
    with pytest.raises(ValueError, match="same image size"):
        stats.compare(ok, np.ones((4, 3, 2, 4)))
    with pytest.raises(ValueError, match="at least 2 seeds"):
        stats.compare(ok, np.ones((1, 3, 3, 4)))
    bad = ok.copy()
    bad[0, 0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="1 NaN or infinite"):
        stats.compare(ok, bad)
