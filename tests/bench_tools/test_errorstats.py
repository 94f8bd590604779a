"""The benchmark's error arithmetic (tests/bench/errorstats.py) against hand-computed values."""
import math

import numpy as np
import pytest

from tests.bench import errorstats as es


def test_relmse_matches_the_formula_by_hand():
    ref = np.zeros((1, 2, 4), np.float32)
    ref[0, 0, :3] = [1.0, 0.0, 2.0]
    ref[0, 1, :3] = [0.5, 0.5, 0.5]
    img = ref.copy()
    img[0, 0, 0] = 1.5          # (0.5)^2 / (1 + 0.01)
    img[0, 1, 2] = 0.0          # (0.5)^2 / (0.25 + 0.01)
    img[..., 3] = 7.0           # alpha is ignored
    expected = (0.25 / 1.01 + 0.25 / 0.26) / 6
    assert es.relmse(img, ref) == pytest.approx(expected, rel=1e-12)
    assert es.relmse(ref, ref) == 0.0
    assert es.relmse_map(img, ref)[0, 0] == pytest.approx(0.25 / 1.01 / 3)


def test_relmse_refuses_mismatched_or_non_finite_images():
    a = np.ones((2, 2, 3))
    with pytest.raises(ValueError, match="differ in size"):
        es.relmse(a, np.ones((2, 3, 3)))
    b = a.copy()
    b[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        es.relmse(b, a)


def test_reference_floor_is_the_variance_of_the_mean_over_r2_eps():
    # two seeds per pixel: values 1 and 3 -> mean 2, sample variance 2, of the mean 1
    s = np.empty((2, 1, 1, 3))
    s[0], s[1] = 1.0, 3.0
    assert es.reference_floor(s) == pytest.approx(1.0 / (4.0 + 0.01))
    with pytest.raises(ValueError):
        es.reference_floor(s[:1])


def test_reference_floor_predicts_the_error_of_a_noisy_mean():
    rng = np.random.default_rng(3)
    truth = rng.uniform(0.2, 1.0, (64, 64, 3))
    seeds = truth + rng.normal(0, 0.1, (8, 64, 64, 3))
    measured = es.relmse(seeds.mean(0), truth)
    assert es.reference_floor(seeds) == pytest.approx(measured, rel=0.1)


def test_efficiency():
    assert es.efficiency(0.01, 2.0) == pytest.approx(50.0)
    assert es.efficiency(0.0, 1.0) == math.inf
    with pytest.raises(ValueError):
        es.efficiency(0.1, 0.0)


def test_time_at_error_interpolates_in_log_log():
    # relMSE = 1/t exactly: any error inside the range maps back to its time
    t = [1.0, 4.0, 16.0]
    e = [1.0, 0.25, 1 / 16]
    r = es.time_at_error(t, e, 0.5)
    assert r.seconds == pytest.approx(2.0) and not r.extrapolated
    # between two points the log-log segment is straight: halfway in log error
    r = es.time_at_error([1.0, 100.0], [1.0, 1e-4], 1e-2)
    assert r.seconds == pytest.approx(10.0) and not r.extrapolated
    # point order does not matter
    assert es.time_at_error(t[::-1], e[::-1], 0.5).seconds == pytest.approx(2.0)


def test_time_at_error_extrapolates_with_slope_minus_one_and_says_so():
    r = es.time_at_error([1.0, 2.0], [0.1, 0.05], 0.01)
    assert r.extrapolated and r.seconds == pytest.approx(10.0)
    r = es.time_at_error([1.0, 2.0], [0.1, 0.05], 1.0)
    assert r.extrapolated and r.seconds == pytest.approx(0.1)
    with pytest.raises(ValueError):
        es.time_at_error([1.0], [0.0], 0.1)
    with pytest.raises(ValueError):
        es.time_at_error([1.0, 2.0], [0.1], 0.1)


def test_equal_error_ratio_and_slope():
    # engine A twice as fast as B for the same error everywhere
    tb = np.array([1.0, 2.0, 4.0])
    eb = 0.1 / tb
    ratio, extrap = es.equal_error_ratio(tb / 2, eb, tb, eb, 0.05)
    assert ratio == pytest.approx(0.5) and not extrap
    assert es.loglog_slope(tb, eb) == pytest.approx(-1.0)
    assert math.isnan(es.loglog_slope([1.0], [1.0]))
