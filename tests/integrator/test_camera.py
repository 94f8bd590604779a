"""Raster -> ray mapping as Cycles does it (reference blender-cycles.md 1.8): known points
project where the formulas say, rays pass through them, shift moves the viewplane, clip start
and end bound the rays, and a render border selects (and with crop, sizes) the film."""
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


@pytest.mark.parametrize('bad,message', [
    (dict(kind='PANO'), 'camera.kind'),
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
