"""Raster -> ray mapping as Cycles does it (reference blender-cycles.md 1.8): known points
project where the formulas say, rays pass through them, shift moves the viewplane, clip start
and end bound the rays, a render border selects (and with crop, sizes) the film, and depth of
field (Cycles' thin lens) spreads rays uniformly over the aperture's disk or polygon while
each still passes through its pinhole ray's point on the plane of focus."""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.camera import CameraModel

from .scenes import ALL_VIS, geometry, material, quad, render, rotation_x


def persp(**kw):
    args = dict(kind='PERSP', matrix=np.eye(4), viewplane=(-1.0, 1.0, -0.75, 0.75), tan_half_fov=0.5,
                clip_start=0.1, clip_end=100.0, width=80, height=60)
    args.update(kw)
    return sd.Camera(**args)


def test_perspective_projection_of_known_points():
    cam = CameraModel(persp())
    # camera at the origin looking down -Z: at depth 10 the half-width is 10 * 0.5 * 1 = 5
    pts = np.array([(0.0, 0.0, -10.0), (5.0, 0.0, -10.0), (0.0, 3.75, -10.0), (-2.5, -1.875, -10.0)])
    rx, ry, depth = cam.project(pts)
    assert np.allclose(rx, [40.0, 80.0, 40.0, 20.0])
    assert np.allclose(ry, [30.0, 30.0, 60.0, 15.0])
    assert np.allclose(depth, 10.0)


def test_rays_pass_through_projected_points_rotated_camera():
    m = rotation_x(0.7) @ np.diag([1.0, 1.0, 1.0, 1.0])
    m[:3, 3] = (1.0, -2.0, 3.0)
    cam = CameraModel(persp(matrix=m))
    rng = np.random.default_rng(3)
    pts = m[:3, :3] @ np.stack([rng.uniform(-3, 3, 50), rng.uniform(-2, 2, 50), -rng.uniform(2, 20, 50)]) \
        + m[:3, 3:4]
    rx, ry, _ = cam.project(pts.T)
    O, D, tmax = cam.rays(rx.astype(np.float32), ry.astype(np.float32))
    to_p = pts - O
    cross = np.cross(D.T, to_p.T)
    assert np.allclose(np.linalg.norm(D, axis=0), 1.0, atol=1e-6)
    assert np.max(np.linalg.norm(cross, axis=1) / np.linalg.norm(to_p, axis=0)) < 1e-5
    assert np.all(np.einsum('ij,ij->j', D, to_p) > 0)


def test_clip_start_and_end():
    cam = CameraModel(persp())
    O, D, tmax = cam.rays(np.array([0.0, 40.0, 80.0], np.float32), np.array([0.0, 30.0, 60.0], np.float32))
    # origins on the clip-start plane (z = -0.1), ends on the clip-end plane (z = -100)
    assert np.allclose(O[2], -0.1, atol=1e-6)
    assert np.allclose((O + D * tmax)[2], -100.0, rtol=1e-5)


def test_orthographic_with_shift():
    m = np.eye(4)
    m[:3, 3] = (0.0, 0.0, 5.0)
    # ortho_scale 4, 80x40: viewplane [-2, 2] x [-1, 1]; shift_x 0.25 moves it by 2*2*0.25 = 1
    cam = CameraModel(sd.Camera('ORTHO', m, (-1.0, 3.0, -1.0, 1.0), 0.0, 0.5, 50.0, 80, 40))
    O, D, tmax = cam.rays(np.array([40.0, 0.0], np.float32), np.array([20.0, 40.0], np.float32))
    assert np.allclose(O.T, [(1.0, 0.0, 4.5), (-1.0, 1.0, 4.5)])
    assert np.allclose(D.T, [(0, 0, -1), (0, 0, -1)])
    assert np.allclose(tmax, 49.5)
    rx, ry, depth = cam.project(np.array([(1.0, 0.0, 0.0), (3.0, -1.0, -2.0)]))
    assert np.allclose(rx, [40.0, 80.0]) and np.allclose(ry, [20.0, 0.0]) and np.allclose(depth, [5.0, 7.0])


def emissive_wall_scene(camera):
    v, t = quad((0.0, 0.0, -20.0), 100.0, 100.0)
    mats = [material('default'), material('wall', (0.0,) * 3, (1.0, 1.0, 1.0))]
    return sd.SceneData(camera, geometry([(v, t, 1, ALL_VIS)]), mats, [], np.zeros(3, np.float32),
                        sd.Settings(samples=2, max_bounces=0))


def test_border_without_crop_renders_only_the_border():
    integ = render(emissive_wall_scene(persp(border=(10, 5, 30, 20))))
    img = integ.film.combined()
    assert img.shape == (60, 80, 4)
    assert np.all(img[5:20, 10:30] == 1.0)
    inside = np.zeros((60, 80), bool)
    inside[5:20, 10:30] = True
    assert np.all(img[~inside] == 0.0)
    assert np.all(integ.film.sample_counts()[~inside] == 0)


def test_border_with_crop_is_the_border_size():
    full = render(emissive_wall_scene(persp(clip_end=15.0)))           # wall beyond clip end
    assert np.all(full.film.combined()[..., :3] == 0.0)
    integ = render(emissive_wall_scene(persp(border=(10, 5, 30, 20), crop=True)))
    assert integ.film.combined().shape == (15, 20, 4)
    assert np.all(integ.film.combined() == 1.0)


def test_crop_keeps_the_noise_of_the_full_frame():
    """Random numbers follow full-frame pixels, so a cropped border equals that part of the frame."""
    scene = emissive_wall_scene(persp())
    scene.materials[1] = material('wall', (0.5,) * 3)
    scene.world = np.array([1.0, 1.0, 1.0], np.float32)
    scene.settings.max_bounces = 1
    full = render(scene).film.combined()
    scene.camera = persp(border=(10, 5, 30, 20), crop=True)
    crop = render(scene).film.combined()
    assert np.allclose(crop, full[5:20, 10:30], rtol=1e-6, atol=1e-7)


def lens_frame():
    m = rotation_x(0.4)
    m[:3, 3] = (0.5, -1.0, 2.0)
    return m


def lens_points(cam, O, D):
    """Where each ray crosses the camera plane, in camera (x, y)."""
    rel = O - cam.pos[:, None]
    fwd = cam.forward
    t = -(fwd @ rel) / (fwd @ D)
    p = rel + D * t
    return cam.rot[:, 0] @ p, cam.rot[:, 1] @ p


@pytest.mark.parametrize('kind', ['PERSP', 'ORTHO'])
@pytest.mark.parametrize('blades,rotation,ratio', [(0, 0.0, 1.0), (0, 0.0, 2.0), (6, 0.3, 1.0), (5, -1.0, 0.7)])
def test_depth_of_field_lens_points_fill_the_aperture_uniformly(kind, blades, rotation, ratio):
    a, focus = 0.2, 4.0
    cam = CameraModel(persp(kind=kind, matrix=lens_frame(), aperture=a, focal_distance=focus,
                            aperture_blades=blades, aperture_rotation=rotation, aperture_ratio=ratio))
    n = 200_000
    rng = np.random.default_rng(7)
    rx = np.full(n, 23.5, np.float32)
    ry = np.full(n, 41.25, np.float32)
    lens = rng.random(n, dtype=np.float32), rng.random(n, dtype=np.float32)
    O, D, tmax = cam.rays(rx, ry, lens=lens)
    x, y = lens_points(cam, O.astype(np.float64), D.astype(np.float64))
    O0, D0, _ = cam.rays(rx[:1], ry[:1])              # the pinhole ray: the aperture's centre
    x0, y0 = lens_points(cam, O0.astype(np.float64), D0.astype(np.float64))
    x, y = (x - x0) * ratio, y - y0                         # undo the anamorphic squeeze: a round or regular shape
    if blades:
        # inside the polygon inscribed in the radius-a circle (corners at rotation + pi/N + 2 pi k/N)
        theta = rotation + 2.0 * np.pi * np.arange(blades) / blades
        reach = np.max(np.outer(x, np.cos(theta)) + np.outer(y, np.sin(theta)), axis=1)
        apothem = a * np.cos(np.pi / blades)
        assert reach.max() <= apothem * (1 + 1e-4) and reach.max() > apothem * 0.995
        second = a * a / 12.0 * (1.0 + 2.0 * np.cos(np.pi / blades) ** 2)   # E[x^2] = E[y^2]
    else:
        r = np.hypot(x, y)
        assert r.max() <= a * (1 + 1e-4) and r.max() > a * 0.995
        second = a * a / 4.0
    # uniform over the shape: centred, with the shape's second moments (5 sigma bounds)
    sd_mean = np.sqrt(second / n)
    assert abs(x.mean()) < 5 * sd_mean and abs(y.mean()) < 5 * sd_mean
    for v in (x, y):
        m2 = np.mean(v * v)
        assert abs(m2 - second) < 5 * np.std(v * v) / np.sqrt(n), (m2, second)


@pytest.mark.parametrize('kind', ['PERSP', 'ORTHO'])
def test_depth_of_field_rays_meet_at_the_plane_of_focus(kind):
    """Every lens ray of a raster position passes through the pinhole ray's point at the focus
    distance from the camera plane (Cycles' perspective and orthographic thin lens)."""
    focus = 3.5
    base = dict(kind=kind, matrix=lens_frame())
    pinhole = CameraModel(persp(**base))
    cam = CameraModel(persp(**base, aperture=0.3, focal_distance=focus, aperture_blades=7,
                            aperture_rotation=0.5, aperture_ratio=1.3))
    rng = np.random.default_rng(11)
    n = 4000
    rx = rng.uniform(0, 80, n).astype(np.float32)
    ry = rng.uniform(0, 60, n).astype(np.float32)
    O0, D0, tmax0 = pinhole.rays(rx, ry)
    O, D, tmax = cam.rays(rx, ry, lens=(rng.random(n, dtype=np.float32), rng.random(n, dtype=np.float32)))
    O0, D0, O, D = (v.astype(np.float64) for v in (O0, D0, O, D))
    fwd = cam.forward
    # the pinhole ray's point at depth `focus` from the camera plane
    F = O0 + D0 * ((focus - fwd @ (O0 - cam.pos[:, None])) / (fwd @ D0))
    to_f = F - O
    miss = np.linalg.norm(np.cross(D.T, to_f.T), axis=1)
    assert np.max(miss) < 2e-5 * focus
    assert np.all(np.einsum('ij,ij->j', D, to_f) > 0)                     # ahead of the ray
    assert np.allclose(np.linalg.norm(D, axis=0), 1.0, atol=1e-6)
    assert np.max(np.linalg.norm(O - O0, axis=0)) > 0.1                   # the lens moved them
    # rays start on (perspective: about) the clip-start plane, as the pinhole rays do
    assert np.allclose(fwd @ (O - cam.pos[:, None]), 0.1, rtol=0.05)


def test_closed_aperture_or_no_lens_samples_give_pinhole_rays():
    rx = np.array([3.0, 40.0, 77.0], np.float32)
    ry = np.array([1.0, 30.0, 59.0], np.float32)
    lens = (np.array([0.1, 0.5, 0.9], np.float32), np.array([0.7, 0.2, 0.4], np.float32))
    want = CameraModel(persp()).rays(rx, ry)
    for got in (CameraModel(persp(aperture=0.0, focal_distance=2.0)).rays(rx, ry, lens=lens),
                CameraModel(persp(aperture=0.5, focal_distance=2.0)).rays(rx, ry)):
        for w, g in zip(want, got):
            assert np.array_equal(w, g)


@pytest.mark.parametrize('bad,message', [
    (dict(aperture=-0.1), 'aperture'),
    (dict(aperture=0.1, focal_distance=0.0), 'focal_distance'),
    (dict(aperture=0.1, aperture_ratio=0.0), 'aperture_ratio'),
    (dict(aperture=float('nan')), 'aperture'),
    (dict(kind='FISHEYE'), 'camera.kind'),
    (dict(kind='PANO'), 'panorama_type'),
    (dict(kind='PANO', panorama_type='FISHEYE_EQUISOLID', fisheye_lens=0.0), 'panorama settings'),
    (dict(kind='PANO', panorama_type='EQUIRECTANGULAR', aperture=0.1), 'depth of field'),
    (dict(width=0), 'resolution'),
    (dict(viewplane=(1.0, -1.0, -1.0, 1.0)), 'viewplane'),
    (dict(clip_start=5.0, clip_end=1.0), 'clip'),
    (dict(border=(50, 0, 40, 10)), 'border'),
    (dict(tan_half_fov=0.0), 'tan_half_fov'),
    (dict(matrix=np.full((4, 4), np.nan)), 'matrix'),
])
def test_bad_camera_is_named(bad, message):
    with pytest.raises(ValueError, match=message):
        CameraModel(persp(**bad))
