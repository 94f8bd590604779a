"""Parity with Cycles: DACRT and Cycles render the scenes of scenes.py with the fair
settings of reference blender-cycles.md 2.7 (rendering.py), each engine 32 seeds of 128 spp,
and must agree statistically (stats.py):

- the image mean of every channel (RGBA) within 1%;
- >= 99% of the pixels pass a per-pixel, per-channel Welch t-test at a Sidak-corrected level
  (family alpha 1% over all pixels and channels);
- >= 99% of the 4x4 pixel tiles pass the same test on tile means (more power for biases
  spread over a region, e.g. a light falling off wrongly).

Cycles' images are cached in build/parity-cache (reference.py); a run that finds them renders
DACRT only. Reports with both images and the failing pixels land in build/parity-report.
The same statistics are also checked on Cycles' own images (even against odd seeds): they
must pass against themselves and catch a 2% global and a 5% regional bias on real noise.
"""
import dataclasses

import numpy as np
import pytest

from . import reference, rendering, report, stats
from .scenes import SPECS

DACRT_SEED_BASE = 100     # DACRT's seeds, disjoint from Cycles' 0..M-1 (no meaning, just tidy)


def dacrt_seeds(spec):
    return list(range(DACRT_SEED_BASE, DACRT_SEED_BASE + spec.dacrt_seeds))


def check_parity(spec):
    cycles, seconds = reference.cycles_images(spec)
    # the reference itself must be a lit, non-trivial image, or agreement would mean nothing
    lit = cycles[..., :3].mean(axis=(0, 1, 2))
    assert (lit > 0.01).all(), f"{spec.name}: Cycles reference is (nearly) black: {lit}"
    assert cycles[..., :3].std(axis=(0, 1, 2)).min() > 0.01, \
        f"{spec.name}: Cycles reference is (nearly) flat"
    dacrt = rendering.render_seeds(spec, 'DACRT', dacrt_seeds(spec))
    assert dacrt.shape[1:] == cycles.shape[1:], \
        f"{spec.name}: DACRT image is {dacrt.shape[2]}x{dacrt.shape[1]}, Cycles' " \
        f"{cycles.shape[2]}x{cycles.shape[1]}"
    result = stats.compare(cycles, dacrt)
    summary = result.summary()
    report.write(spec.name, cycles, dacrt, result, summary)
    print(f"{spec.name}: Cycles {'cached' if seconds is None else f'rendered in {seconds:.1f} s'}"
          f"\n{summary}")
    if not result.passed:
        pytest.fail(f"{spec.name}: DACRT disagrees with Cycles (images: "
                    f"{report.REPORT_DIR / spec.name}.png = Cycles | DACRT | failing pixels)\n"
                    f"{summary}", pytrace=False)
    return result


@pytest.mark.long
@pytest.mark.parametrize("spec", SPECS, ids=[s.name for s in SPECS])
def test_parity_with_cycles(spec, parity_addon):
    check_parity(spec)


@pytest.mark.parametrize("spec", SPECS, ids=[s.name for s in SPECS])
def test_statistics_on_real_render_noise(spec, parity_addon):
    """The comparison on Cycles' own images (even against odd seeds, no extra rendering):
    real noise (QMC, fireflies, exact background pixels) must pass against itself, and fail
    once one half is 2% brighter everywhere or 5% brighter in one quadrant."""
    cycles, _ = reference.cycles_images(spec)
    even, odd = cycles[0::2].astype(np.float64), cycles[1::2].astype(np.float64)
    same = stats.compare(even, odd)
    assert same.passed, f"{spec.name}: Cycles disagrees with itself\n{same.summary()}"
    brighter = odd.copy()
    brighter[..., :3] *= 1.02
    assert not stats.compare(even, brighter).means_agree
    h, w = odd.shape[1:3]
    quadrant = odd.copy()
    quadrant[:, h // 2:, w // 2:, :3] *= 1.05
    result = stats.compare(even, quadrant)
    assert not result.passed, f"{spec.name}: a 5% bias on a quadrant went unnoticed\n" \
                              f"{result.summary()}"


# The same scenes with 4x the samples per seed for both engines: twice the power to find a
# per-pixel bias. Too slow for CI (cold ~17 min on 2 cores, of which Cycles ~3/4; cached ~4
# min), so a tier of its own: `python3 build.py test --precise` (or `-m precise`).
PRECISE = [dataclasses.replace(s, name=s.name + "_precise", cycles_samples=4 * s.cycles_samples,
                               dacrt_samples=4 * s.dacrt_samples) for s in SPECS]


@pytest.mark.precise
@pytest.mark.long
@pytest.mark.parametrize("spec", PRECISE, ids=[s.name for s in PRECISE])
def test_parity_with_cycles_precise(spec, parity_addon):
    check_parity(spec)


def test_reference_cache_key_tracks_settings_and_scene(parity_addon):
    spec = SPECS[0]
    assert reference.cache_key(spec) == reference.cache_key(dataclasses.replace(spec))
    changed = [dataclasses.replace(spec, bounces=spec.bounces + 1),
               dataclasses.replace(spec, filter_width=spec.filter_width + 0.5),
               dataclasses.replace(spec, cycles_samples=spec.cycles_samples * 2),
               dataclasses.replace(spec, cycles_seeds=spec.cycles_seeds + 1),
               dataclasses.replace(spec, resolution=(spec.resolution[0] + 1, spec.resolution[1])),
               dataclasses.replace(spec, build=SPECS[1].build)]
    keys = {reference.cache_key(s) for s in changed}
    assert reference.cache_key(spec) not in keys and len(keys) == len(changed)
    # DACRT's own settings do not invalidate the Cycles reference
    assert reference.cache_key(dataclasses.replace(spec, dacrt_samples=7, dacrt_seeds=3)) == \
        reference.cache_key(spec)
