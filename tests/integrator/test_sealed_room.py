"""A sealed room stays black with a white world and a sun outside (Cycles: exactly 0).

A hit point next to an edge is reconstructed from its barycentrics an ULP or so past the edge;
where the neighbour across it is a wall at an angle (where a room's floor meets a wall), that is
outside the wall, and the self-intersection step along the hit triangle's own normal runs
parallel to the wall. Bounce and shadow rays leaving there toward the outside met nothing: the
fuzzer's 6 m box room lit ~1 pixel per 1.5M camera paths with a full world or sun sample. Here
an orthographic camera a few ULPs wide looks straight down at the floor just inside a wall, so
that every camera hit lies within those ULPs of the edge: the old reconstruction lit 68 of 1536
pixels at scale 1 (gap 2 ULPs, 8 ULPs wide). P now keeps the self-intersection step's length
off every edge of its triangle (native pathvertex.h inside_edges).
"""
from __future__ import annotations

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, render, rotation_x, translation
from .test_thin_walls import _box


def edge_scene(scale, seed, samples=16, gap_ulps=2.0, view_ulps=8.0, open_wall=False):
    """The closed room (-3..3)^2 x (0..3) x scale (open_wall: without its x = +3 wall); an
    orthographic camera 32 x 24 pixels, `view_ulps` ULPs of the wall's coordinate wide, looking
    straight down at the floor, its nearest pixels `gap_ulps` from the wall x = +3."""
    v, t = _box((-3.0 * scale, -3.0 * scale, 0.0), (3.0 * scale, 3.0 * scale, 3.0 * scale))
    if open_wall:
        t = t[[i for i in range(len(t)) if i not in (6, 7)]]
    ulp = float(np.spacing(np.float32(3.0 * scale)))
    half = view_ulps * ulp / 2
    cam = translation(3.0 * scale - (gap_ulps * ulp + half), 0.3 * scale, 1.5 * scale)
    camera = sd.Camera('ORTHO', cam, (-half, half, -half * 0.75, half * 0.75), 0.0, 0.1 * scale, 10.0 * scale, 32, 24)
    sun = light('SUN', 5.0, rotation_x(0.4), angle=0.1)
    return sd.SceneData(camera, geometry([(v, t, 1, ALL_VIS)]), [material('default'), material('white')],
                        [sun], np.ones(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=2, filter_type='BOX', seed=seed))


@pytest.mark.parametrize("scale", [1.0, 1e-3, 1e3, 1e4])
def test_no_light_enters_a_sealed_room_by_its_edges(scale):
    """Every pixel exactly 0 (the old reconstruction lit 68 of these 1536 pixels at scale 1)."""
    for seed in (0, 1):
        integ = render(edge_scene(scale, seed))
        img = integ.film.combined()[..., :3]
        assert integ.stats['rays']['bounce'] > 0
        lit = int((img.sum(-1) > 0).sum())
        assert lit == 0, f"seed {seed}: {lit} pixels lit inside a sealed room (max {img.max():.3g})"


def test_the_floor_by_an_opened_wall_is_lit():
    """Without the wall the same view is lit (the room above is not black for want of light
    reaching that floor)."""
    img = render(edge_scene(1.0, 0, samples=4, open_wall=True)).film.combined()[..., :3]
    assert (img.sum(-1) > 0).mean() > 0.9
