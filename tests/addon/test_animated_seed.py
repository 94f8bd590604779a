"""Use Animated Seed (scene.dacrt.use_animated_seed, Cycles' option of the same name): each frame
of a still scene gets its own noise, the same on every render of that frame; off, every frame has
the seed's. And Cycles' Simplify > Culling, which DACRT does not apply, is said."""
import numpy as np

from addon.demo import build_demo_scene
from addon.export.settings import frame_seed

from . import scenes


def _frame(scene, frame, animated):
    scene.dacrt.use_animated_seed = animated
    scene.frame_set(frame)
    return scenes.render_rgba(scene)


def test_animated_seed_changes_the_noise_per_frame_and_only_then(scene):
    build_demo_scene(scene, resolution=32, samples=2)
    one, two, again = _frame(scene, 1, True), _frame(scene, 2, True), _frame(scene, 1, True)
    assert not np.array_equal(one, two) and np.array_equal(one, again)
    assert abs(one[..., :3].mean() - two[..., :3].mean()) < 0.1 * one[..., :3].mean()   # the same scene
    assert np.array_equal(_frame(scene, 1, False), _frame(scene, 2, False))


def test_frame_seeds_are_distinct_and_in_range():
    seeds = {frame_seed(0, f) for f in range(-50, 1000)} | {frame_seed(7, 1, s / 10) for s in range(1, 10)}
    assert len(seeds) == 1050 + 9 and all(0 <= s < 2 ** 31 for s in seeds)
    assert frame_seed(3, 5) == frame_seed(3, 5) != frame_seed(4, 5)


def test_cycles_culling_is_said_not_applied(scene, said):
    build_demo_scene(scene, resolution=8, samples=1)
    scene.render.use_simplify = True
    scene.cycles.use_camera_cull = True
    scenes.render_rgba(scene)
    assert any("Culling (camera) is not applied" in t for t in said), said


def test_a_nan_subframe_renders_with_its_own_seed(scene, said):
    """A script's frame_set(f, subframe=nan) keeps the NaN (Blender; Cycles 5.0.1 renders it):
    the animated seed read it through int(), which failed the render ('cannot convert float NaN
    to integer'). It is read as Cycles' conversion gives it on x86, INT_MIN."""
    assert 0 <= frame_seed(3, 5, float('nan')) < 2 ** 31
    assert frame_seed(3, 5, float('nan')) == frame_seed(3, 5, float('nan')) != frame_seed(3, 5)
    build_demo_scene(scene, resolution=16, samples=2)
    scene.dacrt.use_animated_seed = True
    scene.frame_set(1, subframe=float('nan'))
    assert scene.frame_subframe != scene.frame_subframe
    img = scenes.render_rgba(scene)
    assert not [t for t in said if "failed" in t], said
    assert np.isfinite(img).all() and img[..., :3].mean() > 0.01
    assert np.array_equal(img, scenes.render_rgba(scene))
