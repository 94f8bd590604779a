"""Poly curves end in hemispherical caps (addon/hair.py), as Cycles' round linear curves (Embree's
cone segments with a sphere at each point) do; Catmull-Rom tubes stay open, as Cycles' swept
circles are."""
import math

import numpy as np
import pytest

from addon import hair


def _areas(v, t):
    c = v[t].astype(np.float64)
    return 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)


@pytest.mark.parametrize('level', hair.LADDER)
def test_a_straight_poly_strand_has_the_area_of_a_cylinder_and_a_sphere(level):
    """By Cauchy's formula a convex strand covers, on average over view directions, a quarter of
    its area: the tube's 2 pi r L and the two caps' 4 pi r^2. Every face points away from the axis's
    nearest point, the caps reach no further than 1.3 radii past the ends, and the vertex normals
    are unit, the poles' along the axis."""
    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    r = 0.1
    v, t, n, kept = hair.tubes(p, np.full(2, r), [0, 2], level, linear=True)
    assert kept == 1 and len(t) == hair.triangle_count([0, 2], level, linear=True)
    assert _areas(v, t).sum() == pytest.approx(2 * math.pi * r * 1.0 + 4 * math.pi * r * r, rel=1e-6)
    c = v[t].astype(np.float64).mean(axis=1)
    axis_point = np.stack([np.zeros(len(c)), np.zeros(len(c)), np.clip(c[:, 2], 0.0, 1.0)], 1)
    tn = np.cross((v[t[:, 1]] - v[t[:, 0]]).astype(np.float64), (v[t[:, 2]] - v[t[:, 0]]).astype(np.float64))
    assert (np.einsum('ij,ij->i', tn, c - axis_point) > 0).all()
    assert -1.3 * r < v[:, 2].min() < -r and 1 + r < v[:, 2].max() < 1 + 1.3 * r
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-6)
    assert np.allclose(n[np.argmin(v[:, 2])], (0, 0, -1), atol=1e-6)
    assert np.allclose(n[np.argmax(v[:, 2])], (0, 0, 1), atol=1e-6)


def test_catmull_rom_tubes_stay_open():
    """Cycles' 3D Curves (Catmull-Rom) sweep a circle along the curve and end open there: the
    tube's area is the cylinder's alone."""
    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.5], [0.0, 0.0, 1.0]])
    v, t, n, kept = hair.tubes(p, np.full(3, 0.1), [0, 3], (16, 4))
    assert _areas(v, t).sum() == pytest.approx(2 * math.pi * 0.1, rel=1e-6)
    assert v[:, 2].min() > -1e-6 and v[:, 2].max() < 1 + 1e-6


def test_caps_of_bent_and_tipped_poly_curves_count_and_have_area():
    """Curves with sharp turns, a tip of radius 0 and a curve of one point: triangle_count bounds
    the triangles, none has no area (it would be reported as the user's degenerate geometry), a
    tip ends in no cap, and each triangle belongs to its curve."""
    zig = np.array([[0, 0, 0], [1, 0, 1], [2, 0, 0], [2.2, 0, 1.5]], np.float64)
    pts = np.concatenate([zig, [[5, 5, 5]], zig + (0, 3, 0)])
    radii = np.concatenate([[0.1, 0.1, 0.1, 0.0], [0.1], [0.05, 0.1, 0.1, 0.1]])
    offsets = [0, 4, 5, 9]
    for level in ((16, 4), (8, 2), (3, 1)):
        v, t, n, kept, curve = hair.tubes(pts, radii, offsets, level, linear=True, curve_of=True)
        assert kept == 2
        assert len(t) <= hair.triangle_count(offsets, level, True, pts) <= hair.triangle_count(offsets, level, True)
        assert (_areas(v, t) > 1e-9).all()
        # the tipped end (radius 0 at (2.2, 0, 1.5)) grows no cap past its point
        tipped = v[t[curve == 0]].reshape(-1, 3).astype(np.float64)
        assert np.linalg.norm(tipped - zig[3], axis=1).min() < 1e-6
        assert (tipped[:, 2] <= 1.5 + 1e-6).all()
        # the other ends do, a radius (of their own point) past it: the first curve's first
        # point, the third curve's both ends
        back = (zig[0] - zig[1]) / np.linalg.norm(zig[0] - zig[1])
        ahead = (zig[3] - zig[2]) / np.linalg.norm(zig[3] - zig[2])
        other = v[t[curve == 2]].reshape(-1, 3).astype(np.float64) - (0, 3, 0)
        assert (tipped @ back).max() > 0.1 and (other @ back).max() > 0.05
        assert ((other - zig[3]) @ ahead).max() > 0.1
