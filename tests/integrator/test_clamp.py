"""Cycles' sample clamps (Light Paths > Clamping, film/light_passes.h film_clamp_light): each
contribution whose absolute channel sum exceeds 3 x the setting is scaled down to it; direct
light is what the camera sees and what vertex 0 gathers (its light samples and its BSDF rays'
finds), the rest is indirect.

- Each native kernel that adds light (light samples, emissive triangles, lamps one by one, the
  environment map) clamps every contribution, against numpy clamping its unclamped ones.
- A huge sun: the clamped pixel is the limit, exactly.
- The split: with a tiny indirect clamp an image with one bounce is the image without it, with
  a tiny direct clamp it is the difference of the two (same random numbers per vertex).
"""
import dacrt
import numpy as np
import pytest
from dacrt import shading

from addon.lights import lamp_records

from ..native.test_shading import _geo
from .scenes import cornell_box, light, plane_scene, render, rotation_x
from .test_environment import environment, sky_map, unit_dirs
from .test_native_lamps import NAMES, gather_rays, make

F32 = np.float32


def _clamped(c, limit):
    """numpy: contributions c (3, n) scaled to an absolute channel sum of at most limit."""
    s = np.abs(c).sum(axis=0)
    return np.where(s > limit, c * (limit / np.where(s > 0, s, 1.0)), c)


def _check(c, got, limit):
    assert (np.abs(c).sum(axis=0) > limit).mean() > 0.2          # many are clamped, not all
    assert (np.abs(c).sum(axis=0) < limit).mean() > 0.2
    assert np.allclose(got, _clamped(c, limit), rtol=1e-5, atol=1e-7)


def test_accumulate_masked_clamps_each_value():
    rng = np.random.default_rng(1)
    n = 10_000
    values = (rng.normal(size=(3, n)) * 4).astype(F32)
    mask = rng.random(n) < 0.7
    L = np.zeros((3, n), F32)
    shading.accumulate_masked(L, np.arange(n), values, mask, clamp=6.0)
    _check(values * mask, L, 6.0)
    with pytest.raises(ValueError, match='clamp'):
        shading.accumulate_masked(L, np.arange(n), values, mask, clamp=0.0)


def test_gather_emission_clamps_each_hit():
    rng = np.random.default_rng(2)
    m, n = 40, 20_000
    geo, area = _geo(rng, m)
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits['prim'], hits['t'] = rng.integers(0, m, n), rng.uniform(0.5, 3.0, n)
    hit = rng.random(n) < 0.8
    emission = rng.uniform(0.0, 8.0, (3, m)).astype(F32)
    thr = rng.uniform(0.0, 2.0, (3, n)).astype(F32)
    O, D = rng.normal(size=(3, n)).astype(F32), np.tile(np.array([[0.0], [0.0], [1.0]], F32), n)
    args = (hits, hit, emission, np.ones(m, bool), None, area, geo, O, D, thr, None, np.arange(n))
    free, got = np.zeros((3, n), F32), np.zeros((3, n), F32)
    shading.gather_emission(*args, free)
    shading.gather_emission(*args, got, clamp=12.0)
    _check(free, got, 12.0)


def test_lamp_gather_clamps_each_lamp_a_ray_meets():
    """Cycles meets lamps one at a time, so each is clamped on its own: the clamped sum of all
    lamps is the sum of each lamp's clamped contribution."""
    rng = np.random.default_rng(3)
    lamps = [make(name) for name in NAMES]
    rec = lamp_records(lamps)
    n = 20_000
    O, D, t_surf, miss = gather_rays(rng, lamps, n)
    thr = rng.uniform(0.5, 4.0, (3, n)).astype(F32)
    pid = np.arange(n)
    each, want = [], np.zeros((3, n))
    for j in range(len(lamps)):
        c = np.zeros((3, n), F32)
        dacrt.lamps.lamp_gather(rec, [j], O, D, t_surf, miss, pid, c, thr=thr)
        each.append(c)
        want += _clamped(c.astype(np.float64), 2.0)
    got = np.zeros((3, n), F32)
    dacrt.lamps.lamp_gather(rec, list(range(len(lamps))), O, D, t_surf, miss, pid, got, thr=thr, clamp=2.0)
    seen = [np.abs(c).sum(axis=0) > 0 for c in each]
    assert (np.sum(seen, axis=0) >= 2).sum() > 100              # rays that meet several lamps
    assert (np.abs(np.sum(each, axis=0)).sum(axis=0) > 2.0).mean() > 0.05
    assert np.allclose(got, want, rtol=1e-5, atol=1e-6)


def test_environment_gather_clamps_each_ray():
    env = environment(sky_map()).native
    n = 5000
    D = unit_dirs(n, seed=5)
    miss = np.random.default_rng(6).random(n) < 0.7
    thr = np.random.default_rng(7).uniform(0.0, 3.0, (3, n)).astype(F32)
    free, got = np.zeros((3, n), F32), np.zeros((3, n), F32)
    env.gather(0.0, D, miss, thr, None, np.arange(n), free)
    limit = float(np.median(np.abs(free[:, miss]).sum(axis=0)))
    env.gather(0.0, D, miss, thr, None, np.arange(n), got, limit)
    _check(free, got, limit)


def test_a_clamped_sun_gives_the_limit():
    """A sun of irradiance 100 pi on albedo 0.8: 80 per channel unclamped; Clamp Direct 10 caps
    the sample at a channel mean of 10. Clamp Indirect does not touch direct light."""
    sun = light('SUN', 100 * np.pi, rotation_x(0.0))
    for direct, indirect, want in ((10.0, 0.0, 10.0), (0.0, 10.0, 80.0), (0.0, 0.0, 80.0), (100.0, 1.0, 80.0)):
        scene = plane_scene([sun], samples=4, max_bounces=0,
                            sample_clamp_direct=direct, sample_clamp_indirect=indirect)
        img = render(scene).film.combined()[..., :3]
        assert np.allclose(img, want, rtol=1e-5), (direct, indirect)


@pytest.mark.parametrize('area_light', [False, True])
def test_direct_and_indirect_are_split_as_cycles_splits_them(area_light):
    """Cornell box (emissive ceiling quad, or an area lamp): vertex 0's light samples and what its
    BSDF rays find are direct light, everything after indirect. The direct part of an image with
    one bounce is the image with none (same random numbers), sample by sample."""
    def image(K, direct=0.0, indirect=0.0):
        scene = cornell_box(width=24, height=18, samples=16, max_bounces=K, area_light=area_light,
                            filter_type='BOX', sample_clamp_direct=direct, sample_clamp_indirect=indirect)
        return render(scene).film.combined()[..., :3].astype(np.float64)
    none, one = image(0), image(1)
    tiny = 1e-7
    assert (one - none).mean() > 0.05 * none.mean()              # the bounce adds light
    assert np.allclose(image(1, indirect=tiny), none, atol=1e-5)
    assert np.allclose(image(1, direct=tiny), one - none, atol=1e-4)
    with pytest.raises(ValueError, match='sample_clamp_direct'):
        image(0, direct=-1.0)
