"""Diffuse transmission (a Translucent BSDF, scenedata.Material.translucency) against closed
forms: a large plane lit from one side by a sun or from both by a uniform world, seen from
either side by a tiny orthographic camera. A Lambertian lobe of albedo T on the far side gives
T E / pi there, beside R E / pi of the reflection on the lit side (reference blender-cycles.md
2.2 for the units); under a white world of radiance 1 both sides see R + T."""
import dataclasses

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, ortho_down, pixel_stats, quad, render, rotation_x, translation


def _plane(R, T, lights, world=(0.0, 0.0, 0.0), below=False, samples=256):
    v, t = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    mats = [material('default'), material('leaf', (R,) * 3, translucency=np.full(3, T, np.float32))]
    cam = ortho_down()
    if below:                                   # the same camera turned to look up at the plane
        cam = dataclasses.replace(cam, matrix=translation(0, 0, -0.5) @ rotation_x(np.pi))
    return sd.SceneData(cam, geometry([(v, t, 1, ALL_VIS)]), mats, list(lights), np.asarray(world, np.float32),
                        sd.Settings(samples=samples, max_bounces=0, filter_type='BOX'))


def _check(scene, expected, rel=0.01):
    mean, err = pixel_stats(render(scene))
    if expected == 0.0:
        assert mean == 0.0
        return
    assert err < 0.3 * rel * expected, f"too noisy to decide: stderr {err:.5f} for {expected:.5f}"
    assert mean == pytest.approx(expected, rel=rel), f"got {mean:.5f}, expected {expected:.5f} (+-{err:.5f})"


SUN = 3.0


@pytest.mark.parametrize('R, T', [(0.5, 0.3), (0.0, 0.7), (0.2, 0.8)])
def test_sunlit_leaf_reflects_on_the_lit_side_and_transmits_to_the_other(R, T):
    sun = light('SUN', SUN, np.eye(4))          # straight down onto the plane's top
    _check(_plane(R, T, [sun]), R * SUN / np.pi)
    _check(_plane(R, T, [sun], below=True), T * SUN / np.pi)


@pytest.mark.parametrize('R, T', [(0.5, 0.3), (0.0, 0.9)])
def test_white_world_on_both_sides_gives_r_plus_t(R, T):
    for below in (False, True):
        _check(_plane(R, T, [], world=(1.0, 1.0, 1.0), below=below), R + T)


def test_translucent_material_with_black_reflection_is_not_skipped_as_black():
    sun = light('SUN', SUN, np.eye(4))
    integ = render(_plane(0.0, 0.5, [sun], below=True, samples=16))
    assert integ.film.combined()[..., 0].mean() > 0.4 * 0.5 * SUN / np.pi


@pytest.mark.parametrize('use_mis', [True, False])
def test_area_light_behind_the_surface_is_unbiased_with_and_without_mis(use_mis):
    """A 1 m square light 1 m below the plane, facing it: seen from above, the plane shows T x
    the closed-form irradiance / pi. With MIS the transmission lobe's light samples and the
    BSDF rays that leave through the far side meet the same light: their weights must still
    sum to one (the lobe's probability is left out of both sides of the heuristic)."""
    from .test_lights import rect_irradiance
    R, T = 0.3, 0.5
    expected = T * 4 * rect_irradiance(100.0 / np.pi, 0.5, 0.5, 1.0) / np.pi
    area = light('AREA', 100.0, translation(z=-1.0) @ rotation_x(np.pi), shape='SQUARE', size_x=1.0,
                 use_mis=use_mis)
    v, t = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    mats = [material('default'), material('leaf', (R,) * 3, translucency=np.full(3, T, np.float32))]
    scene = sd.SceneData(ortho_down(width=32, px=32), geometry([(v, t, 1, ALL_VIS)]), mats, [area],
                         np.zeros(3, np.float32), sd.Settings(samples=1024, max_bounces=1, seed=11, filter_type='BOX'))
    _check(scene, expected, rel=1.5e-3)


def test_valid_reflection_normal_lifts_the_reflection_to_the_threshold():
    """Cycles' ensure_valid_specular_reflection: a bent normal whose mirror reflection of the view
    direction dips below the surface is raised toward Ng until that reflection leaves at
    min(0.9 cos_view, 0.01) above it; a valid one, or any without Bump Map Correction, stays."""
    from addon.translucency import valid_reflection_normal
    rng = np.random.default_rng(5)
    n = 2000
    Ng = np.tile([[0.0], [0.0], [1.0]], n)
    I = rng.normal(size=(3, n))
    I[2] = np.abs(I[2]) + 0.05
    I /= np.linalg.norm(I, axis=0)
    N = rng.normal(size=(3, n)) * [[1.0], [1.0], [0.3]]
    N[2] = np.abs(N[2]) + 0.01
    N /= np.linalg.norm(N, axis=0)
    out = valid_reflection_normal(Ng, I, N, np.ones(n, bool)).astype(np.float64)
    R = lambda m: 2 * (m * I).sum(axis=0) * m - I  # noqa: E731
    t = np.minimum(0.9 * I[2], 0.01)
    valid = R(N)[2] >= t
    assert 0.05 < valid.mean() < 0.95                         # both kinds are tested
    np.testing.assert_allclose(out[:, valid], N[:, valid], atol=1e-6)
    np.testing.assert_allclose(R(out)[2][~valid], t[~valid], atol=2e-4)
    np.testing.assert_allclose(np.linalg.norm(out, axis=0), 1.0, atol=1e-5)
    assert np.all(out[2] > 0)
    np.testing.assert_allclose(valid_reflection_normal(Ng, I, N, np.zeros(n, bool)), N, atol=1e-6)
