"""Bump heights bend the shading normal per point (Integrator._bent_normals, bump.bend): against
closed forms. A height a x on the plane z = 0 gives N = normalize((-distance a, 0, 1)); a height
sin(k x) the normal of that slope at each point; strength mixes towards the unbent normal;
Invert and a back face; Cycles' surface-gradient formula (svm_node_set_bump) at finite
differentials tends to the same normal. Before, Bump nodes were ignored (reported): N stayed
(0, 0, 1). Within 1e-3: the heights read float32 coordinates, as the textures do, which round
by some 1e-4 of the difference step where x is near 2."""
from __future__ import annotations

import dacrt
import numpy as np
import pytest

from addon import bump as bumpmap
from addon import scenedata as sd
from addon.integrator import Integrator
from addon.procedural import ProceduralTexels

from . import scenes


def _integrator(height, strength=1.0, distance=1.0, size=2.0, needs=('position',), displacement=False,
                normals=None, linear=None, object_height=False, object_space=False, filter_width=0.1):
    """An Integrator over a plane z = 0 (2 triangles, +-size) whose material bumps with
    height(coords) -> (n,), at that strength, distance and Filter Width; linear: its
    placement's 3x3 map."""
    def values(c):
        h = np.asarray(height(c), np.float64)
        return np.stack([h, np.full(len(h), strength), np.full(len(h), distance)], axis=1)
    b = sd.Bump(ProceduralTexels(values, frozenset(needs), 'height'), object_height, object_space, filter_width)
    v, t = scenes.quad((0.0, 0.0, 0.0), size, size)
    mat = scenes.material('bumpy', bumps=() if displacement else (b,), displacement_bump=b if displacement else None)
    geo = scenes.geometry([(v, t, 1, scenes.ALL_VIS)])
    if normals is not None:
        geo.normals = normals
    if linear is not None:
        geo.instance = np.zeros(len(geo.triangles), np.int32)
        geo.tangent_xf = np.asarray(linear, np.float32)[None]
    scene = sd.SceneData(scenes.ortho_down(view=4.0), geo, [scenes.material('default'), mat], [],
                         np.zeros(3, np.float32), sd.Settings(samples=1, max_bounces=0))
    return Integrator(scene)


def _hits(integ, xy):
    """(prim, u, v) float32 of points (n, 2) on the plane's triangles."""
    g = integ.tri.geo
    out = []
    for x, y in xy:
        for p in range(g.shape[1]):
            p0, e1, e2 = g[0:3, p].astype(np.float64), g[3:6, p].astype(np.float64), g[6:9, p].astype(np.float64)
            A = np.stack([e1[:2], e2[:2]], axis=1)
            u, v = np.linalg.solve(A, np.array([x, y]) - p0[:2])
            if u >= -1e-9 and v >= -1e-9 and u + v <= 1 + 1e-9:
                out.append((p, u, v))
                break
    prim, u, v = (np.array(c) for c in zip(*out))
    return prim.astype(np.int32), u.astype(np.float32), v.astype(np.float32)


def _bent(integ, xy, up=1.0):
    prim, u, v = _hits(integ, xy)
    n = np.zeros((3, len(prim)), np.float32)
    n[2] = up
    bent, bump = integ._bent_normals(prim, u, v, n, n.copy())
    return bent.astype(np.float64), bump


@pytest.mark.parametrize('a,distance', [(0.5, 1.0), (2.0, 0.3), (-1.0, 1.0), (0.5, -1.0)])
def test_a_linear_height_tilts_the_plane_by_its_slope(a, distance):
    integ = _integrator(lambda c: a * c['position'][:, 0], distance=distance)
    xy = np.random.default_rng(1).uniform(-1.8, 1.8, (64, 2))
    N, bump = _bent(integ, xy)
    want = np.array([-distance * a, 0.0, 1.0]) / np.hypot(distance * a, 1.0)
    np.testing.assert_allclose(N.T, np.broadcast_to(want, (64, 3)), atol=1e-3)
    np.testing.assert_array_equal(bump[:3], np.array([[0], [0], [1]], np.float32) * np.ones((1, 64)))
    assert (bump[3] == 1).all()                      # Bump Map Correction on, as the default


def test_a_sine_height_bends_each_point_by_its_own_slope():
    k, amp = 3.0, 0.2
    # (a Filter Width of 0.001: Cycles' forward taps over this 8-pixel render's 0.5-wide pixels
    # at the default 0.1 see the slope 0.025 further on; the limit is the slope at the point)
    integ = _integrator(lambda c: amp * np.sin(k * c['position'][:, 0]), distance=1.0, filter_width=1e-3)
    xy = np.random.default_rng(2).uniform(-1.9, 1.9, (200, 2))
    N, _ = _bent(integ, xy)
    slope = amp * k * np.cos(k * xy[:, 0])
    want = np.stack([-slope, np.zeros_like(slope), np.ones_like(slope)], axis=1) / np.hypot(slope, 1)[:, None]
    np.testing.assert_allclose(N.T, want, atol=1e-3)


@pytest.mark.parametrize('strength', [0.5, 0.0, 2.0])
def test_strength_mixes_the_bent_normal_with_the_unbent_one(strength):
    a = 1.5
    integ = _integrator(lambda c: a * c['position'][:, 0], strength=strength)
    N, _ = _bent(integ, [(0.3, 0.2), (-0.5, 1.0)])
    full = np.array([-a, 0.0, 1.0]) / np.hypot(a, 1.0)
    s = max(strength, 0.0)
    mixed = s * full + (1 - s) * np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(N[:, 0], mixed / np.linalg.norm(mixed), atol=1e-3)


def test_uv_and_position_heights_agree_and_a_back_face_bends_the_same_gradient():
    """A height on UV (u = (x + 2) / 4 on this plane) moves with its own coordinate: the same
    tilt as the same height on position; seen from below (N = -Z) the gradient is the same
    vector, so N' = normalize(-Z - d g)."""
    a = 0.8
    pos = _integrator(lambda c: a * c['position'][:, 0])
    v, t = scenes.quad((0.0, 0.0, 0.0), 2.0, 2.0)
    geo_uv = np.stack([(v[t][..., 0] + 2.0) / 4.0, (v[t][..., 1] + 2.0) / 4.0], axis=-1).astype(np.float32)
    uvi = _integrator(lambda c: 4.0 * a * c['uv'][:, 0], needs=('uv',))
    uvi.tri.uvs = dacrt.shading.corner_rows(np.ascontiguousarray(geo_uv))
    xy = [(0.1, 0.4), (-1.2, -0.7)]
    np.testing.assert_allclose(_bent(uvi, xy)[0], _bent(pos, xy)[0], atol=1e-3)
    below, _ = _bent(pos, xy, up=-1.0)
    want = np.array([-a, 0.0, -1.0]) / np.hypot(a, 1.0)
    np.testing.assert_allclose(below[:, 0], want, atol=1e-3)


def test_a_displacement_bump_sets_the_shading_normal_itself():
    """Read as bump, a Displacement output's height bends the normal the closures start from:
    bump shadowing then compares it with itself (rows 0-2 of bump are the bent normal)."""
    a = 0.5
    integ = _integrator(lambda c: a * c['position'][:, 0], displacement=True)
    N, bump = _bent(integ, [(0.2, 0.3)])
    want = np.array([-a, 0.0, 1.0]) / np.hypot(a, 1.0)
    np.testing.assert_allclose(N[:, 0], want, atol=1e-3)
    np.testing.assert_allclose(bump[:3, 0], want, atol=1e-3)


def test_cycles_surface_gradient_at_small_differentials_tends_to_bend():
    """svm_node_set_bump's formula with the differentials of a tilted, skewed frame (any two
    directions in the plane) and a smooth normal off the face's: the same normal as bend()."""
    rng = np.random.default_rng(3)
    Ng = np.array([0.2, -0.1, 1.0]) / np.linalg.norm([0.2, -0.1, 1.0])
    t1 = np.cross(Ng, [1.0, 0.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(Ng, t1)
    N = Ng + np.array([0.05, 0.08, 0.0])
    N /= np.linalg.norm(N)
    grad = np.array([0.7, -0.4, 0.3])

    def h(p):
        return grad @ p + 0.3 * np.sin(p[0])
    P = rng.normal(size=3)
    P -= (P @ Ng) * Ng
    dx, dy = 1e-4 * (t1 + 0.3 * t2), 1e-4 * (-0.2 * t1 + t2)
    hc, hx, hy = h(P), h(P + dx), h(P + dy)
    rx, ry = np.cross(dy, N), np.cross(N, dx)
    det = dx @ rx
    surf = (hx - hc) * rx + (hy - hc) * ry
    d = 0.6
    cyc = np.abs(det) * N - d * np.sign(det) * surf
    cyc /= np.linalg.norm(cyc)
    e1, e2 = t1 * 2.0, t1 + t2
    dh1 = (h(P + 1e-6 * e1) - h(P - 1e-6 * e1)) / 2e-6
    dh2 = (h(P + 1e-6 * e2) - h(P - 1e-6 * e2)) / 2e-6
    ours = bumpmap.bend(N[:, None], e1[:, None], e2[:, None], [dh1], [dh2], [d], [1.0])[:, 0]
    np.testing.assert_allclose(ours, cyc, atol=1e-4)


@pytest.mark.parametrize('linear,object_space,factor', [
    (np.diag([1.0, 1.0, 3.0]), False, 3.0),          # |M^T N| = 3: the displacement 3x as long
    (np.diag([0.5, 4.0, 1.0]), False, 1.0),          # scaled in the plane: no longer along N
    (2.0 * np.eye(3), True, 4.0),                    # and bent in object space: the gradient 2x again
    (np.diag([1.0, 1.0, 3.0]), True, 9.0)])          # the object-space normal back by M^-T: 3x steeper again
def test_an_object_space_displacement_takes_the_object_scale_along_the_normal(linear, object_space, factor):
    """A Displacement node in object space (Bump.object_height): the height times |M^T N|; the
    bump of Displacement and Bump (object_space) bends N in object space. The plane's own
    geometry is world space here: only the height's factor and the frame change."""
    a = 0.3
    integ = _integrator(lambda c: a * c['position'][:, 0], displacement=True, linear=linear,
                        object_height=True, object_space=object_space)
    N, _ = _bent(integ, [(0.2, 0.3), (-1.0, 0.5)])
    want = np.array([-factor * a, 0.0, 1.0]) / np.hypot(factor * a, 1.0)
    np.testing.assert_allclose(N.T, np.broadcast_to(want, (2, 3)), atol=1e-3)


def test_the_difference_step_follows_the_pixel_footprint_within_the_scene_bounds():
    """The footprint times the Filter Width (a tenth by default, as Cycles' taps), at least 1e-6
    of the scene's extent: a small object near a perspective camera in a large scene is
    differentiated inside its own features, and a wide footprint is not capped (1e-4 of the
    extent had been: a wider Filter Width softened nothing)."""
    np.testing.assert_allclose(bumpmap.step_lengths([1e-3, 10.0, 1e-9], 100.0), [1e-4, 1.0, 1e-4])
    np.testing.assert_allclose(bumpmap.step_lengths([1e-3, 10.0], 100.0, 4.0), [4e-3, 40.0])
    integ = _integrator(lambda c: c['position'][:, 0])
    cam = integ.camera                                   # orthographic, 4 wide over 8 pixels
    np.testing.assert_allclose(integ._footprint(np.zeros((3, 2))), [0.5, 0.5])
    assert cam.kind == 'ORTHO'
