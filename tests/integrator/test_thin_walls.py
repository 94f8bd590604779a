"""Thin walls far from the origin: the self-intersection step never carries a path through.

A hit point steps off its triangle by 8 ULPs of the triangle's largest coordinate
(surfacetables.OFFSET_ULPS): 7.8 mm at 10 km, where a wide scene (a ground plane around the
origin) keeps the renderer from recentring. Where a ray met a wall's back from inside at t ~ 0
(a path hitting a side wall within a ULP of the wall, its next ray starting on the wall's
plane), the step toward the side it came from crossed a wall of a few millimetres and its light
samples saw the lit room (a helper's scene: 13 of 3072 pixels lit at 64 spp where Cycles has
none). The step is now at most half the distance the ray's origin lay off the plane.
"""
from __future__ import annotations

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, render, translation


def _box(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
                  (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], np.float64)
    f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
         (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return v, np.array(f)


def two_rooms(thickness, x0, samples, max_bounces, from_lit=False):
    """A closed 4 x 2 x 2 m room at x = x0 split by a closed slab `thickness` thick that pierces
    its walls (no coplanar faces); a point light in the right half, the camera in the left half
    looking at the slab (from_lit: in the right half); a 50 km ground plane around the origin
    below (no recentring)."""
    room = _box((x0 - 2, -1, 0), (x0 + 2, 1, 2))
    slab = _box((x0 - thickness / 2, -1.1, -0.1), (x0 + thickness / 2, 1.1, 2.1))
    g = 2.5e4
    ground = (np.array([(-g, -g, -1), (g, -g, -1), (g, g, -1), (-g, g, -1)], np.float64),
              np.array([(0, 1, 2), (0, 2, 3)]))
    cam = np.eye(4)
    side = -1 if from_lit else 1
    cam[:3, 0], cam[:3, 1], cam[:3, 2] = (0, -side, 0), (0, 0, 1), (-side, 0, 0)   # looking along side * x
    cam[:3, 3] = (x0 - 1.9 * side, 0, 1)
    camera = sd.Camera('PERSP', cam, (-4 / 3, 4 / 3, -1.0, 1.0), 1.0, 0.01, 100.0, 64, 48)
    lamp = light('POINT', 200.0, translation(x0 + 0.5, 0, 1), radius=0.0)
    return sd.SceneData(camera, geometry([(*room, 1, ALL_VIS), (*slab, 1, ALL_VIS), (*ground, 1, ALL_VIS)]),
                        [material('default'), material('white', (0.8, 0.8, 0.8))], [lamp],
                        np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=max_bounces, filter_type='BOX'))


@pytest.mark.parametrize("thickness", [3e-3, 5e-3])
def test_no_light_through_millimetre_walls_ten_km_out(thickness):
    """The dark half stays black (the old step lit 18-19 of its 3072 pixels at 256 spp)."""
    integ = render(two_rooms(thickness, 1e4, samples=256, max_bounces=2))
    img = integ.film.combined()[..., :3]
    assert integ.stats['rays']['bounce'] > 0
    lit = int((img.sum(-1) > 0).sum())
    assert lit == 0, f"{lit} pixels of the dark room lit through a {thickness * 1e3:g} mm wall"


def test_the_lit_half_is_lit():
    """The same scene seen from the lit half (the test above is not black for want of light)."""
    img = render(two_rooms(5e-3, 1e4, samples=4, max_bounces=2, from_lit=True)).film.combined()[..., :3]
    assert (img.sum(-1) > 0).mean() > 0.99
