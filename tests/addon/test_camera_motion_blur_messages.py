"""The "motion blur is not rendered: the camera may move" warning is said only for what Cycles
blurs of the camera (BlenderSync::sync_camera_motion, export/motion.py MotionCheck.camera_moves):
its placement with its Object > Motion Blur on, and a perspective camera's zoom (lens, sensor),
which Cycles blurs whatever that flag. A keyed focus distance (a rack focus), f-stop, clip range,
shift or orthographic scale, a lens keyed on an orthographic camera, and a camera moved with its
own Motion Blur off had been warned, where Cycles' image with Motion Blur on is bit-identical to
the one with it off (measured: mean |difference| 0.0000 at 64 spp; a camera move 0.059, a zoom
0.085, a keyed sensor width 0.19)."""
import math

import bpy
import pytest

from tests.addon import scenes


def _scene(scene):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0
    scene.dacrt.samples = 1
    scenes.cube("Cube")
    return scene.camera


def _camera_said(scene, said):
    scene.frame_set(1)
    bpy.ops.render.render()
    return [t for t in said if "motion blur" in t and "the camera" in t]


@pytest.mark.parametrize("owner, prop, values", [
    ('dof', 'focus_distance', (3.0, 12.0)),        # a rack focus
    ('dof', 'aperture_fstop', (1.4, 8.0)),
    ('data', 'clip_start', (0.1, 0.5)),
    ('data', 'clip_end', (100.0, 50.0)),
    ('data', 'shift_x', (0.0, 0.5)),
])
def test_camera_settings_cycles_does_not_blur_are_not_warned(scene, said, owner, prop, values):
    cam = _scene(scene)
    target = cam.data.dof if owner == 'dof' else cam.data
    cam.data.dof.use_dof = True
    scenes.keyed(target, prop, {1: values[0], 2: values[1]})
    assert _camera_said(scene, said) == []


def test_orthographic_scale_and_lens_are_not_warned(scene, said):
    """Cycles blurs the field of view of a perspective camera only."""
    cam = _scene(scene)
    cam.data.type = 'ORTHO'
    scenes.keyed(cam.data, 'ortho_scale', {1: 5.0, 2: 9.0})
    scenes.keyed(cam.data, 'lens', {1: 30.0, 2: 90.0})
    assert _camera_said(scene, said) == []


def test_moving_camera_with_its_blur_off_is_not_warned(scene, said):
    """Object > Motion Blur off on the camera: Cycles gives it no motion steps, also when a
    moving parent carries it."""
    cam = _scene(scene)
    scenes.keyed(cam, 'location', {1: (0, -10, 0), 2: (1.5, -10, 0)})
    cam.cycles.use_motion_blur = False
    assert _camera_said(scene, said) == []
    rig = bpy.data.objects.new("Rig", None)
    scene.collection.objects.link(rig)
    cam.animation_data_clear()
    cam.parent = rig
    scenes.keyed(rig, 'location', {1: (0, 0, 0), 2: (1.5, 0, 0)})
    assert _camera_said(scene, said) == []
    cam.cycles.use_motion_blur = True
    assert len(_camera_said(scene, said)) == 1


@pytest.mark.parametrize("blur_flag", [True, False])
def test_zoom_is_warned_whatever_the_cameras_blur_flag(scene, said, blur_flag):
    cam = _scene(scene)
    cam.cycles.use_motion_blur = blur_flag
    scenes.keyed(cam.data, 'lens', {1: 30.0, 2: 90.0})
    text = _camera_said(scene, said)
    assert len(text) == 1 and "the camera may move" in text[0], text


def test_sensor_keyed_driven_or_in_an_nla_strip_is_warned(scene, said):
    cam = _scene(scene)
    scenes.keyed(cam.data, 'sensor_width', {1: 20.0, 2: 50.0})
    assert len(_camera_said(scene, said)) == 1
    said.clear()
    cam.data.animation_data_clear()
    driver = cam.data.driver_add('lens').driver
    driver.expression = "30 + frame"
    assert len(_camera_said(scene, said)) == 1
    said.clear()
    cam.data.animation_data_clear()
    scenes.keyed(cam.data, 'lens', {1: 30.0, 2: 90.0})
    ad = cam.data.animation_data
    action = ad.action
    ad.action = None
    ad.nla_tracks.new().strips.new("Zoom", 1, action)
    assert len(_camera_said(scene, said)) == 1
