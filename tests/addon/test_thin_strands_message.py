"""Hair too thin for float32 where it renders: the renderer centres the scene on the geometry
around the camera (sceneprep.recentred), so hair 800 m off through a long lens keeps coordinates
of 800, where float32's spacing (6.1e-5) exceeds a strand of radius 5e-5: its tubes round out of
shape (Cycles 0.0475, DACRT 0.0414 here), which had been said nothing. The render now says
which hair (sceneprep.rounded_strands); hair near the render's origin is not said."""
import math

import numpy as np
import pytest

from tests.parity import rendering

from . import scenes

SAID = "of their tube triangles are thinner than float32 can hold"


@pytest.mark.parametrize('distance', [0.3, 800.0])
def test_strands_thinner_than_float32_where_they_are_are_said(scene, said, distance):
    t = np.linspace(0, 1, 4)[:, None]
    rng = np.random.default_rng(1)
    base = np.stack([rng.uniform(-0.05, 0.05, 300), np.zeros(300), rng.uniform(-0.05, 0.05, 300)], 1)
    scenes.hair_curves('Hair', [b + t * [0, 0, 0.06] + [0, distance, 0] for b in base], radius=5e-5,
                       material=scenes.emission('e', (1, 1, 1), 1.0))
    cam = scenes.camera(location=(0, 0, 0.03), rotation=(math.radians(90), 0, 0))
    cam.data.lens, cam.data.clip_end = 50 * distance / 0.3, 2 * distance
    scenes.plane('Ground', 4.0, location=(0, 0, -1), materials=[scenes.diffuse('g', (0.5, 0.5, 0.5))])
    scenes.black_world()
    rendering.matched(scene, 4, 0)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    said.clear()
    assert scenes.render_rgba()[..., 0].mean() > 0.01        # the hair is in view
    got = [t for t in said if SAID in t]
    if distance < 1.0:
        assert got == [], got
    else:
        assert len(got) == 1 and got[0].startswith("hair or curves of 'Hair': "), got


COINCIDE = "coincide with other triangles: rendered as one surface"


NEAR = "repeat other emissive triangles up to rounding"


@pytest.mark.parametrize('copies, strands', [(1, 300), (1, 100), (2, 300)])
def test_tapering_tips_thinner_than_float32_near_the_origin_are_not_said(scene, said, tmp_path, copies, strands):
    """Fur whose radius falls steeply to 0 at the tips (Shape 0.9: (1 - t)^10, radii down to
    1e-9) always ends thinner than float32 near the tip, wherever it is: those tip triangles
    round, some onto each other, but the area they can move is a negligible share of the
    tubes' and the image is Cycles'. rounded_strands had said 'out of shape' of every such scene
    (and gone through all its tube triangles on every render), and the rounded-together tip
    triangles had been said to be coincident emitters Cycles renders darker (Cycles' curves have
    no such triangles), or, where the emitters are few enough to compare (100 strands), to
    repeat each other up to rounding, 'up to twice as bright as in Cycles'. A second copy of the
    whole fur in place is the user's and still said."""
    t = np.linspace(0, 1, 5)[:, None]
    rng = np.random.default_rng(1)
    base = np.stack([rng.uniform(-0.05, 0.05, strands), np.zeros(strands), rng.uniform(-0.05, 0.05, strands)], 1)
    radius = np.tile(2e-3 * (1 - t[:, 0]) ** 10, strands)
    assert 0 < radius[radius > 0].min() < 1e-8
    for k in range(copies):
        scenes.hair_curves(f'Fur{k}', [b + t * [0, 0, 0.06] + [0, 0.3, 0] for b in base], radius=radius,
                           material=scenes.emission('e', (1, 1, 1), 1.0))
    cam = scenes.camera(location=(0, 0, 0.03), rotation=(math.radians(90), 0, 0))
    cam.data.clip_end = 1.0
    scenes.plane('Ground', 4.0, location=(0, 0, -1), materials=[scenes.diffuse('g', (0.5, 0.5, 0.5))])
    scenes.black_world()
    rendering.matched(scene, 16, 0)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    said.clear()
    if copies == 1:
        images = scenes.render_engines(scene, tmp_path)
        cycles, dacrt = (images[e]['ViewLayer.Combined.R'] for e in ('CYCLES', 'DACRT'))
        assert cycles.mean() > 0.01                                 # the fur is in view
        assert abs(dacrt.mean() / cycles.mean() - 1) < 0.05, (dacrt.mean(), cycles.mean())
    else:
        scenes.render_rgba()
    assert [t for t in said if SAID in t] == [], said
    assert [t for t in said if NEAR in t] == [], said
    coincide = [t for t in said if COINCIDE in t]
    if copies == 1:
        assert coincide == [], coincide
    else:
        assert len(coincide) == 1 and "'Fur0', 'Fur1'" in coincide[0], coincide
