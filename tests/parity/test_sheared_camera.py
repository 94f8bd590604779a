"""A camera parented under a rotated, non-uniformly scaled empty has a sheared world matrix:
Cycles normalises its columns (transform_clear_scale) but they are no longer orthogonal.

- Depth and Denoising Normal: Cycles maps world to camera by the matrix's inverse
  (camera_z_depth, transform_direction(worldtocamera, N)); DACRT used the transpose, which is the
  inverse only for an orthonormal matrix. Depth over a floor: Cycles 11.560, DACRT 12.637 (max
  difference 2.99); camera-space normal Cycles (-0.34, -1.92, 1.72), DACRT (-0.38, -0.50, -0.06).
- Panoramic clip: Cycles normalises the world direction and clips along it; DACRT did not, so
  the clip landed at clip_start * |d| (equirectangular floor coverage 0.88x, fisheye 0.85x).
- Perspective clip: Cycles' camera_sample_perspective lays clip start and range (camera-space
  depths over d_cam.z) along the normalised world ray; DACRT's native rays started on the sheared
  image of the clip-start plane (floor coverage at clip start 11: 0.78x Cycles', at clip end 10:
  1.29x), with or without depth of field. Orthographic rays already matched (their origins are
  the matrix's image of camera-space points in both), but with depth of field their directions
  were not unit length.
"""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

W, H = 48, 36


def _scene(kind='PERSP', samples=1, emission=False, clip=(0.1, 1000.0), pano=None):
    """A floor and a block seen by a camera under a rotated empty scaled (1, 2, 0.5)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = W, H
    cam = scenes.camera(location=(0, -6, 4), rotation=(math.radians(50), 0, 0.2), kind=kind, ortho_scale=9.0)
    rig = scenes.link(bpy.data.objects.new('Rig', None), sc)
    rig.rotation_euler, rig.scale = (0.3, -0.3, 0.0), (1.0, 2.0, 0.5)
    cam.parent = rig
    cam.data.clip_start, cam.data.clip_end = clip
    if pano:
        cam.data.type, cam.data.panorama_type = 'PANO', pano
    if emission:
        mats = [scenes.emission("Glow", (1.0, 1.0, 1.0), 1.0)]
    else:
        mats = [scenes.diffuse("Floor", (0.8, 0.5, 0.3))]
    scenes.plane(size=20, materials=mats)
    scenes.cube(size=1.5, location=(0.5, 0.5, 0.75), materials=mats)
    bpy.context.view_layer.update()
    m = np.array(cam.matrix_world)[:3, :3]
    m = m / np.linalg.norm(m, axis=0)
    assert np.abs(m.T @ m - np.eye(3)).max() > 0.05, "the camera's matrix must be sheared"
    sc.render.film_transparent = True
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    return sc


def _channels(sc, tmp_path, name, axes):
    layer = sc.view_layers[0].name
    return {engine: np.stack([exr[f"{layer}.{name}.{a}"] for a in axes], -1)
            for engine, exr in scenes.render_engines(sc, tmp_path).items()}


@pytest.mark.parametrize('kind', ['PERSP', 'ORTHO'])
def test_depth_and_denoising_normal_of_a_sheared_camera(kind, tmp_path):
    sc = _scene(kind)
    vl = sc.view_layers[0]
    vl.use_pass_z = vl.use_pass_mist = True
    vl.cycles.denoising_store_passes = True
    layer = vl.name
    out = scenes.render_engines(sc, tmp_path)
    c, d = (out[e][f"{layer}.Depth.Z"] for e in ('CYCLES', 'DACRT'))
    hit = (c < 1e9) & (d < 1e9)
    assert hit.sum() > 0.25 * W * H
    # Depth comes from sample 0 through the pixel centre in both: equal up to rounding
    diff = np.abs(c - d)[hit]
    assert diff.max() < 0.01, (c[hit].mean(), d[hit].mean(), diff.max())
    # the Mist pass measures along the view axis (orthographic) or from the camera: unchanged
    cm, dm = (out[e][f"{layer}.Mist.Z"] for e in ('CYCLES', 'DACRT'))
    assert np.abs(cm - dm).mean() < 0.005, np.abs(cm - dm).mean()
    # camera-space normals, not normalised (Cycles): only a floor and a block's faces, so the
    # means over the view agree up to the pixel filter's jitter at edges
    cn, dn = (np.stack([out[e][f"{layer}.Denoising Normal.{a}"] for a in 'XYZ'], -1) for e in ('CYCLES', 'DACRT'))
    assert np.abs(np.linalg.norm(cn[hit], axis=-1) - 1).max() > 0.2, "the sheared inverse must show"
    assert np.abs(cn[hit].mean(0) - dn[hit].mean(0)).max() < 0.03, (cn[hit].mean(0), dn[hit].mean(0))
    assert np.median(np.abs(cn - dn)[hit]) < 1e-3


@pytest.mark.parametrize('pano', ['EQUIRECTANGULAR', 'FISHEYE_EQUIDISTANT', 'MIRRORBALL'])
@pytest.mark.parametrize('clip', [(6.0, 1000.0), (0.1, 7.0)], ids=['start', 'end'])
def test_panoramic_clip_of_a_sheared_camera(pano, clip, tmp_path):
    sc = _scene(samples=32, emission=True, clip=clip, pano=pano)
    out = _channels(sc, tmp_path, 'Combined', 'RA')
    c, d = out['CYCLES'], out['DACRT']
    cov_c, cov_d = c[..., 1].mean(), d[..., 1].mean()
    assert 0.01 < cov_c < 0.9, "the clip must cut the floor"
    assert abs(cov_d / cov_c - 1) < 0.03, (cov_c, cov_d)
    assert abs(d[..., 0].mean() / c[..., 0].mean() - 1) < 0.03, (c[..., 0].mean(), d[..., 0].mean())


@pytest.mark.parametrize('kind,fstop', [('PERSP', None), ('PERSP', 0.2), ('ORTHO', None), ('ORTHO', 0.2)],
                         ids=['persp', 'persp-dof', 'ortho', 'ortho-dof'])
@pytest.mark.parametrize('clip', [(11.0, 1000.0), (0.1, 10.0)], ids=['start', 'end'])
def test_clip_of_a_sheared_camera(kind, fstop, clip, tmp_path):
    sc = _scene(kind, samples=32, emission=True, clip=clip)
    if fstop:
        dof = sc.camera.data.dof
        dof.use_dof, dof.aperture_fstop, dof.focus_distance = True, fstop, 9.0
    out = _channels(sc, tmp_path, 'Combined', 'RA')
    c, d = out['CYCLES'], out['DACRT']
    cov_c, cov_d = c[..., 1].mean(), d[..., 1].mean()
    assert 0.05 < cov_c < 0.9, ("the clip must cut the floor", cov_c)
    assert abs(cov_d / cov_c - 1) < 0.03, (cov_c, cov_d)
    assert abs(d[..., 0].mean() / c[..., 0].mean() - 1) < 0.03, (c[..., 0].mean(), d[..., 0].mean())


@pytest.mark.parametrize('kind,aperture', [('PERSP', 0.0), ('PERSP', 0.3), ('ORTHO', 0.0), ('ORTHO', 0.3)])
def test_sheared_camera_rays_follow_cycles_formulas(kind, aperture):
    """CameraModel.rays of a sheared matrix against Cycles' camera_sample_perspective /
    _orthographic in float64: unit world directions normalize(R d), a perspective ray starting
    clip_start * |d_cam| / |d_cam.z| along it (from the pinhole or the lens point R (lx, ly, 0))
    and clip_range * |d_cam| / |d_cam.z| long; orthographic: origin R (camera-space point),
    clip_range long."""
    from addon.camera import CameraModel
    from addon.scenedata import Camera
    rng = np.random.default_rng(3)
    rot = np.array([[0.9, 0.3, -0.2], [0.1, 0.8, 0.5], [-0.3, 0.4, 0.9]])
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rot * [1.0, 2.0, 0.5], (1.0, -2.0, 3.0)    # columns scaled: normalised away
    cam = Camera(kind=kind, matrix=m, width=16, height=12, viewplane=(-1.0, 1.0, -0.75, 0.75),
                 tan_half_fov=0.4, clip_start=2.5, clip_end=9.0, aperture=aperture, focal_distance=6.0)
    model = CameraModel(cam)
    assert model.sheared
    n = 64
    rx, ry = rng.uniform(0, 16, n).astype(np.float32), rng.uniform(0, 12, n).astype(np.float32)
    lens = rng.uniform(0, 1, (2, n)).astype(np.float32) if aperture else None
    O, D, tmax = model.rays(rx, ry, lens=lens)
    R = rot / np.linalg.norm(rot, axis=0)
    sx, sy = model._viewplane(rx, ry)
    np.testing.assert_allclose(np.linalg.norm(D, axis=0), 1.0, atol=2e-6)
    if kind == 'PERSP':
        dc = np.stack([sx * 0.4, sy * 0.4, -np.ones(n)])
        z_inv = np.linalg.norm(dc, axis=0)          # |d_cam| / |d_cam.z|, d_cam.z = -1
        np.testing.assert_allclose(tmax, 6.5 * z_inv, rtol=1e-6)
        if not aperture:
            w = R @ dc
            Dw = w / np.linalg.norm(w, axis=0)
            np.testing.assert_allclose(D, Dw, atol=2e-6)
            np.testing.assert_allclose(O, m[:3, 3, None] + 2.5 * z_inv * Dw, atol=2e-5)
        else:
            # the ray meets the pinhole ray's point on the plane of focus (camera depth 6)
            P = O - 2.5 * z_inv * D                  # the lens point, on the camera plane
            lp = np.linalg.solve(R, P - m[:3, 3, None])
            np.testing.assert_allclose(lp[2], 0.0, atol=2e-5)
            focus = m[:3, 3, None] + R @ (dc * 6.0)
            t = np.linalg.norm(focus - P, axis=0)
            np.testing.assert_allclose(P + t * D, focus, atol=1e-4)
    else:
        np.testing.assert_allclose(tmax, 6.5, rtol=1e-6)
        cp = np.linalg.solve(R, O - m[:3, 3, None])   # origins: camera-space points on z = -clip_start
        if not aperture:
            np.testing.assert_allclose(cp, np.stack([sx, sy, np.full(n, -2.5)]), atol=2e-5)
            np.testing.assert_allclose(D, -R[:, 2:3] * np.ones(n), atol=2e-6)
        else:
            np.testing.assert_allclose(cp[2], -2.5, atol=2e-5)
            # towards the pinhole's point (sx, sy) at depth focal_distance
            focus = m[:3, 3, None] + R @ np.stack([sx, sy, np.full(n, -6.0)])
            t = np.linalg.norm(focus - O, axis=0)
            np.testing.assert_allclose(O + t * D, focus, atol=1e-4)


def test_camera_under_a_flattened_parent_renders(tmp_path):
    """A parent scaled to 0 on one axis leaves the camera's columns coplanar: no inverse. It
    renders (Cycles does too; its Depth there is arbitrary), its Combined as Cycles'."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 16, 12
    cam = scenes.camera(location=(0, -6, 4), rotation=(math.radians(50), 0, 0.2))
    rig = scenes.link(bpy.data.objects.new('Rig', None), sc)
    rig.scale = (1.0, 0.0, 1.0)       # every column loses its y: exactly coplanar
    cam.parent = rig
    scenes.plane(size=20, materials=[scenes.emission("Glow", (1.0, 1.0, 1.0), 1.0)])
    sc.view_layers[0].use_pass_z = True
    sc.cycles.device = 'CPU'
    sc.cycles.samples = sc.dacrt.samples = 4
    out = _channels(sc, tmp_path, 'Combined', 'R')
    assert abs(out['DACRT'].mean() - out['CYCLES'].mean()) < 0.01
