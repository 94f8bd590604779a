"""Emission Sampling None (scenedata.Material.emission_sampling; addon/emissionsampling.py):
light sampling never picks such an emitter, BSDF rays alone find it and weigh its hits 1. The
image keeps its mean (against the same emitter light-sampled), also where the last bounce's BSDF
rays are what finds it, and the light samples go to the lamp instead."""

import dataclasses

import numpy as np

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, ortho_down, pixel_stats, quad, render, translation


def _scene(sampling, samples=256, max_bounces=1, lamp=True):
    """A floor under a large, dim emissive ceiling panel (the light-sampling hog a user sets to
    None) and, unless lamp is False, a small area lamp."""
    v0, t0 = quad((0.0, 0.0, 0.0), 100.0, 100.0)
    v1, t1 = quad((0.0, 0.0, 1.0), 3.0, 3.0, up=False)
    mats = [material('default'), material('floor', (0.8, 0.8, 0.8)),
            material('panel', (0.0, 0.0, 0.0), emission=(0.3, 0.25, 0.2), emission_sampling=sampling)]
    lights = [light('AREA', 20.0, translation(0.3, 0.0, 0.9), size_x=0.2)] if lamp else []
    geo = geometry([(v0, t0, 1, ALL_VIS), (v1, t1, 2, ALL_VIS)])
    return sd.SceneData(ortho_down(height=0.5, width=16, px=16, view=1.0), geo, mats, lights,
                        np.zeros(3, np.float32), sd.Settings(samples=samples, max_bounces=max_bounces))


def test_unsampled_emitter_is_left_to_bsdf_rays():
    sampled, unsampled = render(_scene('FRONT_BACK')), render(_scene('NONE'))
    assert sampled.lights.triangles is not None and len(sampled.lights.triangles) == 2
    assert unsampled.lights.triangles is None and unsampled.lights.num_entries == 1   # the lamp alone
    for c in range(3):
        a, ea = pixel_stats(sampled, c)
        b, eb = pixel_stats(unsampled, c)
        assert abs(a - b) < 4 * np.hypot(ea, eb), f"channel {c}: {a} vs {b} (+- {ea}, {eb})"


def test_unsampled_emitter_alone_is_found_on_the_last_bounce():
    """No light to sample at all and max bounces 0: the one BSDF ray each path casts must still
    be traced (it is the only way to the panel)."""
    sampled = render(_scene('FRONT_BACK', max_bounces=0, lamp=False))
    unsampled = render(_scene('NONE', max_bounces=0, lamp=False))
    assert not unsampled.lights and unsampled.lights.seen_by_bsdf
    a, ea = pixel_stats(sampled, 0)
    b, eb = pixel_stats(unsampled, 0)
    assert b > 0.5 * a > 0
    assert abs(a - b) < 4 * np.hypot(ea, eb), f"{a} vs {b} (+- {ea}, {eb})"


def test_front_and_back_settings_are_sampled():
    for mode in ('FRONT', 'BACK'):
        integ = render(dataclasses.replace(_scene(mode, samples=1)))
        assert integ.lights.triangles is not None and len(integ.lights.triangles) == 2, mode


def test_an_emitter_does_not_light_itself():
    """A quad that both emits (1) and reflects (albedo 0.8), turned to no axis, under a black
    world with no bounces: each pixel is its emission exactly, as in Cycles (1.0000). Its points
    lie within rounding of their own triangle's plane, from where that triangle filled half the
    sphere: light samples of it had added 0.064-0.071 (a helper's hunt)."""
    v, t = quad((0.0, 0.0, 0.0), 0.3, 0.3)
    c, s = np.cos(0.52), np.sin(0.52)
    turn = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.array([[np.cos(0.19), 0, np.sin(0.19)], [0, 1, 0],
                                                                     [-np.sin(0.19), 0, np.cos(0.19)]])
    v = v @ turn.T
    mats = [material('default'), material('panel', (0.8,) * 3, emission=(1.0, 1.0, 1.0))]
    scene = sd.SceneData(ortho_down(height=2.0), geometry([(v, t, 1, ALL_VIS)]), mats, [], np.zeros(3, np.float32),
                         sd.Settings(samples=16, max_bounces=0, filter_type='BOX'))
    img = render(scene).film.combined()
    # (1e-4: the quad's other half, coplanar within rounding, still adds a few 1e-6..1e-5 to a
    # point a few ULPs off their shared edge, where hit points now keep (pathvertex.h
    # inside_edges): seed 0 had 3.8e-5 in one of 64 pixels, 3e-6 before)
    assert np.allclose(img[..., :3], 1.0, rtol=1e-4), (img[..., 0].min(), img[..., 0].max())
