"""Hair tessellation and export fixes checked without Cycles (addon/hair.py,
addon/export/strands.py)."""
import math

import numpy as np
import pytest

from addon import hair


def _tri_normals(v, t):
    v = v.astype(np.float64)
    return np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])


def _off_axis(points, direction):
    """Distance of each point from the line through the origin along unit `direction`."""
    return np.linalg.norm(points - np.outer(points @ direction, direction), axis=-1)


@pytest.mark.parametrize('turn', [30.0, 90.0, 150.0, 180.0])
@pytest.mark.parametrize('linear', [True, False])
def test_a_turn_keeps_the_width_of_each_segment(turn, linear):
    """Two Poly segments of length 1 meeting at the origin with a turn: the joint's rings are
    mitred (a turn past MAX_TURN_POLY split into several), so the first lies on the incoming segment's
    cylinder and the last on the outgoing one's, the tube 2r wide up to the joint, where a ring
    square to the mean tangent had shown cos(turn / 2) of it (a 150-degree turn: a quarter).
    No triangle without area (reported as degenerate geometry), and triangle_count bounds them."""
    a = math.radians(turn)
    d_in, d_out = np.array([1.0, 0, 0]), np.array([math.cos(a), math.sin(a), 0])
    p = np.stack([-d_in, np.zeros(3), d_out])
    sides, steps = 16, 4
    v, t, n, kept = hair.tubes(p, np.full(3, 0.1), [0, 3], (sides, steps), linear=linear)
    assert kept == 1
    assert (0.5 * np.linalg.norm(_tri_normals(v, t), axis=1) > 1e-9).all()
    exact = hair.triangle_count([0, 3], (sides, steps), linear, p)
    assert len(t) <= exact <= hair.triangle_count([0, 3], (sides, steps), linear)
    if not linear:
        return
    rings = v.astype(np.float64).reshape(-1, sides, 3)
    joint = rings[np.linalg.norm(rings.mean(axis=1), axis=1) < 1e-6]
    assert len(joint) == math.ceil(turn / 45 - 1e-9)          # Poly: MAX_TURN_POLY, to round as Cycles' sphere
    scale = np.pi / (sides * np.sin(np.pi / sides))
    np.testing.assert_allclose(_off_axis(joint[0], d_in), 0.1 * scale, rtol=1e-5)
    np.testing.assert_allclose(_off_axis(joint[-1], d_out), 0.1 * scale, rtol=1e-5)


def test_a_nan_radius_leaves_no_nan_vertex():
    p = np.stack([np.zeros(6), np.zeros(6), np.linspace(0, 1, 6)], 1)
    r = np.full(6, 0.1)
    r[2] = np.nan
    v, t, n, kept = hair.tubes(p, r, [0, 6], (8, 2))
    assert np.isfinite(v).all() and np.isfinite(n).all() and 0 < len(t) < hair.triangle_count([0, 6], (8, 2), False, p)
