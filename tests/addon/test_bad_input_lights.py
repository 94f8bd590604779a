"""A sun with a NaN location or Angle, an area light with a NaN Spread (a script or driver gone
wrong): Cycles lights the scene with them (a sun's location does not matter; a NaN angle or
spread renders as 0), DACRT skipped the light: a tester's frame 0.177 / 0.212 / 0.254 (the
world alone) against Cycles' 0.504 / 0.515 / 0.557, now 0.504 / 0.515 / 0.557."""
import bpy

import numpy as np
import pytest

from . import scenes

NAN = float('nan')


def _render(kind, tmp_path, **props):
    """A grey floor under a dim world, lit by one light of kind with props ('location' is the
    object's), rendered at 8x6."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.render.engine = 'DACRT'
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 4
    scenes.world((0.05, 0.05, 0.05))
    scenes.camera((0, 0, 4))
    scenes.plane("Floor", size=20, materials=(scenes.diffuse("Grey", (0.8, 0.8, 0.8)),))
    location = props.pop('location', (0, 0, 2))
    scenes.light(kind, 3.0 if kind == 'SUN' else 50.0, location=location, rotation=(0.3, 0.2, 0), **props)
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "r.exr", scene)))
    assert np.isfinite(img).all()
    return img


def test_sun_with_a_nan_location_lights_the_scene(scene, tmp_path, said):
    ref = _render('SUN', tmp_path)
    img = _render('SUN', tmp_path, location=(NAN, 0, 2))
    assert np.array_equal(img, ref) and img[..., 0].mean() > 0.5
    assert any("sun light 'Sun' has a NaN or infinite location; rendered from its direction" in t for t in said)


def test_sun_with_a_nan_angle_renders_as_a_sharp_sun(scene, tmp_path, said):
    ref = _render('SUN', tmp_path, angle=0.0)
    img = _render('SUN', tmp_path, angle=NAN)
    assert np.array_equal(img, ref) and img[..., 0].mean() > 0.5
    assert any("sun light 'Sun' has an Angle of nan; rendered as 0" in t for t in said), said


def test_area_light_with_a_nan_spread_renders_as_spread_zero(scene, tmp_path, said):
    ref = _render('AREA', tmp_path, spread=0.0, size=1.0)
    img = _render('AREA', tmp_path, spread=NAN, size=1.0)
    assert np.array_equal(img, ref) and img[..., 0].max() > 0.1
    assert any("area light 'Area' has a Spread of nan; rendered as 0" in t for t in said), said


@pytest.mark.parametrize("kind, radius", [('POINT', float('inf')), ('POINT', 1e30), ('SPOT', 1e25)])
def test_lamp_whose_radiance_rounds_to_zero_is_named(scene, tmp_path, said, kind, radius):
    """A radius so large (an 'inf' typed: Blender stores float32's largest) that the lamp's power
    over its area rounds to 0 in float32: Cycles' 1 / area is 0 and the lamp gives nothing
    (measured: 0.3997 over a 0.4 world-lit floor, with or without the lamp); DACRT rendered it
    so too, without a word, while tracing a shadow ray per bounce toward it."""
    img = _render(kind, tmp_path, shadow_soft_size=radius)
    assert np.allclose(img[..., :3], 0.05 * 0.8, atol=1e-6), img[..., :3].mean(axis=(0, 1))
    assert any(t.startswith(f"light '{kind.title()}': its radiance") and "rounds to 0 in float32" in t
               and "emits nothing" in t for t in said), said


def test_lamp_of_a_large_but_float32_radiance_is_not_named(scene, tmp_path, said):
    """A 1e15 m sphere: its radiance ~1e-30 is tiny but held by float32."""
    _render('POINT', tmp_path, shadow_soft_size=1e15)
    assert not any("rounds to 0" in t for t in said), said
