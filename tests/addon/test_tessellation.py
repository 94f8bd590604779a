"""Point clouds as spheres and hair curves as tubes (addon/pointcloud.py, addon/hair.py),
against geometry computed independently: Cauchy's formula (a convex body's mean projected
area is a quarter of its surface area), the area of a straight tube, Catmull-Rom's
interpolation of its keys, outward winding and transported (untwisted) rings."""
import numpy as np
import pytest

from addon import hair, pointcloud


def _tri_normals(v, t):
    v = v.astype(np.float64)
    return np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])


@pytest.mark.parametrize('level', [0, 1, 2, 3])
def test_sphere_template_outward_with_the_sphere_surface_area(level):
    v, t, scale = pointcloud.unit_sphere(level)
    assert len(t) == 20 * 4 ** level and np.allclose(np.linalg.norm(v, axis=1), 1.0)
    n = _tri_normals(v, t)
    assert (np.einsum('ij,ij->i', n, v[t].mean(axis=1)) > 0).all(), "a face is wound inward"
    area = 0.5 * np.linalg.norm(n, axis=1).sum() * scale ** 2
    assert area == pytest.approx(4 * np.pi, rel=1e-12)


def test_spheres_mean_projected_area_is_the_disk():
    """Projected area of the level-1 sphere (80 faces) over random view directions: pi r^2
    on average, where the unscaled inscribed one is 7% short."""
    r = 0.3
    v, t, n_vert, kept = pointcloud.spheres([[1.0, 2.0, 3.0]], [r], level=1)
    assert kept == 1
    n = _tri_normals(v, t)
    dirs = np.random.default_rng(0).normal(size=(4000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    projected = 0.5 * np.abs(n @ dirs.T).sum(axis=0) / 2      # each direction sees half the faces
    assert projected.mean() == pytest.approx(np.pi * r * r, rel=0.01)
    inscribed = projected.mean() / pointcloud.unit_sphere(1)[2] ** 2
    assert inscribed < 0.95 * np.pi * r * r
    centre = v.astype(np.float64).mean(axis=0)
    assert np.allclose(centre, [1, 2, 3], atol=1e-5)
    # smooth normals are the exact radial directions
    radial = (v - centre) / np.linalg.norm(v - centre, axis=1, keepdims=True)
    assert np.abs(np.einsum('ij,ij->i', radial, n_vert)).min() > 1 - 1e-5


def test_points_without_size_are_dropped_and_levels_bound_the_triangles():
    v, t, n, kept = pointcloud.spheres([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], [0.1, 0.0, -1.0, np.nan])
    assert kept == 1 and len(t) == len(pointcloud.unit_sphere(pointcloud.level_for(1))[1])
    assert t.max() < len(v)
    assert [pointcloud.level_for(k) for k in (1, 3_000, 3_001, 12_001, 50_001)] == [3, 3, 2, 1, 0]
    for most, level in pointcloud.LEVELS:   # a cloud's triangles stay below ~4M
        assert most * 20 * 4 ** level <= 4_000_000
    for most, sides, steps in hair.LEVELS:
        assert most * steps * sides * 2 <= 8_000_000


def _straight(length=2.0, keys=5, radius=0.1):
    z = np.linspace(0.0, length, keys)
    return np.stack([np.zeros(keys), np.zeros(keys), z], 1), np.full(keys, radius)


@pytest.mark.parametrize('sides,steps', [(8, 4), (6, 2), (3, 1)])
def test_straight_tube_has_the_cylinder_area_and_faces_outward(sides, steps):
    p, r = _straight()
    v, t, n, kept = hair.tubes(p, r, [0, len(p)], (sides, steps))
    assert kept == 1
    assert len(t) == (len(p) - 1) * steps * sides * 2
    tn = _tri_normals(v, t)
    assert 0.5 * np.linalg.norm(tn, axis=1).sum() == pytest.approx(2 * np.pi * 0.1 * 2.0, rel=1e-6)
    outward = v[t].mean(axis=1).astype(np.float64) * [1, 1, 0]
    assert (np.einsum('ij,ij->i', tn, outward) > 0).all()
    assert np.allclose(n[:, 2], 0, atol=1e-6) and np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-6)


def test_tube_follows_catmull_rom_through_its_keys_without_twisting():
    th = np.linspace(0, 4 * np.pi, 17)
    p = np.stack([np.cos(th), np.sin(th), th / 4], 1)          # a helix
    r = np.linspace(0.05, 0.02, len(p))
    sides, steps = 6, 4
    v, t, n, kept = hair.tubes(p, r, [0, len(p)], (sides, steps))
    rings = v.astype(np.float64).reshape(-1, sides, 3)
    centres = rings.mean(axis=1)
    # every steps-th ring is centred on a key, with that key's radius (times the ring scale),
    # stretched along the bend by the mitre of the helix's gentle turns (at most 2%)
    assert np.allclose(centres[::steps], p, atol=1e-5)
    scale = np.pi / (sides * np.sin(np.pi / sides))
    reach = np.linalg.norm(rings[::steps] - p[:, None], axis=2) / (r[:, None] * scale)
    assert reach.min() > 1 - 1e-5 and reach.max() < 1.02
    # in between, the uniform Catmull-Rom point of the segment (keys 3..6, u = 1/2)
    k = 4
    mid = 0.5 * (2 * p[k] + (p[k + 1] - p[k - 1]) * 0.5 + (2 * p[k - 1] - 5 * p[k] + 4 * p[k + 1] - p[k + 2]) * 0.25
                 + (3 * p[k] - p[k - 1] - 3 * p[k + 1] + p[k + 2]) * 0.125)
    assert np.allclose(centres[k * steps + 2], mid, atol=1e-5)
    # consecutive rings keep their orientation: vertex j of one ring is nearest to vertex j of the next
    rad = n.reshape(-1, sides, 3)
    assert np.einsum('ijk,ijk->ij', rad[:-1], rad[1:]).min() > np.cos(2 * np.pi / sides / 2)
    tn = _tri_normals(v, t)
    assert (np.einsum('ij,ij->i', tn, n[t].mean(axis=1)) > 0).all()


def test_a_tip_of_radius_zero_closes_the_tube_as_a_cone():
    """Hair's default tip radius 0: the last ring is one point, so its quads are triangles of
    a cone, each with area (none degenerate: the render had reported 16 per strand as the
    user's degenerate geometry), and the lateral area is the frustum's and the cone's."""
    p, _ = _straight(length=2.0, keys=3)
    r = np.array([0.1, 0.1, 0.0])
    sides, steps = 8, 1
    v, t, n, kept = hair.tubes(p, r, [0, len(p)], (sides, steps))
    area = 0.5 * np.linalg.norm(_tri_normals(v, t), axis=1)
    assert len(t) == sides * 2 + sides and (area > 0).all()
    # the polygon ring has the circle's perimeter: lateral areas 2 pi r h and pi r slant
    expect = 2 * np.pi * 0.1 * 1.0 + np.pi * 0.1 * np.hypot(0.1 * np.pi / (sides * np.sin(np.pi / sides)) *
                                                               np.cos(np.pi / sides), 1.0)
    assert area.sum() == pytest.approx(expect, rel=2e-3)
    v, t, n, kept = hair.tubes(p, np.zeros(3), [0, len(p)], (sides, steps))
    assert len(t) == 0                          # no width anywhere: nothing (Cycles: none)
    # with a tip, strands differ in triangle count: each triangle says its curve (a lone point,
    # curve 1, is not rendered)
    pts = np.concatenate([p, [[9.0, 9.0, 9.0]], p + [3, 0, 0]])
    v, t, n, kept, curve = hair.tubes(pts, np.concatenate([r, [0.1], [0.1, 0.1, 0.1]]), [0, 3, 4, 7],
                                      (sides, steps), curve_of=True)
    assert kept == 2 and len(curve) == len(t) == 3 * sides + 4 * sides
    assert (curve[:3 * sides] == 0).all() and (curve[3 * sides:] == 2).all()
    assert (v[t[curve == 2]][..., 0] > 2.5).all() and (v[t[curve == 0]][..., 0] < 0.5).all()


def test_curves_of_one_point_are_dropped_and_offsets_respected():
    a, _ = _straight(keys=3)
    pts = np.concatenate([a, [[5, 5, 5]], a + [3, 0, 0]])
    v, t, n, kept = hair.tubes(pts, np.full(len(pts), 0.01), [0, 3, 4, 7], (4, 1))
    assert kept == 2 and len(t) == 2 * 2 * 4 * 2
    xs = v[:, 0]
    assert set(np.round(xs[np.abs(xs) > 0.5]).astype(int).tolist()) <= {3}, "a tube joined two curves"
    assert hair.tubes(np.zeros((1, 3)), [0.1], [0, 1])[3] == 0


@pytest.mark.parametrize('shape,power', [(0.0, 1.0), (0.5, 2.0), (-0.5, 0.5)])
def test_hair_particle_radius_follows_the_hair_shape(shape, power):
    """Cycles' shaperadius: tip + (root - tip) (1 - t)^p with p = 1 / (1 - shape) for a
    positive shape and 1 + shape for a negative one, on half the Radius Scale; Close Tip
    zeroes the last point."""
    from types import SimpleNamespace

    from addon.export.strands import hair_radius
    t = np.array([[0.0, 0.25, 0.5, 1.0]])
    s = SimpleNamespace(shape=shape, radius_scale=0.1, root_radius=2.0, tip_radius=0.5, use_close_tip=False)
    want = 0.05 * (0.5 + (2.0 - 0.5) * (1 - t) ** power)
    assert np.allclose(hair_radius(s, t), want)
    s.use_close_tip = True
    got = hair_radius(s, t)
    assert got[0, -1] == 0 and np.allclose(got[0, :-1], want[0, :-1])
