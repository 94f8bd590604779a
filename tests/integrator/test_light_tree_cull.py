"""The light tree culls a one-sided area light at points behind it and an area light with a
Spread at points outside its cone (addon/lights/area.py bounds, native/cpp/lighttree.cpp
weigh / weigh8_float), so their light samples go to the lights that can light those points,
and never culls where the light gives anything (which would bias the image).

Before: inside a node's bounding sphere the tree did no culling at all, so ceiling points just
behind a 1 m panel 5 cm under the ceiling picked the panel 98.5% of the time (samples that are
always 0); and an area light's cone was a full hemisphere whatever its Spread, so wall points
picked a 20-degree-spread panel 93% of the time."""

import dataclasses
import math

import numpy as np
import pytest
from dacrt import lamps

from addon.lights import make_lamp
from addon.lights.tree import build_tree

from .scenes import light, ortho_down, pixel_stats, plane_scene, render, rotation_x, translation

F32 = np.float32


def _pdf(tree, P, key, N=None):
    P = np.asarray(P, F32).reshape(-1, 3).T.copy()
    n = P.shape[1]
    if N is not None:
        N = np.repeat(np.asarray(N, F32).reshape(3, 1), n, 1)
    return tree.pdf(P, np.full(n, key, np.int64), N)


def test_points_behind_a_one_sided_area_light_pick_the_other_light():
    """A 1 m panel 5 cm under a ceiling, facing down, and a point light: ceiling points (inside
    the panel's bounding sphere, behind its plane) pick the point light always; points in front
    of the panel still pick it by importance (by Cycles' mean of the shares by the largest and
    smallest importances: the point light, whose smallest is > 0 where the panel's is 0, keeps
    about half, so the panel gets a little under half at worst)."""
    panel = make_lamp(light('AREA', 60.0, translation(0.0, 0.0, 1.95), size_x=1.0))
    bulb = make_lamp(light('POINT', 40.0, translation(0.0, -0.5, 1.0)))
    tree, _ = build_tree([panel, bulb], None, 2)
    ceiling = [(0.0, 0.0, 2.0), (0.4, 0.3, 2.0), (0.0, 0.6, 2.0), (-0.7, -0.7, 2.0), (0.0, 0.0, 1.951)]
    for N in (None, (0.0, 0.0, -1.0)):
        assert np.all(_pdf(tree, ceiling, 0, N) == 0.0)
        np.testing.assert_allclose(_pdf(tree, ceiling, 1, N), 1.0, rtol=1e-12)
    below = [(0.0, 0.0, 1.9), (0.3, 0.2, 1.0), (0.9, 0.9, 0.0), (0.0, 0.0, 1.9499)]
    assert np.all(_pdf(tree, below, 0) > 0.45)
    assert np.all(_pdf(tree, below[:3], 0, (0.0, 0.0, 1.0)) > 0.45)


def test_points_outside_a_narrow_spread_pick_the_other_light():
    """A 0.6 m panel at 1.2 m with Spread 20 degrees lights only the floor below it: wall points
    pick the point light always (as they would not with Spread 180); floor points below it
    still pick the panel."""
    walls = [(0.99, 0.0, 0.5), (0.99, 0.5, 1.0), (0.0, 0.99, 0.3), (0.8, 0.8, 0.0)]
    normals = [(-1, 0, 0), (-1, 0, 0), (0, -1, 0), (0, 0, 1)]
    for deg, culled in ((180.0, False), (20.0, True)):
        panel = make_lamp(light('AREA', 60.0, translation(0.0, 0.0, 1.2), size_x=0.6, spread=math.radians(deg)))
        bulb = make_lamp(light('POINT', 40.0, translation(-0.5, -0.3, 1.6)))
        tree, _ = build_tree([panel, bulb], None, 2)
        for P, N in zip(walls, normals):
            p = _pdf(tree, P, 0, N)[0]
            assert (p == 0.0) if culled else (p > 0.4), (deg, P, p)   # (Cycles' split: see above)
            # the panel's own samples there: all 0 where it is culled
            value = panel.sample(np.repeat(np.asarray(P, F32)[:, None], 64, 1),
                                 *np.random.default_rng(1).random((2, 64), F32)).value
            assert (not culled) or np.all(value == 0.0)
        assert _pdf(tree, (0.0, 0.0, 0.0), 0, (0, 0, 1))[0] > 0.4
        assert _pdf(tree, (0.25, -0.25, 0.0), 0, (0, 0, 1))[0] > 0.3


def _random_area(rng):
    m = np.eye(4)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    m[:3, :3] = q @ np.diag([rng.uniform(0.3, 2.0), rng.uniform(0.3, 2.0), 1.0])
    m[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    spread = rng.choice([math.pi, rng.uniform(0.02, math.pi), rng.uniform(0.01, 0.3)])
    return light('AREA', 50.0, m, shape=str(rng.choice(['SQUARE', 'RECTANGLE', 'DISK', 'ELLIPSE'])),
                 size_x=rng.uniform(0.1, 1.5), size_y=rng.uniform(0.1, 1.5), spread=float(spread))


def test_the_tree_never_culls_a_point_an_area_light_reaches():
    """Random area lights (rotated, scaled, every shape, with and without a Spread), random
    points about them (inside their bounding spheres, a hair in front of or behind their plane,
    at the edge of the spread cone): wherever the tree gives the light probability 0, none of
    the light's own samples there is > 0 (a brute force over a grid of sample positions)."""
    rng = np.random.default_rng(7)
    u = ((np.arange(24) + 0.5) / 24).astype(F32)
    u1, u2 = (a.ravel() for a in np.meshgrid(u, u))
    culled = reached = 0
    for _ in range(60):
        area = make_lamp(_random_area(rng))
        far = make_lamp(light('POINT', 1.0, translation(30.0, 30.0, 30.0)))
        tree, _ = build_tree([area, far], None, 2)
        c = area.center.astype(np.float64)
        n = area.normal.astype(np.float64)
        ext = np.linalg.norm(area.axis_x) + np.linalg.norm(area.axis_y)
        pts = c + rng.normal(size=(80, 3)) * ext
        # a hair in front of and behind the plane, and on it
        near = c + rng.uniform(-0.6, 0.6, (30, 1)) * area.axis_x + rng.uniform(-0.6, 0.6, (30, 1)) * area.axis_y
        pts = np.concatenate([pts, near + n * 1e-4, near - n * 1e-4, near + n * 1e-3, near])
        p = _pdf(tree, pts, 0)
        for P, pk in zip(pts.astype(F32), p):
            if pk > 0.0:
                continue
            value = area.sample(np.repeat(P[:, None], u1.size, 1), u1, u2).value
            assert np.all(value == 0.0), (P, area.center, area.normal)
            culled += 1
        reached += int((p > 0).sum())
    assert culled > 1000 and reached > 1000      # (a test of both sides)


@pytest.mark.parametrize("scale", [1.0, 1e17, 1e-17])
def test_behind_a_flat_light_is_culled_in_float_and_float64_alike(scale):
    """The native tree's two weighs (eight lanes in float; float64 where squared distances
    leave float's range, at 1e17 and 1e-17): a flat one-sided light is 0 behind its plane,
    inside its sphere too, and > 0 in front of it, the same points either way."""
    c = np.array([[0.0, 3.0], [0.0, 0.0], [0.0, 0.0]]) * scale
    half = np.array([[0.5, 0.0], [0.5, 0.0], [0.0, 0.0]]) * scale
    tree = lamps.light_tree((c - half).astype(F32), (c + half).astype(F32),
                            np.array([[0.0, 0.0], [0.0, 0.0], [-1.0, 1.0]]), np.array([1.0, -1.0]),
                            np.array([0.0, 0.0]), np.array([1.0, 1.0]), np.array([0, 1], np.int32))
    z = np.array([1e-3, 0.01, 0.1, 0.3, 2.0])
    xy = np.array([[0.0, 0.0], [0.3, -0.2], [-0.45, 0.45], [0.7, 0.0]])
    front = np.array([(x, y, -h) for x, y in xy for h in z]) * scale
    behind = np.array([(x, y, h) for x, y in xy for h in z]) * scale
    assert np.all(_pdf(tree, front, 0) > 0.0)
    assert np.all(_pdf(tree, behind, 0) == 0.0)
    np.testing.assert_allclose(_pdf(tree, behind, 1), 1.0, rtol=1e-12)


def _plane_with_culled_lights(samples, tree, seed=1):
    """A plane lit by a point light, under a panel 5 cm above it facing up (away: the plane is
    behind it, inside its sphere) and a panel with Spread 30 degrees facing down from 0.6 m (a
    small lit patch): the tree culls the two panels over most of the plane."""
    lights = [light('AREA', 80.0, translation(0.0, 0.0, 0.05) @ rotation_x(math.pi), size_x=1.0),
              _SPREAD_PANEL, light('POINT', 30.0, translation(-0.8, -0.5, 1.0))]
    return plane_scene(lights, samples=samples, max_bounces=1, use_light_tree=tree, seed=seed, camera=_CULL_CAMERA)


_SPREAD_PANEL = light('AREA', 40.0, translation(0.6, 0.3, 0.6), size_x=0.4, spread=math.radians(30.0))
_CULL_CAMERA = ortho_down(height=0.3, width=24, px=24, view=3.0)


def _noise(tree, patch, pairs=8):
    """(inside patch, outside it): the noise per pixel at 4 samples (half the mean squared
    difference of two seeds' red), summed over `pairs` pairs of seeds."""
    total = np.zeros(2)
    for s in range(1, 2 * pairs, 2):
        a, b = (render(_plane_with_culled_lights(4, tree, seed)).film.combined()[..., 0] for seed in (s, s + 1000))
        d = (a - b).astype(np.float64) ** 2 / 2
        total += d[patch].mean(), d[~patch].mean()
    return total


def test_culling_keeps_the_image_and_lowers_its_noise(monkeypatch):
    """The same scene with the tree and with the global choice: the same image mean (within 4
    standard errors of the two: culling what gives nothing moves no mean). Noise per pixel at 4
    samples outside the Spread panel's lit patch, where the tree culls both panels and the point
    light alone is sampled: ~0 (at most 1.6e-5 per seed pair over 400 pairs) against the tree as
    it was (every area light a cone just wider than a hemisphere: no culling inside its sphere, no
    Spread), 0.011-0.018; with only the one-sided panel's culling undone 0.0011-0.0018, only the
    Spread's 0.004-0.007 (40 pairs). Inside the patch the tree pays Cycles' split (the mean of the
    shares by the largest and smallest importances: a Spread narrower than the panel's angular
    size makes its smallest 0 even over its own patch, where the point light's is not, so the
    point light keeps half the samples there): 1.65x the global choice's noise (median over 50
    blocks of 8 seed pairs, at most 2.45x; README), a ceiling of 3x that catches the one-sided
    panel's culling undone (6.7x: it takes the patch's samples)."""
    with_tree = render(_plane_with_culled_lights(256, True))
    assert with_tree.lights.tree is not None and with_tree.lights.tree.members == 3
    without = render(_plane_with_culled_lights(256, False))
    for ch in range(3):
        a, ea = pixel_stats(with_tree, ch)
        b, eb = pixel_stats(without, ch)
        assert abs(a - b) < 4 * np.hypot(ea, eb) + 1e-4 * b, f"channel {ch}: {a} vs {b} (+- {ea}, {eb})"

    patch = render(plane_scene([_SPREAD_PANEL], samples=16, max_bounces=1, camera=_CULL_CAMERA)).film.combined()[..., 0] > 0
    assert 20 < patch.sum() < 100
    culling, chosen = _noise(True, patch), _noise(False, patch)
    import addon.lights.area as area_module
    bounds = area_module.AreaLight.bounds
    monkeypatch.setattr(area_module.AreaLight, 'bounds', lambda self: dataclasses.replace(bounds(self), cos_e=-1e-3))
    uncut = _noise(True, patch)
    assert culling[1] < 0.05 * uncut[1], (culling, uncut)
    assert culling[0] < 3.0 * chosen[0], (culling, chosen)


def _rotation_z(angle):
    m = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def _floor_grid(half=6.0, n=121):
    xs = np.linspace(-half, half, n)
    X, Y = np.meshgrid(xs, xs)
    return np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)


def test_a_tilted_area_light_is_culled_by_its_own_sphere_not_its_box():
    """Fuzz seed 10's lights: a 1.16 m square tilted 44 degrees with Spread 106 degrees, 2.5 m
    over a floor, and a spot. The cone test widens the Spread by the angle the light's bounding
    sphere subtends; that sphere had been its box's (1.08 m, where the square's corners reach
    0.82 m), so floor points just outside the Spread's reach still picked the square, ~3000x
    the spot's energy, and got the spot ~1 sample in 3000 (the spot-lit patch 0.68x Cycles'
    light group at 8192 samples). The points that the square's own sphere culls and its box's
    does not: the tree now gives the square 0 there and the other light 1, and none of the square's own
    samples reaches them (the cull is exact, not a bias)."""
    m = translation(-2.06, -1.65, 2.53) @ _rotation_z(math.radians(-34.0)) @ rotation_x(math.radians(38.0))
    square = make_lamp(light('AREA', 5e4, m, size_x=1.16, spread=math.radians(106.0)))
    bulb = make_lamp(light('POINT', 14.0, translation(0.96, 2.66, 1.94)))      # (the spot, never culled)
    tree, _ = build_tree([square, bulb], None, 2)
    P = _floor_grid()
    c, n = square.center.astype(np.float64), square.normal.astype(np.float64)
    ax, ay = square.axis_x.astype(np.float64), square.axis_y.astype(np.float64)
    v = c - P
    d = np.linalg.norm(v, axis=1)
    theta = np.arccos(np.clip(-(v / d[:, None]) @ n, -1.0, 1.0))     # off the normal, seen from the light
    theta_e = math.radians(53.0) + 2e-3
    own = 0.5 * max(np.linalg.norm(ax + ay), np.linalg.norm(ax - ay))
    box = 0.5 * np.linalg.norm(np.abs(ax) + np.abs(ay))
    assert box > 1.25 * own
    between = (theta - np.arcsin(np.minimum(own / d, 1.0)) > theta_e) & \
              (theta - np.arcsin(np.minimum(box / d, 1.0)) < theta_e - 2e-3)
    assert between.sum() > 100
    N = (0.0, 0.0, 1.0)
    p_square = _pdf(tree, P[between], 0, N)
    assert np.all(p_square == 0.0), f"{(p_square > 0).sum()} of {between.sum()} points still pick the square"
    np.testing.assert_allclose(_pdf(tree, P[between], 1, N), 1.0, rtol=1e-12)
    u = ((np.arange(16) + 0.5) / 16).astype(F32)
    u1, u2 = (a.ravel() for a in np.meshgrid(u, u))
    for p in P[between][::7].astype(F32):
        assert np.all(square.sample(np.repeat(p[:, None], u1.size, 1), u1, u2).value == 0.0)


def test_the_tree_never_culls_a_point_a_spot_of_some_radius_reaches():
    """Random spots with a radius (disk and sphere, blends, scaled cones), random points about
    them and at their cone's edge: where the tree gives the spot probability 0 (its own sphere
    of that radius widening the cone, no longer the sqrt(3)x wider sphere of its box), none of
    its samples there is > 0 (a brute force over a grid of sample positions)."""
    rng = np.random.default_rng(11)
    u = ((np.arange(16) + 0.5) / 16).astype(F32)
    u1, u2 = (a.ravel() for a in np.meshgrid(u, u))
    culled = reached = 0
    for _ in range(40):
        m = np.eye(4)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        m[:3, :3] = q @ np.diag([rng.uniform(0.5, 2.0), rng.uniform(0.5, 2.0), 1.0])
        m[:3, 3] = rng.uniform(-1.0, 1.0, 3)
        spot = make_lamp(light('SPOT', 50.0, m, radius=rng.uniform(0.05, 1.0), soft_falloff=bool(rng.random() < .5),
                               spot_size=rng.uniform(0.2, 2.6), spot_blend=rng.uniform(0.0, 1.0)))
        far = make_lamp(light('POINT', 1.0, translation(30.0, 30.0, 30.0)))
        tree, _ = build_tree([spot, far], None, 2)
        pts = spot.center.astype(np.float64) + rng.normal(size=(150, 3)) * rng.uniform(0.3, 3.0)
        p = _pdf(tree, pts, 0)
        for P, pk in zip(pts.astype(F32), p):
            if pk > 0.0:
                continue
            value = spot.sample(np.repeat(P[:, None], u1.size, 1), u1, u2).value
            assert np.all(value == 0.0), (P, spot.center)
            culled += 1
        reached += int((p > 0).sum())
    assert culled > 500 and reached > 500      # (a test of both sides)
