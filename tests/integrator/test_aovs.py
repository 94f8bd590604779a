"""Shader AOVs (Cycles' svm/aov.h, film/aov_passes.h): each sample adds what the shaders of
the surfaces its camera ray meets write, up to and including the first surface at least as
opaque as the Pass Alpha Threshold: a COLOR AOV (r, g, b, 1), a VALUE AOV its value; the pass
is the mean over the samples. Closed forms on a plane under a transparent pane."""
import dataclasses

import numpy as np
import pytest

from addon import scenedata as sd
from .scenes import ALL_VIS, geometry, material, ortho_down, quad, render

AOVS = (('tint', 'COLOR'), ('mask', 'VALUE'), ('unused', 'VALUE'))


def _scene(transparency, **settings):
    """An 8x8 orthographic view of 2 m of floor (AOVs tint (0.2, 0.4, 0.6), mask 0.5) with a
    pane over its left half (x < 0; tint (1, 0, 0), mask 1, transparency as given) and a
    third material, without AOVs, on a strip at the far right (x > 0.75)."""
    floor_v, floor_t = quad((-0.125, 0.0, 0.0), 0.875, 1.0)
    strip_v, strip_t = quad((0.875, 0.0, 0.0), 0.125, 1.0)
    pane_v, pane_t = quad((-0.5, 0.0, 0.5), 0.5, 1.0)
    mats = [material('default'),
            material('floor', (0.5, 0.5, 0.5), aovs={'tint': ((0.2, 0.4, 0.6), 0.25), 'mask': ((0, 0, 0), 0.5)}),
            material('plain', (0.5, 0.5, 0.5)),
            material('pane', (0.5, 0.5, 0.5), transparency=np.full(3, transparency, np.float32),
                     aovs={'tint': ((1.0, 0.0, 0.0), 0.0), 'mask': ((0.3, 0.3, 0.3), 1.0)})]
    geo = geometry([(floor_v, floor_t, 1, ALL_VIS), (strip_v, strip_t, 2, ALL_VIS), (pane_v, pane_t, 3, ALL_VIS)])
    s = dict(samples=256, max_bounces=1, filter_type='BOX', filter_width=1.0, aovs=AOVS)
    s.update(settings)
    return sd.SceneData(ortho_down(height=2.0, view=2.0), geo, mats, [], np.full(3, 0.5, np.float32),
                        sd.Settings(**s))


def _passes(scene):
    film = render(scene).film
    return film, film.pass_image('AOV:tint'), film.pass_image('AOV:mask')[..., 0]


@pytest.mark.parametrize('transparency', [0.8, 0.3])
def test_aovs_add_up_to_the_first_mostly_opaque_surface(transparency):
    film, tint, mask = _passes(_scene(transparency))
    assert tint.shape == (8, 8, 4) and mask.shape == (8, 8)
    left, floor, strip = np.s_[:, 0:3], np.s_[:, 4:6], np.s_[:, 7:8]     # away from the edges
    if transparency > 0.5:
        # alpha 0.2 < 0.5: the pane writes, and the floor under it for the samples that pass the
        # pane, which they do with probability p = transparency / (transparency + albedo), as
        # Cycles picks the transparent closure by its weight
        passed = tint[left][..., 3] - 1.0                 # each pixel's share of samples that passed
        np.testing.assert_allclose(tint[left][..., :3], 0.0 + np.stack([1.0 + 0.2 * passed, 0.4 * passed,
                                                                       0.6 * passed], axis=-1), atol=1e-6)
        np.testing.assert_allclose(mask[left], 1.0 + 0.5 * passed, atol=1e-6)
        p = transparency / (transparency + 0.5)
        assert abs(passed.mean() - p) < 0.03, (passed.mean(), p)   # 24 pixels x 256 samples
    else:                        # alpha 0.7: the pane ends the pass
        np.testing.assert_allclose(tint[left], np.broadcast_to([1.0, 0.0, 0.0, 1.0], tint[left].shape), rtol=1e-6)
        np.testing.assert_allclose(mask[left], 1.0, rtol=1e-6)
    np.testing.assert_allclose(tint[floor], np.broadcast_to([0.2, 0.4, 0.6, 1.0], tint[floor].shape), rtol=1e-6)
    np.testing.assert_allclose(mask[floor], 0.5, rtol=1e-6)
    assert not tint[strip].any() and not mask[strip].any()   # a material that writes nothing
    assert not film.pass_image('AOV:unused').any()


def test_pass_alpha_threshold_zero_stops_at_the_first_surface():
    _, tint, mask = _passes(_scene(0.8, pass_alpha_threshold=0.0))
    np.testing.assert_allclose(mask[:, 0:3], 1.0, rtol=1e-6)
    np.testing.assert_allclose(tint[:, 0:3, 3], 1.0, rtol=1e-6)


def test_aovs_change_nothing_else():
    with_aovs = render(_scene(0.8)).film.combined()
    without = render(dataclasses.replace(_scene(0.8), settings=dataclasses.replace(_scene(0.8).settings, aovs=())))
    assert np.array_equal(with_aovs, without.film.combined())
    assert without.film.aov_passes == ()


def test_world_aovs_where_camera_rays_miss():
    """The world's AOVs where camera rays miss (through the pane too, when the pass is not
    done there), not with transparent film unless the Environment pass is on, and not where
    the world is hidden from the camera."""
    scene = _scene(0.3, samples=16)
    floor = scene.geometry.material == 1
    g = scene.geometry
    keep = ~floor                                        # no floor: the view's middle sees the world
    scene = dataclasses.replace(scene, geometry=dataclasses.replace(
        g, triangles=g.triangles[keep], material=g.material[keep], normals=g.normals[keep],
        visibility=g.visibility[keep], object_index=g.object_index[keep]),
        world_aovs={'mask': ((0.0, 0.0, 0.0), 0.125), 'tint': ((0.5, 0.5, 0.0), 0.0)})
    _, tint, mask = _passes(scene)
    np.testing.assert_allclose(mask[:, 4:6], 0.125)
    np.testing.assert_allclose(tint[:, 4:6], np.broadcast_to([0.5, 0.5, 0.0, 1.0], tint[:, 4:6].shape))
    np.testing.assert_allclose(mask[:, 0:3], 1.0)        # the pane (alpha 0.7) ends the pass
    veil = dataclasses.replace(scene, materials=scene.materials[:3] + [dataclasses.replace(
        scene.materials[3], transparency=np.full(3, 0.8, np.float32))])
    _, _, mask = _passes(veil)                           # alpha 0.2: the world behind it adds
    passed = (mask[:, 0:3] - 1.0) / 0.125
    assert np.all((passed >= -1e-6) & (passed <= 1 + 1e-6)) and 0.4 < passed.mean() < 0.8
    hidden = dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, film_transparent=True))
    assert not _passes(hidden)[2][:, 4:6].any()
    # transparent film with the Environment pass: Cycles runs the background shader for it, and
    # its AOVs write (Cycles: (0.2, 0.3, 0.4, 1) of a world AOV; DACRT had written 0)
    env = dataclasses.replace(hidden, settings=dataclasses.replace(
        hidden.settings, passes=tuple(hidden.settings.passes) + ('Env',)))
    np.testing.assert_allclose(_passes(env)[2][:, 4:6], 0.125)
    hidden = dataclasses.replace(scene, world_visibility=sd.VIS_DIFFUSE)
    assert not _passes(hidden)[2][:, 4:6].any()


def test_images_write_aovs_on_the_uv_map():
    """An AOV fed by an image: what the texel under each hit holds, added to the constants."""
    scene = _scene(0.3)
    g = scene.geometry
    # the UV map: u = (x + 1) / 2 over the view, so the floor's left texel covers x < 0
    uvs = ((g.vertices[g.triangles][..., :2] + 1.0) / 2.0).astype(np.float32)
    texels = np.ones((1, 2, 4), np.float32)
    texels[0, 0, :3], texels[0, 1, :3] = 0.25, 0.75
    floor = dataclasses.replace(scene.materials[1], aov_textures={('mask', 'value'): (texels, 'Closest', 'EXTEND', None)})
    scene = dataclasses.replace(scene, geometry=dataclasses.replace(g, uvs=uvs),
                                materials=[scene.materials[0], floor] + scene.materials[2:])
    _, tint, mask = _passes(scene)
    np.testing.assert_allclose(mask[:, 4:6], 0.5 + 0.75, rtol=1e-6)     # constant + the right texel
    np.testing.assert_allclose(mask[:, 0:3], 1.0, rtol=1e-6)            # the pane ends the pass there
    np.testing.assert_allclose(tint[:, 4:6], np.broadcast_to([0.2, 0.4, 0.6, 1.0], tint[:, 4:6].shape))
    veil = dataclasses.replace(scene, materials=scene.materials[:3] + [dataclasses.replace(
        scene.materials[3], transparency=np.full(3, 0.8, np.float32))])
    _, _, mask = _passes(veil)               # through the pane: the floor's left texel, 0.25
    passed = (mask[:, 0:3] - 1.0) / (0.5 + 0.25)
    assert np.all((passed >= -1e-6) & (passed <= 1 + 1e-6)) and 0.4 < passed.mean() < 0.8


@pytest.mark.parametrize('how', ['object', 'shader'])
@pytest.mark.parametrize('pane', [False, True])
def test_held_out_surfaces_write_their_aovs(how, pane):
    """A held-out surface (object or collection holdout, or a Holdout shader) is transparent to
    the camera and its light and data passes stay 0, but Cycles evaluates its shader, AOV nodes
    included, before the path ends: the floor's AOVs are written there (they were 0), also
    seen through the transparent pane."""
    scene = _scene(0.8, samples=16)
    g = scene.geometry
    floor = g.material == 1
    if how == 'object':
        vis = g.visibility.copy()
        vis[floor] |= sd.HOLDOUT
        scene = dataclasses.replace(scene, geometry=dataclasses.replace(g, visibility=vis))
    else:
        mats = list(scene.materials)
        mats[1] = dataclasses.replace(mats[1], holdout=True)
        scene = dataclasses.replace(scene, materials=mats)
    if not pane:
        keep = g.material != 3
        g = scene.geometry
        scene = dataclasses.replace(scene, geometry=dataclasses.replace(
            g, triangles=g.triangles[keep], material=g.material[keep], normals=g.normals[keep],
            visibility=g.visibility[keep], object_index=g.object_index[keep]))
    film, tint, mask = _passes(scene)
    np.testing.assert_allclose(mask[:, 4:6], 0.5, rtol=1e-6)
    np.testing.assert_allclose(tint[:, 4:6], np.broadcast_to([0.2, 0.4, 0.6, 1.0], tint[:, 4:6].shape), rtol=1e-6)
    assert not film.combined()[:, 4:6].any()            # held out: no light, alpha 0
    if pane:                                             # under the pane (alpha 0.2): pane + floor where passed
        passed = mask[:, 0:3] - 1.0
        assert 0.3 < (passed / 0.5).mean() < 0.9
