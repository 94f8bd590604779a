"""Light Groups (Cycles' Combined_<group> passes): each group's pass holds the light of its
emitters (lamps, emissive objects, the world), by every way it arrives (seen, sampled, found by
BSDF rays, through transparent surfaces), clamped as Combined is; so where every emitter is in a
group, the groups add up to Combined in every pixel."""
import dataclasses

import numpy as np

from addon import scenedata as sd
from .scenes import cornell_box, light, render, translation


def _box(**settings):
    """The Cornell box with its emissive ceiling quad, a point light, a spot light and a
    world seen through the open front; groups: ceiling quad 'panel', point 'key', world 'sky'."""
    scene = cornell_box(32, 24, samples=16, max_bounces=3, **settings)
    n_obj = int(scene.geometry.object_index.max()) + 1
    groups = [''] * n_obj
    groups[-1] = 'panel'                                   # the emissive ceiling quad (last part)
    spot = np.array(translation(0.7, 0.4, 0.9))
    return dataclasses.replace(
        scene, world=np.full(3, 0.2, np.float32), object_lightgroups=groups, world_lightgroup='sky',
        lights=[light('POINT', 8.0, translation(0.3, 0.3, 0.7), radius=0.05, lightgroup='key'),
                light('SPOT', 10.0, spot, spot_size=1.2, spot_blend=0.3, radius=0.02, lightgroup='fill')])


def test_light_groups_add_up_to_combined():
    scene = _box(lightgroups=('panel', 'key', 'sky', 'fill', 'empty'))
    film = render(scene).film
    combined = film.combined()[..., :3].astype(np.float64)
    groups = {g: film.pass_image('Combined_' + g).astype(np.float64) for g in ('panel', 'key', 'sky', 'fill', 'empty')}
    for g in ('panel', 'key', 'sky', 'fill'):
        assert groups[g].mean() > 0.01 * combined.mean(), g
    assert not groups['empty'].any()                      # a group no emitter is in
    total = sum(groups.values())
    assert np.allclose(total, combined, rtol=2e-5, atol=1e-6)
    # the world's group holds the world seen directly, so it is the whole light of pixels that see it
    assert groups['sky'].max() > 0.19


def test_world_group_holds_the_world_behind_transparent_film_with_the_environment_pass():
    """With Film > Transparent, Combined leaves out the world the camera sees (alpha 0 there).
    Cycles evaluates that world only for the Environment pass, and then its light group takes
    it too (Cycles 5.0, a floor under a uniform world in group 'sky': the group's sky pixels
    0.5 with the pass, 0.0 without, Combined 0 both ways); the world's light on surfaces is
    there either way."""
    opaque = render(_box(lightgroups=('sky',))).film
    clear = render(_box(lightgroups=('sky',), film_transparent=True)).film
    with_env = render(_box(lightgroups=('sky',), film_transparent=True, passes=('Env',))).film
    sky_o, sky_c, sky_e = (f.pass_image('Combined_sky') for f in (opaque, clear, with_env))
    background = clear.combined()[..., 3] == 0
    assert background.sum() > 20
    assert not clear.combined()[background, :3].any() and not with_env.combined()[background, :3].any()
    assert not sky_c[background].any()
    np.testing.assert_allclose(sky_e[background], 0.2, rtol=1e-6)       # the world's colour
    np.testing.assert_array_equal(sky_e, sky_o)
    solid = clear.combined()[..., 3] == 1.0                  # (edge pixels blend in some world)
    assert solid.sum() > 200
    np.testing.assert_array_equal(sky_c[solid], sky_o[solid])


def test_emitters_outside_the_view_layer_groups_are_only_in_combined():
    scene = _box(lightgroups=('panel', 'sky'))            # 'key' and 'fill' are not view-layer groups
    film = render(scene).film
    combined = film.combined()[..., :3].astype(np.float64)
    total = film.pass_image('Combined_panel').astype(np.float64) + film.pass_image('Combined_sky')
    assert np.all(total <= combined * (1 + 1e-5) + 1e-6) and total.mean() < 0.9 * combined.mean()
    # and the same image: the groups change nothing else
    plain = render(_box()).film.combined()
    assert np.array_equal(plain, film.combined())


def test_light_groups_through_transparent_surfaces_and_clamps():
    """A transparent pane in front of the box and clamped light: still the sum of the groups."""
    scene = _box(lightgroups=('panel', 'key', 'sky', 'fill'), sample_clamp_indirect=0.5,
                 sample_clamp_direct=2.0)
    g = scene.geometry
    pane = sd.Material('pane', np.full(3, 0.3, np.float32), np.zeros(3, np.float32),
                       transparency=np.full(3, 0.6, np.float32))
    scene.materials.append(pane)
    v = np.array([(0.1, -0.3, 0.1), (0.9, -0.3, 0.1), (0.9, -0.3, 0.9), (0.1, -0.3, 0.9)])
    base = len(g.vertices)
    tris = np.array([(0, 1, 2), (0, 2, 3)]) + base
    n = np.cross(v[1] - v[0], v[2] - v[0])
    n = (n / np.linalg.norm(n)).astype(np.float32)
    scene.geometry = dataclasses.replace(
        g, vertices=np.concatenate([g.vertices, v]), triangles=np.concatenate([g.triangles, tris]).astype(np.int32),
        material=np.concatenate([g.material, [len(scene.materials) - 1] * 2]).astype(np.int32),
        normals=np.concatenate([g.normals, np.repeat(np.repeat(n[None, None], 3, axis=1), 2, axis=0)]),
        visibility=np.concatenate([g.visibility, g.visibility[:2]]),
        object_index=np.concatenate([g.object_index, [g.object_index.max() + 1] * 2]).astype(np.int32))
    scene.object_lightgroups = list(scene.object_lightgroups) + ['']
    film = render(scene).film
    combined = film.combined()[..., :3].astype(np.float64)
    total = sum(film.pass_image('Combined_' + k).astype(np.float64) for k in ('panel', 'key', 'sky', 'fill'))
    assert np.allclose(total, combined, rtol=2e-5, atol=1e-6)
