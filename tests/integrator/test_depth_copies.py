"""Materials built per bounce depth (scenedata.Material.depth_class, export/rayvariants.py): the
bounce rays arriving at the first vertex see the copies of class 1, deeper ones those of class 2
(Integrator's 'bounce_deep' scene), each never both. A floor under a point lamp and a ceiling
that bounce rays alone see: with the ceiling's two copies alike the image is (to float rounding) the
image of one ceiling; with the deeper copy black, paths end at their second ceiling hit, as a
Max Bounces of 2 ends them."""
import dataclasses

import numpy as np

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, ortho_down, quad, render, translation


def _floor_and_ceiling(deep_albedo=None, max_bounces=4):
    """The floor (0.8) at z = 0, a point lamp at z = 0.5, a 0.6 ceiling at z = 1 that only
    bounce and shadow rays see; with deep_albedo, the ceiling's copy for deeper bounce rays."""
    parts = [(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS),
             (*quad((0.0, 0.0, 1.0), 100.0, 100.0, up=False), 2, sd.VIS_DIFFUSE | sd.VIS_SHADOW)]
    ceiling = material('ceiling', (0.6,) * 3)
    mats = [material('default'), material('floor', (0.8,) * 3), ceiling]
    if deep_albedo is not None:
        mats[2] = dataclasses.replace(ceiling, depth_class=1)
        mats.append(dataclasses.replace(ceiling, base_color=np.full(3, deep_albedo, np.float32), depth_class=2,
                                        visibility=sd.VIS_DIFFUSE, variant_of=2))
        parts.append((*quad((0.0, 0.0, 1.0), 100.0, 100.0, up=False), 3, sd.VIS_DIFFUSE | sd.NO_TRANSMISSION))
    lamp = light('POINT', 30.0, translation(z=0.5), radius=0.0)
    scene = sd.SceneData(ortho_down(height=0.4), geometry(parts), mats, [lamp], np.zeros(3, np.float32),
                         sd.Settings(samples=32, filter_type='BOX', max_bounces=max_bounces))
    return render(scene).film.combined()[..., :3]


def test_copies_alike_render_as_one_surface():
    # (the same paths: only the tracer scenes differ, so hits agree to float rounding)
    np.testing.assert_allclose(_floor_and_ceiling(0.6), _floor_and_ceiling(), rtol=1e-4)


def test_deeper_bounce_rays_see_the_deeper_copy_alone():
    cut = _floor_and_ceiling(0.0)
    np.testing.assert_allclose(cut, _floor_and_ceiling(max_bounces=2), rtol=1e-4)
    assert cut.mean() < 0.99 * _floor_and_ceiling().mean()      # (the deeper light it drops)
