"""Camera export against the reference formulas (blender-cycles.md 1.8) and Blender's own
projection (`Camera.view_frame`, `bpy_extras.object_utils.world_to_camera_view`)."""

import math

import bpy
import numpy as np
import pytest
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

from addon import export

from . import scenes

CONFIGS = {
    # name: (kind, res_x, res_y, pct, pixel aspect (x, y), sensor_fit, shift (x, y))
    "auto_landscape": ('PERSP', 1920, 1080, 50, (1, 1), 'AUTO', (0, 0)),
    "auto_portrait_200pct": ('PERSP', 80, 120, 200, (1, 1), 'AUTO', (0, 0)),
    "horizontal_shift_y": ('PERSP', 80, 120, 100, (1, 1), 'HORIZONTAL', (0, 0.3)),
    "vertical_square": ('PERSP', 100, 100, 100, (1, 1), 'VERTICAL', (0, 0)),
    "auto_pixel_aspect": ('PERSP', 100, 80, 100, (2, 1), 'AUTO', (0.1, -0.2)),
    "ortho_shift": ('ORTHO', 120, 80, 100, (1, 1), 'AUTO', (0.25, 0.1)),
    "ortho_vertical_aspect": ('ORTHO', 64, 96, 100, (1, 1.5), 'VERTICAL', (0, 0.2)),
    "rounding_333pct": ('PERSP', 90, 90, 333, (1, 1), 'AUTO', (0, 0)),
}


def make(scene, kind, rx, ry, pct, aspect, fit, shift):
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = rx, ry, pct
    r.pixel_aspect_x, r.pixel_aspect_y = aspect
    cam = scenes.camera((1.0, -2.0, 3.0), (1.1, 0.2, 0.7), lens=35.0, kind=kind, ortho_scale=4.5)
    cam.scale = (2.0, 0.5, 3.0)                       # object scale must not change the view
    cam.data.sensor_fit, cam.data.sensor_width, cam.data.sensor_height = fit, 36.0, 20.0
    cam.data.shift_x, cam.data.shift_y = shift
    cam.data.clip_start, cam.data.clip_end = 0.25, 250.0
    bpy.context.view_layer.update()                   # evaluate matrix_world
    return cam


def project(c, world_points):
    """Raster (x, y) of world points through the exported camera, per the reference."""
    inv = np.linalg.inv(c.matrix)
    p = (world_points - c.matrix[:3, 3]) @ inv[:3, :3].T
    left, right, bottom, top = c.viewplane
    if c.kind == 'PERSP':
        sx = p[:, 0] / -p[:, 2] / c.tan_half_fov
        sy = p[:, 1] / -p[:, 2] / c.tan_half_fov
    else:
        sx, sy = p[:, 0], p[:, 1]
    return np.stack([(sx - left) / (right - left), (sy - bottom) / (top - bottom)], axis=1)


@pytest.mark.parametrize("name", CONFIGS)
def test_projection_matches_blender(scene, name):
    cam = make(scene, *CONFIGS[name])
    c = export.export_camera(scene)
    rx, ry, pct = CONFIGS[name][1:4]
    assert (c.width, c.height) == (rx * pct // 100, ry * pct // 100)
    assert c.kind == CONFIGS[name][0]
    assert np.allclose(np.linalg.norm(c.matrix[:3, :3], axis=0), 1.0)
    assert np.allclose(c.matrix[:3, 3], cam.matrix_world.translation)
    assert (c.clip_start, c.clip_end) == (0.25, 250.0)
    rng = np.random.default_rng(1)
    fwd = -np.array(cam.matrix_world.normalized().col[2][:3])
    pts = np.array(cam.matrix_world.translation) + fwd * rng.uniform(2, 20, (50, 1)) + rng.normal(0, 2, (50, 3))
    ours = project(c, pts)
    theirs = np.array([world_to_camera_view(scene, cam, Vector(p))[:2] for p in pts])
    assert np.allclose(ours, theirs, atol=1e-5)


@pytest.mark.parametrize("name", CONFIGS)
def test_viewplane_matches_view_frame(scene, name):
    cam = make(scene, *CONFIGS[name])
    c = export.export_camera(scene)
    frame = np.array([v[:] for v in cam.data.view_frame(scene=scene)])   # camera-space corners
    if c.kind == 'PERSP':
        xy = frame[:, :2] / -frame[:, 2:3] / c.tan_half_fov
    else:
        xy = frame[:, :2]
    left, right, bottom, top = c.viewplane
    assert np.allclose(sorted(set(np.round(xy[:, 0], 6))), [left, right], atol=1e-5)
    assert np.allclose(sorted(set(np.round(xy[:, 1], 6))), [bottom, top], atol=1e-5)


def test_hand_computed_full_hd(scene):
    make(scene, 'PERSP', 1920, 1080, 100, (1, 1), 'AUTO', (0, 0))
    scene.camera.data.lens = 50.0
    c = export.export_camera(scene)
    ar = 1920 / 1080
    assert c.viewplane == pytest.approx((-ar, ar, -1, 1))
    assert c.tan_half_fov == pytest.approx(36.0 / (2 * 50.0 * ar))
    assert ar * c.tan_half_fov == pytest.approx(0.36)       # horizontal half angle: 18 mm / 50 mm


def test_border_and_crop(scene):
    make(scene, 'PERSP', 90, 90, 333, (1, 1), 'AUTO', (0, 0))
    r = scene.render
    r.use_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.1, 0.55, 0.3, 0.95
    c = export.export_camera(scene)
    assert (c.width, c.height) == (299, 299)
    assert c.border == (int(0.1 * 299), int(0.3 * 299), int(0.55 * 299), int(0.95 * 299))
    assert c.crop is False
    r.use_crop_to_border = True
    assert export.export_camera(scene).crop is True
    r.use_border = False
    assert export.export_camera(scene).border == (0, 0, 299, 299)


def test_bad_cameras_are_explained(scene):
    with pytest.raises(export.ExportError, match="no active camera"):
        export.export_camera(scene)
    cam = scenes.camera()
    cam.data.type = 'CUSTOM'
    with pytest.raises(export.ExportError, match="is custom; DACRT renders"):
        export.export_camera(scene)


def test_central_cylindrical_settings_as_cycles_reads_them(scene):
    """A Central Cylindrical camera's range is Cycles' central_cylindrical_range: the longitudes
    negated, the heights divided by the cylinder's radius; a NaN among them is named and stood in
    for (only the world is rendered, as Cycles' NaN rays see nothing else). The type had been
    refused (the render failed)."""
    import math
    messages = []
    cam = scenes.camera()
    d = cam.data
    d.type, d.panorama_type = 'PANO', 'CENTRAL_CYLINDRICAL'
    d.central_cylindrical_range_u_min, d.central_cylindrical_range_u_max = math.radians(-150), math.radians(120)
    d.central_cylindrical_range_v_min, d.central_cylindrical_range_v_max = -1.2, 0.9
    d.central_cylindrical_radius = 1.5
    c = export.export_camera(scene, messages)
    np.testing.assert_allclose(c.cylindrical_range, (math.radians(150), math.radians(-120), -0.8, 0.6), rtol=1e-6)
    assert not messages
    d.central_cylindrical_range_v_max = float('nan')
    c = export.export_camera(scene, messages)
    assert np.isfinite(c.cylindrical_range).all()
    assert [t for _, t in messages if "Cylinder Radius 1.5 is not finite" in t and "only the world" in t], messages


def test_panoramic_camera_settings_as_cycles_reads_them(scene):
    """The panorama's viewplane is the unit square moved by the shift; an equisolid fisheye's
    sensor is fitted to the frame (pixel aspect included) as Cycles fits it; depth of field is
    reported and dropped (every panoramic ray leaves the camera's position)."""
    import math
    cam = scenes.camera()
    d = cam.data
    d.type, d.panorama_type = 'PANO', 'FISHEYE_EQUISOLID'
    d.fisheye_lens, d.fisheye_fov = 9.0, math.radians(200)
    d.sensor_fit, d.sensor_width, d.sensor_height = 'VERTICAL', 36.0, 20.0
    d.shift_x, d.shift_y = 0.1, -0.05
    d.longitude_min, d.longitude_max, d.latitude_min, d.latitude_max = -1.0, 2.0, -0.5, 0.7
    d.dof.use_dof, d.dof.aperture_fstop = True, 2.0
    r = scene.render
    r.resolution_x, r.resolution_y, r.pixel_aspect_x = 300, 100, 2.0
    messages = []
    c = export.export_camera(scene, messages)
    assert c.kind == 'PANO' and c.panorama_type == 'FISHEYE_EQUISOLID'
    assert np.allclose(c.viewplane, (0.1, 1.1, -0.05, 0.95))
    assert np.allclose(c.sensor_mm, (20.0 * 600 / 100, 20.0))        # vertical fit: height is the sensor
    assert np.isclose(c.fisheye_lens, 9.0) and np.isclose(c.fisheye_fov, math.radians(200))
    assert np.allclose(c.longitude, (-1.0, 2.0)) and np.allclose(c.latitude, (-0.5, 0.7))
    assert c.aperture == 0.0 and any("depth of field is not rendered for panoramic" in m for _, m in messages)
    d.sensor_fit = 'AUTO'                                              # 600 x 100: horizontal
    assert np.allclose(export.export_camera(scene).sensor_mm, (36.0, 36.0 * 100 / 600))


def test_scene_camera_read_from_evaluated_depsgraph(scene, exported):
    """Animated camera: the export reads the evaluated (current frame) transform."""
    cam = scenes.camera((0, 0, 0))
    cam.keyframe_insert("location", frame=1)
    cam.location = (0, 0, 10)
    cam.keyframe_insert("location", frame=11)
    scene.frame_set(6)
    data = exported()
    assert data.camera.matrix[2, 3] == pytest.approx(cam.matrix_world.translation.z)
    assert 0 < data.camera.matrix[2, 3] < 10


def test_depth_of_field_as_cycles_reads_it(scene):
    """Cycles' thin lens (blender/camera.cpp): aperture radius lens / (2 f-stop) in metres
    (orthographic: 1 / (2 f-stop)), focus distance from the focus object along the view axis,
    0 blades a round aperture, and nothing without use_dof."""
    make(scene, 'PERSP', 64, 48, 100, (1, 1), 'AUTO', (0, 0))
    cam = scene.camera
    dof = cam.data.dof
    assert export.export_camera(scene).aperture == 0.0            # use_dof off: a pinhole
    dof.use_dof, dof.aperture_fstop, dof.focus_distance = True, 2.8, 7.5
    dof.aperture_blades, dof.aperture_rotation, dof.aperture_ratio = 0, 0.4, 1.5
    c = export.export_camera(scene)
    assert c.aperture == pytest.approx(35e-3 / (2 * 2.8))
    assert c.focal_distance == pytest.approx(7.5)
    assert (c.aperture_blades, c.aperture_rotation, c.aperture_ratio) == (0, pytest.approx(0.4), pytest.approx(1.5))
    dof.aperture_blades = 6
    assert export.export_camera(scene).aperture_blades == 6
    # a focus object counts by its distance along the view axis, not straight-line distance
    target = scenes.link(bpy.data.objects.new("Focus", None))
    target.location = (4.0, 1.0, -2.0)
    dof.focus_object = target
    bpy.context.view_layer.update()
    m = np.array(cam.matrix_world)
    view = -m[:3, 2] / np.linalg.norm(m[:3, 2])
    want = abs(float(view @ (np.array(target.location) - m[:3, 3])))
    assert want < np.linalg.norm(np.array(target.location) - m[:3, 3]) - 0.1
    assert export.export_camera(scene).focal_distance == pytest.approx(want, rel=1e-6)
    cam.data.type = 'ORTHO'
    assert export.export_camera(scene).aperture == pytest.approx(1.0 / (2 * 2.8))


@pytest.mark.parametrize("kind, spot, lens", [('SPOT', 1.2, 16.0 / math.tan(0.6)),
                                               ('POINT', None, 16.0 / math.tan(math.radians(22.5))),
                                               ('EMPTY', None, 50.0)])
def test_a_light_or_empty_as_camera_has_cycles_lens(scene, kind, spot, lens):
    """Cycles looks through a light as Blender's view through a spot light does (lens 16 /
    tan(spot size / 2); Python reads a spot size on spot lights only, so other lights get
    Blender's default 45 degrees) and through any other object with a 50 mm lens; Cycles'
    default 36 mm sensor fits the wider side (64 x 48: t = 18 / lens / (64 / 48))."""
    make(scene, 'PERSP', 64, 48, 100, (1, 1), 'AUTO', (0, 0))
    if kind == 'EMPTY':
        ob = bpy.data.objects.new("Eye", None)
    else:
        ob = bpy.data.objects.new("Eye", bpy.data.lights.new("Eye", kind))
        if spot is not None:
            ob.data.spot_size = spot
    scene.collection.objects.link(ob)
    scene.camera = ob
    c = export.export_camera(scene)
    assert c.tan_half_fov == pytest.approx(18.0 / lens / (64 / 48), rel=1e-6)
