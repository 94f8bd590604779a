"""Panoramic cameras as Cycles maps them (kernel/camera/projection.h, addon/panorama.py), checked
against closed forms: an equirectangular camera's longitude and latitude per pixel, a fisheye's
angle from the view axis (equidistant: proportional to the radius; equisolid: r = 2 f sin(theta/2)
on the fitted sensor), the mirror ball's reflections, and the pixels outside a fisheye's circle:
no ray, opaque black, while a uniform world fills the circle exactly."""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.camera import CameraModel

from .scenes import render, rotation_x


def pano(kind, **kw):
    args = dict(kind='PANO', panorama_type=kind, matrix=np.eye(4), viewplane=(0.0, 1.0, 0.0, 1.0),
                tan_half_fov=1.0, clip_start=0.5, clip_end=100.0, width=200, height=100)
    args.update(kw)
    return sd.Camera(**args)


def rays_at(cam, u, v):
    """Rays through viewplane points (u, v) of a camera whose viewplane is the unit square."""
    model = CameraModel(cam)
    rx = np.asarray(u, np.float32) * model.width
    ry = np.asarray(v, np.float32) * model.height
    return model, model.rays(rx, ry)


def test_equirectangular_longitude_and_latitude():
    rng = np.random.default_rng(1)
    u, v = rng.uniform(0, 1, 500), rng.uniform(0, 1, 500)
    lon, lat = (-2.0, 1.5), (-0.4, 1.2)
    _, (O, D, tmax) = rays_at(pano('EQUIRECTANGULAR', longitude=lon, latitude=lat), u, v)
    # u runs from longitude min at the left edge to max at the right (longitude grows to the
    # right of the view axis, -Z), v from latitude min at the bottom to max at the top
    want_lon = lon[0] + np.float32(u) * (lon[1] - lon[0])
    want_lat = lat[0] + np.float32(v) * (lat[1] - lat[0])
    assert np.allclose(np.arcsin(np.clip(D[1], -1, 1)), want_lat, atol=2e-5)
    assert np.allclose(np.arctan2(D[0], -D[2]), want_lon, atol=2e-5)
    assert np.allclose(np.linalg.norm(D, axis=0), 1.0, atol=1e-6)
    assert np.allclose(O, 0.5 * D, atol=1e-6) and np.allclose(tmax, 99.5)


def test_equirectangular_full_sphere_axes_and_rotation():
    # centre: forward; quarter turns right, left, behind; top and bottom: up and down
    uv = [(0.5, 0.5), (0.75, 0.5), (0.25, 0.5), (0.0, 0.5), (0.5, 1.0), (0.5, 0.0)]
    want = [(0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 1, 0), (0, -1, 0)]
    m = rotation_x(0.6)
    m[:3, 3] = (1.0, 2.0, 3.0)
    _, (O, D, _) = rays_at(pano('EQUIRECTANGULAR', matrix=m), *zip(*uv))
    assert np.allclose(D.T, np.asarray(want, float) @ m[:3, :3].T, atol=1e-6)
    assert np.allclose(O, m[:3, 3:4] + 0.5 * D, atol=1e-6)


@pytest.mark.parametrize('fov', [np.pi, np.radians(230.0)])
def test_fisheye_equidistant_angle_grows_with_radius(fov):
    rng = np.random.default_rng(2)
    u, v = rng.uniform(0, 1, 600), rng.uniform(0, 1, 600)
    model, (_, D, tmax) = rays_at(pano('FISHEYE_EQUIDISTANT', fisheye_fov=fov, width=100), u, v)
    x, y = (np.float32(u) - 0.5) * 2, (np.float32(v) - 0.5) * 2
    r = np.hypot(x, y)
    inside = r <= 1.0
    assert inside.any() and (~inside).any()
    theta = np.arccos(np.clip(-D[2], -1, 1))
    assert np.allclose(theta[inside], r[inside] * fov / 2, atol=2e-5)
    azimuth = np.arctan2(D[1], D[0])[inside & (r > 1e-3)]
    assert np.allclose(np.cos(azimuth - np.arctan2(y, x)[inside & (r > 1e-3)]), 1.0, atol=1e-5)
    assert (tmax[~inside] == 0).all() and (tmax[inside] > 0).all()
    seen = model.sees(np.float32(u) * model.width, np.float32(v) * model.height)
    assert np.array_equal(seen, inside)


def test_fisheye_equisolid_radius_on_the_sensor():
    lens, sensor = 8.0, (36.0, 18.0)
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0, 1, 600), rng.uniform(0, 1, 600)
    _, (_, D, tmax) = rays_at(pano('FISHEYE_EQUISOLID', fisheye_lens=lens, fisheye_fov=np.pi,
                                   sensor_mm=sensor), u, v)
    r_mm = np.hypot((np.float32(u) - 0.5) * sensor[0], (np.float32(v) - 0.5) * sensor[1])
    inside = r_mm <= 2 * lens * np.sin(np.pi / 4)          # the 180-degree circle
    assert inside.any() and (~inside).any()
    theta = np.arccos(np.clip(-D[2], -1, 1))
    assert np.allclose(2 * lens * np.sin(theta[inside] / 2), r_mm[inside], atol=1e-4)
    assert (tmax[~inside] == 0).all()


def test_mirror_ball_reflections():
    # the ball's centre reflects straight back at the camera's view: forward; at 45 degrees of
    # the ball's normal, a quarter turn; at its rim, behind the camera
    s = np.sqrt(0.5)
    uv = [(0.5, 0.5), ((1 + s) / 2, 0.5), ((1 - s) / 2, 0.5), (0.5, (1 + s) / 2), (1.0, 0.5)]
    want = [(0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, 0, 1)]
    _, (_, D, tmax) = rays_at(pano('MIRRORBALL'), *zip(*uv))
    assert np.allclose(D.T, want, atol=2e-3)
    _, (_, _, tmax) = rays_at(pano('MIRRORBALL'), [0.05, 0.5], [0.05, 0.5])
    assert tmax[0] == 0 and tmax[1] > 0


def test_fisheye_under_a_uniform_world_fills_its_circle_exactly():
    """World only, no geometry: every ray inside the circle sees the world's colour, pixels
    wholly outside it get no ray and stay black but opaque (Cycles); pixel depth is the
    distance, as Cycles gives it for panoramic cameras."""
    cam = pano('FISHEYE_EQUIDISTANT', fisheye_fov=np.pi, width=24, height=24)
    data = sd.SceneData(geometry=sd.Geometry.empty(),
                        materials=[sd.Material('default', np.full(3, 0.8), np.zeros(3))], lights=[], camera=cam,
                        world=np.array([0.25, 0.5, 1.0]),
                        settings=sd.Settings(samples=4, max_bounces=1, filter_type='BOX', filter_width=1.0))
    integ = render(data)
    img = integ.film.combined()
    c = (np.arange(24) + 0.5) / 24 - 0.5
    r_far = np.hypot(*np.meshgrid(np.abs(c) + 0.5 / 24, np.abs(c) + 0.5 / 24)) * 2   # pixel's farthest corner
    r_near = np.hypot(*np.meshgrid(np.maximum(np.abs(c) - 0.5 / 24, 0), np.maximum(np.abs(c) - 0.5 / 24, 0))) * 2
    inside, outside = r_far <= 1.0, r_near > 1.0
    assert inside.sum() > 300 and outside.sum() > 50
    assert np.allclose(img[inside], [0.25, 0.5, 1.0, 1.0], atol=1e-6)
    assert np.allclose(img[outside], [0.0, 0.0, 0.0, 1.0])
    assert np.allclose(img[..., 3], 1.0)


@pytest.mark.parametrize('kind', ['EQUIRECTANGULAR', 'FISHEYE_EQUIDISTANT', 'FISHEYE_EQUISOLID', 'MIRRORBALL',
                                  'EQUIANGULAR_CUBEMAP_FACE', 'CENTRAL_CYLINDRICAL'])
def test_viewplane_of_inverts_the_projection(kind):
    from addon import panorama
    cam = pano(kind, longitude=(-2.5, 2.0), latitude=(-1.2, 1.0), fisheye_fov=2.8, fisheye_lens=10.5,
               sensor_mm=(36.0, 24.0), cylindrical_range=(2.6, -2.1, -0.9, 1.4))
    rng = np.random.default_rng(3)
    u, v = rng.uniform(0.2, 0.8, 400), rng.uniform(0.2, 0.8, 400)
    seen = panorama.sees(cam, u, v)
    seen = np.ones(400, bool) if seen is None else seen
    u2, v2 = panorama.viewplane_of(cam, panorama.directions(cam, u, v))
    assert seen.sum() > 100
    np.testing.assert_allclose(u2[seen], u[seen], atol=1e-9)
    np.testing.assert_allclose(v2[seen], v[seen], atol=1e-9)


def test_cubemap_face_and_cylinder_directions_in_closed_form():
    """An Equiangular Cubemap Face: the angles left of and above the view axis grow evenly, 45
    degrees at the face's edges (u = 0: left, v = 1: up); a Central Cylindrical camera: the angle
    left of the view axis, about the camera's up axis, runs linearly over Cycles' range (its
    first two numbers, -Longitude Min to -Longitude Max) and the height on the cylinder of radius
    1 (the direction's up over its horizontal length) over the last two (Blender's camera frame:
    -Z forward, +Y up, +X right)."""
    from addon import panorama
    u, v = np.array([0.0, 0.25, 0.5, 1.0, 0.5]), np.array([0.5, 0.5, 0.5, 0.5, 1.0])
    d = panorama.directions(pano('EQUIANGULAR_CUBEMAP_FACE'), u, v)
    left = np.arctan2(-d[0], -d[2])        # angle to the left of -Z, about +Y
    up = np.arctan2(d[1], -d[2])
    np.testing.assert_allclose(left, (0.5 - u) * np.pi / 2, atol=1e-12)
    np.testing.assert_allclose(up, (v - 0.5) * np.pi / 2, atol=1e-12)
    a0, a1, z0, z1 = 2.6, -2.1, -0.9, 1.4
    cyl = pano('CENTRAL_CYLINDRICAL', cylindrical_range=(a0, a1, z0, z1))
    u, v = np.array([0.0, 0.3, 0.5, 1.0]), np.array([0.0, 0.6, 0.5, 1.0])
    d = panorama.directions(cyl, u, v)
    np.testing.assert_allclose(np.arctan2(-d[0], -d[2]), a0 + (a1 - a0) * u, atol=1e-12)
    np.testing.assert_allclose(d[1] / np.hypot(d[0], d[2]), z0 + (z1 - z0) * v, atol=1e-12)
    assert panorama.sees(cyl, u, v) is None and panorama.sees(pano('EQUIANGULAR_CUBEMAP_FACE'), u, v) is None


def test_footprint_is_cycles_compact_ray_differential():
    """Cycles' compact differential, 0.5 (|dD.dx| + |dD.dy|) x the distance: an equirectangular
    pixel of a full sphere 200 x 100 spans 2 pi / 200 of longitude x cos(latitude) and pi / 100
    of latitude; a perspective pixel at the centre is the view plane's step, off the axis the
    normalised direction's change, |D.z| sqrt(1 - D.x^2) per unit step (first order)."""
    model = CameraModel(pano('EQUIRECTANGULAR', longitude=(-np.pi, np.pi), latitude=(-np.pi / 2, np.pi / 2)))
    lat = np.array([0.0, 0.5, 1.2])
    dist = np.array([1.0, 3.0, 7.0])
    # points straight ahead (-Z) raised by lat, at those distances
    P = np.stack([np.zeros(3), np.sin(lat), -np.cos(lat)]) * dist
    want = dist * 0.5 * (np.cos(lat) * 2 * np.pi / 200 + np.pi / 100)
    np.testing.assert_allclose(model.footprint(P), want, rtol=2e-3)
    persp = CameraModel(sd.Camera(kind='PERSP', matrix=np.eye(4), viewplane=(-1.0, 1.0, -0.5, 0.5),
                                  tan_half_fov=0.8, clip_start=0.1, clip_end=100.0, width=400, height=200))
    step = 2.0 / 400 * 0.8                              # the view plane's step at z = -1, per pixel
    P = np.array([[0.0, 0.0, -2.0], [1.5, 0.0, -2.0]]).T
    D = P / np.linalg.norm(P, axis=0)
    want = np.linalg.norm(P, axis=0) * step * np.abs(D[2]) * 0.5 * (np.sqrt(1 - D[0] ** 2) + np.sqrt(1 - D[1] ** 2))
    np.testing.assert_allclose(persp.footprint(P), want, rtol=2e-3)
    # (the axis' step x the distance, as it had been everywhere: 1.39x Cycles' 37 degrees off)
    assert persp.footprint(P)[1] < 0.75 * step * np.linalg.norm(P[:, 1])
