"""Adaptive sampling: Cycles' schedule, pixels that stop only when converged and only at the
check points, the image unchanged within noise, and the samples saved counted."""
import math

import numpy as np
import pytest

import addon.integrator as integrator_module
from addon.adaptive import STEP, AdaptiveSampling
from addon.integrator import Integrator

from .scenes import cornell_box, light, plane_scene, render, translation


def test_automatic_minimum_and_threshold_as_cycles():
    # Cycles' comment: "Threshold 0.1 -> 32, 0.01 -> 64, 0.001 -> 128"
    assert [AdaptiveSampling(1024, t, 0).min_samples for t in (0.1, 0.01, 0.001)] == [32, 64, 128]
    assert AdaptiveSampling(1024, 0.01, 2).min_samples == 4          # never below 4
    assert AdaptiveSampling(1024, 0.01, 100).min_samples == 100
    assert AdaptiveSampling(500, 0.0, 0).user_threshold == pytest.approx(1 / 500)
    assert AdaptiveSampling(1 << 20, 0.0, 0).user_threshold == 0.001
    assert AdaptiveSampling(64, 0.02, 0).threshold == pytest.approx(0.1)   # Cycles scales by 5
    for bad in (dict(threshold=-1.0, min_samples=0), dict(threshold=float('nan'), min_samples=0),
                dict(threshold=0.01, min_samples=-3)):
        with pytest.raises(ValueError):
            AdaptiveSampling(64, **bad)


@pytest.mark.parametrize('min_samples', [4, 40, 64, 100])
def test_align_stops_exactly_at_the_checks(min_samples):
    a = AdaptiveSampling(4096, 0.01, min_samples)
    checks = [s for s in range(600) if a.need_filter(s)]
    assert checks[0] > a.min_samples and all((s + 1) % STEP == 0 for s in checks)
    assert all(b - c == STEP for c, b in zip(checks, checks[1:]))
    # any blocking that honours align() lands on every check (Cycles' naive definition)
    for want in (1, 7, 16, 50, 1000):
        start, landed = 0, []
        while start < 600:
            n = a.align(start, min(want, 600 - start))
            naive = 1
            while not a.need_filter(start + naive - 1) and naive < min(want, 600 - start):
                naive += 1
            assert n == naive
            start += n
            if a.need_filter(start - 1):
                landed.append(start - 1)
        assert landed == checks


@pytest.fixture
def cycles_cadence(monkeypatch):
    """Checks every 16 samples however few pixels are left (these images are tiny)."""
    monkeypatch.setattr(integrator_module, '_ADAPTIVE_MIN_BATCH', 0)


def test_checks_spread_out_when_few_pixels_remain():
    assert AdaptiveSampling.step_for(100_000, 1 << 19) == 16
    assert AdaptiveSampling.step_for(20_000, 1 << 19) == 32
    assert AdaptiveSampling.step_for(1000, 1 << 19) == 1024
    assert AdaptiveSampling.step_for(5, 0) == 16
    a = AdaptiveSampling(4096, 0.01, 64)
    assert [s for s in range(400) if a.need_filter(s, 64)] == [127, 191, 255, 319, 383]
    assert a.align(80, 1000, 64) == 48 and a.align(128, 1000, 64) == 64


def test_large_check_interval_keeps_stops_on_its_grid(monkeypatch):
    # as a scene of 2^17 triangles or more would: 1,200 pixels, checks 512 apart
    monkeypatch.setattr(integrator_module, '_ADAPTIVE_PATHS_PER_TRIANGLE', 1 << 20)
    integ = render(_scene(True, samples=512))
    counts = integ.film.sample_counts()
    assert (counts == 512).all() and integ.stats['samples_skipped'] == 0


def test_a_small_frame_of_a_small_scene_is_checked_every_16_samples():
    """A 40 x 30 Cornell box (a few dozen triangles: its batches stay cheap however small) is
    checked as Cycles checks it, and its pixels stop (a fixed minimum batch of 2^19 paths had
    put the checks 512 samples apart: nothing stopped)."""
    integ = render(_scene(True, samples=256, threshold=0.1))
    counts = integ.film.sample_counts()
    first = (integ.adaptive.min_samples + 1) | (STEP - 1)
    stopped = counts[counts < 256]
    assert len(stopped) > 0.3 * counts.size and integ.stats['samples_skipped'] > 0
    assert np.all((stopped - (first + 1)) % STEP == 0)
    assert len(np.unique(stopped)) > 1                  # at more than one check


def test_the_error_estimate_follows_the_film_exposure():
    """Cycles scales its convergence test by the film exposure (an image twice as bright
    converges later), and normalises by the brightness itself from R+G+B = 1 up."""
    from addon.film import Film
    x = np.random.default_rng(2).random((4, 1, 32)).astype(np.float32) * 0.1
    errs = []
    for exposure in (1.0, 4.0, 40.0):
        f = Film(1, 1, adaptive=True, exposure=exposure)
        f.add_samples(np.array([0]), x, first_sample=0)
        errs.append(f.adaptive_error(np.array([0]))[0])
    total = x[:3].sum(axis=2, dtype=np.float64)[:, 0]
    diff = np.abs(total - 2 * x[:3, 0, 1::2].sum(axis=1, dtype=np.float64)).sum() / 32
    i1 = total.sum() / 32
    assert i1 < 1.0 / 4.0 and i1 * 40.0 > 1.0             # below 1, then above
    np.testing.assert_allclose(errs[0], diff / (1e-4 + np.sqrt(i1)), rtol=1e-12)
    np.testing.assert_allclose(errs[1], 4 * diff / (1e-4 + np.sqrt(4 * i1)), rtol=1e-12)
    np.testing.assert_allclose(errs[2], 40 * diff / (1e-4 + 40 * i1), rtol=1e-12)


def _scene(adaptive, samples=256, threshold=0.05, min_samples=0, **kw):
    return cornell_box(40, 30, samples, 3, area_light=True, use_adaptive_sampling=adaptive,
                       adaptive_threshold=threshold, adaptive_min_samples=min_samples, **kw)


def test_converged_pixels_stop_and_the_image_stays_within_noise(cycles_cadence):
    full = render(_scene(False))
    fast = render(_scene(True))
    counts = fast.film.sample_counts()
    a = fast.adaptive
    first = (a.min_samples + 1) | (STEP - 1)
    # every pixel took at least the first check's samples, stopped only right after a check
    # (or ran to the end), and many stopped early
    assert counts.min() >= first + 1
    stopped = counts[counts < 256]
    assert np.all((stopped - (first + 1)) % STEP == 0)
    assert counts.mean() < 0.7 * 256
    s = fast.stats
    assert s['samples_skipped'] == 40 * 30 * 256 - counts.sum() == s['skipped']['samples']
    assert s['pixels_converged'] == np.count_nonzero(counts < 256)
    assert s['rays_total'] < 0.75 * full.stats['rays_total']
    # same random numbers per (pixel, sample): each pixel's value is the mean of a prefix of the
    # full render's samples, so the images agree within that prefix's noise; the image means
    # agree within 1%
    img_a, img_f = fast.film.combined()[..., :3], full.film.combined()[..., :3]
    assert img_a.mean() == pytest.approx(img_f.mean(), rel=0.01)
    # per pixel: the difference is small relative to the estimated noise of the shorter run
    err = np.abs(img_a - img_f).sum(axis=2) / (1e-4 + np.sqrt(img_f.sum(axis=2)))
    assert np.percentile(err, 99) < 5 * a.threshold


def test_flat_regions_stop_at_the_first_check(cycles_cadence):
    # a plane under a sun with angle 0: every sample of a pixel has the same value
    scene = plane_scene([light('SUN', 3.0, np.eye(4))], samples=512, max_bounces=0,
                        use_adaptive_sampling=True, adaptive_threshold=0.01)
    integ = render(scene)
    counts = integ.film.sample_counts()
    first = (integ.adaptive.min_samples + 1) | (STEP - 1)
    assert (counts == first + 1).all()
    assert integ.stats['samples_skipped'] == counts.size * (512 - first - 1)
    assert integ.stats['samples_done'] == 512           # every pixel has finished


def test_adaptive_images_do_not_depend_on_blocking(cycles_cadence):
    a = Integrator(_scene(True, samples=160), paths_per_pass=997)
    for _ in a.passes():
        pass
    b = render(_scene(True, samples=160))
    assert np.array_equal(a.film.combined(), b.film.combined())
    assert np.array_equal(a.film.sample_counts(), b.film.sample_counts())


def test_fewer_samples_than_the_minimum_is_plain_sampling(cycles_cadence):
    integ = render(_scene(True, samples=20))
    assert (integ.film.sample_counts() == 20).all() and integ.stats['samples_skipped'] == 0


def test_error_estimate_is_cycles_formula():
    from addon.film import Film
    f = Film(2, 1, adaptive=True)
    rng = np.random.default_rng(1)
    x = rng.random((4, 2, 32)).astype(np.float32)
    f.add_samples(np.array([0, 1]), x[:, :, :16], first_sample=0)
    f.add_samples(np.array([0, 1]), x[:, :, 16:], first_sample=16)
    total = x[:3].sum(axis=2, dtype=np.float64)
    odd = 2 * x[:3, :, 1::2].sum(axis=2, dtype=np.float64)
    intensity = total.sum(axis=0) / 32
    assert intensity.min() >= 1.0            # (below 1: the other test)
    expect = np.abs(total - odd).sum(axis=0) / 32 / (1e-4 + intensity)
    np.testing.assert_allclose(f.adaptive_error(np.array([0, 1])), expect, rtol=1e-12)
    with pytest.raises(RuntimeError):
        Film(2, 1).adaptive_error(np.array([0]))
