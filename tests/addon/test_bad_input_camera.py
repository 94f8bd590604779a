"""Bad camera and mist settings (NaN or infinity from a script or driver, an orthographic
scale of 0, a camera scaled to 0 on an axis): Cycles' camera rays then meet nothing and its
render shows only the world; DACRT's failed the whole render with internal field names
(camera.tan_half_fov, camera.viewplane, settings.mist), and an orthographic scale of 0 showed the
point straight ahead in every pixel. Now: the world alone, with a warning naming the setting."""
import math

import bpy
import numpy as np
import pytest

from . import scenes

WORLD = (0.2, 0.25, 0.3)
NAN, INF = float('nan'), float('inf')


def _lit_scene(scene, kind='PERSP'):
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.world(WORLD)
    scenes.plane("Floor", size=20, materials=(scenes.diffuse("Grey", (0.8, 0.8, 0.8)),))
    scenes.light('SUN', 3.0)
    return scenes.camera((0, 0, 5), kind=kind, ortho_scale=4.0)


def _image(scene, tmp_path):
    return scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "r.exr", scene)))


def _world_only(img):
    assert np.allclose(img[..., :3], WORLD, atol=1e-6), img[..., :3].mean(axis=(0, 1))


def test_the_scene_renders_lit_without_a_bad_setting(scene, tmp_path, said):
    """The reference: the floor fills the view, lit by the sun (far brighter than the world)."""
    _lit_scene(scene)
    img = _image(scene, tmp_path)
    assert (img[..., 0] > 0.5).all() and not any("camera" in t for t in said)


@pytest.mark.parametrize("setting, value, named", [
    ('lens', NAN, "Focal Length is nan"),
    ('sensor_width', NAN, "Sensor Width is nan"),
    ('shift_x', INF, "Shift X is inf"),
    ('shift_y', NAN, "Shift Y is nan"),
    ('clip_end', NAN, "clip range is 0.1 .. nan"),
    ('clip_start', NAN, "clip range is nan .. 100"),
])
def test_non_finite_camera_setting_renders_the_world_with_a_warning(scene, tmp_path, said, setting, value, named):
    cam = _lit_scene(scene)
    setattr(cam.data, setting, value)
    img = _image(scene, tmp_path)         # had failed: "camera.tan_half_fov nan must be positive"
    _world_only(img)
    assert any(t.startswith("camera 'Camera': ") and named in t and "only the world" in t for t in said), said


@pytest.mark.parametrize("kind, setting, value, named", [
    ('PERSP', 'shift_x', 1e30, "Shift X is 1e+30"),
    ('PERSP', 'shift_y', -1e30, "Shift Y is -1e+30"),
    ('ORTHO', 'shift_x', 3e38, "Shift X is 3e+38"),            # (overflows float32)
    ('EQUIRECTANGULAR', 'shift_y', 1e30, "Shift Y is 1e+30"),
])
def test_shift_too_far_for_float32_renders_the_world_with_a_warning(scene, tmp_path, said, kind, setting, value,
                                                                      named):
    """A finite shift so large that float32 rounds the frame's edges to one value: Cycles' rays
    then start ~1e29 aside (or take one garbled direction) and it renders the world alone
    (measured: 0.4998 over a 0.5 world, a cube on the shifted side too, perspective and
    panoramic). The render had failed: "camera.viewplane (2.666666706793243e+30,
    2.666666706793243e+30, -1.0, 1.0) must be finite (left < right, bottom < top)"."""
    if kind in ('PERSP', 'ORTHO'):
        cam = _lit_scene(scene, kind).data
    else:
        cam = _panorama(scene, kind)
    setattr(cam, setting, value)
    img = _image(scene, tmp_path)
    _world_only(img)
    assert any(t.startswith("camera 'Camera': ") and named in t and "only the world" in t for t in said), said


@pytest.mark.parametrize("how", ['scale', 'location'])
def test_camera_of_zero_scale_or_nan_location_renders_the_world_with_a_warning(scene, tmp_path, said, how):
    cam = _lit_scene(scene)
    if how == 'scale':
        cam.scale = (0, 1, 1)
    else:
        cam.location = (NAN, 0, 5)
    img = _image(scene, tmp_path)         # had failed: "zero or non-finite scale/transform"
    _world_only(img)
    assert any("camera 'Camera': its transform has a zero scale" in t for t in said), said


@pytest.mark.parametrize("value", [0.0, NAN])
def test_orthographic_scale_zero_or_nan_renders_the_world(scene, tmp_path, said, value):
    """Cycles shows only the world at an orthographic scale of 0 (the point straight ahead at
    1e-6); every pixel had shown the lit floor's point (0.611 / 0.080 / 0.085 in a tester's
    scene, Cycles 0.2 / 0.25 / 0.3)."""
    cam = _lit_scene(scene, 'ORTHO')
    cam.data.ortho_scale = value
    img = _image(scene, tmp_path)
    _world_only(img)
    assert any(f"Orthographic Scale is {value:g}" in t and "only the world" in t for t in said), said


def test_tiny_orthographic_scale_still_sees_the_point_ahead(scene, tmp_path, said):
    cam = _lit_scene(scene, 'ORTHO')
    cam.data.ortho_scale = 1e-6
    img = _image(scene, tmp_path)
    # every pixel sees the one sunlit floor point (sun 3 x 0.8 / pi, plus the world's light)
    assert np.allclose(img[..., :3], img[0, 0, :3], rtol=1e-4) and img[0, 0, 0] > 3.0 * 0.8 / math.pi
    assert not any("camera" in t for t in said)


def test_infinite_clip_end_still_renders_the_objects(scene, tmp_path, said):
    """An infinite clip end is a valid camera in Cycles (rays of any length)."""
    cam = _lit_scene(scene)
    cam.data.clip_end = INF
    img = _image(scene, tmp_path)
    assert (img[..., 0] > 0.5).all() and not any("camera" in t for t in said)


def test_nan_mist_depth_renders_with_a_zero_mist_pass(scene, tmp_path, said):
    """Cycles' film keeps 1 / depth only for depth > 0, so a NaN depth gives mist 0 on every
    surface; the render had failed ("settings.mist must be ...")."""
    _lit_scene(scene)
    bpy.context.view_layer.use_pass_mist = True
    scene.world.mist_settings.depth = NAN
    ch = scenes.read_exr(scenes.render_exr(tmp_path / "m.exr", scene, multilayer=True))
    mist = next(v for k, v in ch.items() if k.endswith('Mist.Z') or k.endswith('Mist.V') or k.endswith('Mist.X'))
    assert np.all(mist == 0.0)
    assert (scenes.rgba(ch, 'ViewLayer.Combined.')[..., 0] > 0.5).all()
    assert any("world 'World': its Mist Pass Depth is nan" in t for t in said), said


def test_nan_sensor_of_an_orthographic_camera_changes_nothing(scene, tmp_path, said):
    """An orthographic view reads no sensor: its NaN is not a broken camera."""
    cam = _lit_scene(scene, 'ORTHO')
    cam.data.sensor_width = NAN
    img = _image(scene, tmp_path)
    assert (img[..., 0] > 0.5).all() and not any("camera" in t for t in said)


def _panorama(scene, kind):
    """The lit scene through a panoramic camera of type kind; the camera's data."""
    cam = _lit_scene(scene, 'PANO')
    cam.data.panorama_type = kind
    return cam.data


@pytest.mark.parametrize("kind, setting", [
    ('FISHEYE_EQUISOLID', 'latitude_min'), ('FISHEYE_EQUISOLID', 'longitude_max'),
    ('EQUIRECTANGULAR', 'fisheye_fov'), ('EQUIRECTANGULAR', 'sensor_width'), ('EQUIRECTANGULAR', 'fisheye_lens'),
    ('FISHEYE_EQUIDISTANT', 'sensor_width'), ('FISHEYE_EQUIDISTANT', 'fisheye_lens'),
    ('MIRRORBALL', 'latitude_max'), ('MIRRORBALL', 'sensor_width'),
])
def test_nan_in_a_setting_the_panorama_does_not_read_changes_nothing(scene, tmp_path, said, kind, setting):
    """Cycles' panoramic cameras read only their own type's settings; DACRT's render failed on a
    NaN in any of them ("camera panorama settings must be finite")."""
    cam = _panorama(scene, kind)
    ref = _image(scene, tmp_path)
    setattr(cam, setting, NAN)
    img = _image(scene, tmp_path)
    assert np.array_equal(img, ref) and (img[..., 0] > 0.5).any()
    assert not any("camera" in t for t in said), said


@pytest.mark.parametrize("kind, setting, named", [
    ('EQUIRECTANGULAR', 'latitude_min', "Latitude nan .. 1.5708 is not finite"),
    ('EQUIRECTANGULAR', 'longitude_max', "Longitude -3.14159 .. nan"),
    ('FISHEYE_EQUISOLID', 'fisheye_lens', "Fisheye Lens is nan"),
    ('FISHEYE_EQUISOLID', 'sensor_width', "Sensor Width is nan"),
])
def test_nan_panorama_setting_renders_the_world_in_every_pixel(scene, tmp_path, said, kind, setting, named):
    """Cycles' rays then have NaN directions: they meet nothing, and even the equisolid frame's
    pixels outside its circle show the world (its test against a NaN radius cuts nothing;
    measured: 0.1998 / 0.2497 / 0.2976 in every pixel of a 16x8 frame, 4 spp)."""
    setattr(_panorama(scene, kind), setting, NAN)
    img = _image(scene, tmp_path)
    _world_only(img)
    assert any(t.startswith("camera 'Camera': ") and named in t and "only the world" in t for t in said), said


def test_nan_equidistant_field_of_view_renders_the_world_within_its_circle(scene, tmp_path, said):
    """Cycles' equidistant fisheye cuts its circle before it reads the field of view, so NaN
    directions (the world) fill the circle and the corners stay black: as the same camera with
    nothing but the world to see."""
    _panorama(scene, 'FISHEYE_EQUIDISTANT').fisheye_fov = NAN
    img = _image(scene, tmp_path)
    assert any("Field of View is nan" in t and "only the world" in t for t in said), said
    for ob in scene.objects:
        ob.hide_render = ob.type != 'CAMERA'
    ref = _image(scene, tmp_path)
    assert np.allclose(img, ref, atol=1e-6) and ref[..., 0].min() < 0.1 < ref[..., 0].max()


def test_nan_equisolid_field_of_view_reads_as_360_degrees(scene, tmp_path, said):
    """Cycles' equisolid fisheye compares the radius with NaN (nothing cut) and its rays within
    reach of the lens stay valid: the scene as through a 360-degree field of view. DACRT's
    render had failed."""
    cam = _panorama(scene, 'FISHEYE_EQUISOLID')
    cam.fisheye_fov = 2 * math.pi
    ref = _image(scene, tmp_path)
    cam.fisheye_fov = NAN
    img = _image(scene, tmp_path)
    assert np.array_equal(img, ref) and (img[..., 0] > 0.5).any()
    assert any("Field of View is nan, read as 360 degrees" in t for t in said), said


def _depth_of_field(cam, **settings):
    d = cam.data.dof
    d.use_dof, d.aperture_fstop, d.focus_distance = True, 0.1, 5.0
    for name, value in settings.items():
        setattr(d, name, value)


@pytest.mark.parametrize("kind, settings, named", [
    ('PERSP', dict(focus_distance=1e20), "depth of field's focus distance 1e+20 m"),
    ('PERSP', dict(focus_distance=3e38), "depth of field's focus distance 3e+38 m"),
    ('ORTHO', dict(focus_distance=1e20), "depth of field's focus distance 1e+20 m"),
    ('PERSP', dict(aperture_blades=5, aperture_rotation=NAN), "Aperture Rotation is nan"),
    ('PERSP', dict(aperture_ratio=NAN), "Aperture Ratio is nan"),
])
def test_depth_of_field_rays_without_a_direction_render_the_world_with_a_warning(scene, tmp_path, said, kind,
                                                                                 settings, named):
    """Cycles normalises a lens ray's direction in float32: past a focus distance of ~1.8e19 its
    squared length overflows and the direction is 0, and a NaN blade rotation or ratio makes it
    NaN; its rays then meet nothing (measured: 0.4998 over a 0.5 world, the lit floor 0.3998
    at 1e18). DACRT's render had failed: "rays[0].dir is the zero vector", "camera.
    aperture_rotation nan must be finite", "camera.aperture_ratio nan must be positive"."""
    cam = _lit_scene(scene, kind)
    _depth_of_field(cam, **settings)
    img = _image(scene, tmp_path)
    _world_only(img)
    assert any(t.startswith("camera 'Camera': ") and named in t and "only the world" in t for t in said), said


@pytest.mark.parametrize("settings", [dict(focus_distance=1.5e19), dict(aperture_blades=0, aperture_rotation=NAN)])
def test_depth_of_field_within_float32_or_a_nan_rotation_of_a_round_aperture_renders_the_floor(scene, tmp_path,
                                                                                              said, settings):
    """Just inside float32's range (this frame's corner rays reach 1.7e19) the lens rays are
    valid, and a round aperture reads no blade rotation: Cycles renders the lit floor (0.3997
    with a NaN rotation and no blades); the NaN rotation had failed the render."""
    cam = _lit_scene(scene)
    _depth_of_field(cam, **settings)
    img = _image(scene, tmp_path)
    assert (img[..., 0] > 0.5).all() and not any("camera" in t for t in said), said
