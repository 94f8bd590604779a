"""NaN in a Sky Texture's settings (a script or driver gone wrong), Multiple Scattering under a
grey floor seen from above: Cycles 5.0.1 renders a NaN Sun Rotation, Air, Aerosols or Ozone
black (3e-7 against 8.51 with the defaults), segfaults on a NaN Sun Elevation or Altitude, and
with a NaN Sun Size renders part of the sun disc's light (5.65; 2.50 without the disc). DACRT's
render had failed on all but Sun Intensity: "index -9223372036854775808 is out of bounds",
"environment map: pixel value nan at 0 is negative or not finite", "cannot convert float NaN to
integer". Preetham (Turbidity, Sun Direction) and Hosek-Wilkie (Turbidity, Ground Albedo) skies render black
in Cycles too. Now: black with a warning naming the setting; without the disc for the Sun Size."""
import bpy
import numpy as np
import pytest

from . import scenes

NAN = float('nan')


def _sky_scene(scene, **settings):
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=20, materials=(scenes.diffuse("Grey", (0.8, 0.8, 0.8)),))
    w = scenes.world((0.0, 0.0, 0.0))
    nt = w.node_tree
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sky_type = 'MULTIPLE_SCATTERING'
    for name, value in settings.items():
        setattr(sky, name, value)
    nt.links.new(sky.outputs['Color'], next(n for n in nt.nodes if n.type == 'BACKGROUND').inputs['Color'])
    return sky


@pytest.mark.parametrize("setting, named", [
    ('sun_rotation', "Sun Rotation is nan"), ('air_density', "Air is nan"), ('aerosol_density', "Aerosols is nan"),
    ('ozone_density', "Ozone is nan"), ('sun_elevation', "Sun Elevation is nan"), ('altitude', "Altitude is nan"),
])
def test_nan_scattering_sky_setting_renders_black_with_a_warning(scene, said, setting, named):
    _sky_scene(scene, **{setting: NAN})
    img = scenes.render_rgba(scene)
    assert np.all(img[..., :3] == 0.0), img[..., :3].max()
    assert any(f"Sky Texture 'Sky Texture': {named}" in t and "rendered black" in t for t in said), said


@pytest.mark.parametrize("kind, setting, value, named", [
    ('PREETHAM', 'turbidity', NAN, "Turbidity is nan"), ('PREETHAM', 'sun_direction', (NAN, 0.0, 1.0),
                                                          "Sun Direction is nan"),
    ('HOSEK_WILKIE', 'turbidity', NAN, "Turbidity is nan"), ('HOSEK_WILKIE', 'ground_albedo', NAN,
                                                              "Ground Albedo is nan"),
])
def test_nan_analytic_sky_setting_renders_black_as_cycles(scene, said, kind, setting, value, named):
    """Cycles renders these black (3e-7); DACRT's render had failed, and a Preetham sky of a NaN
    Sun Direction had rendered lit (0.53)."""
    _sky_scene(scene, sky_type=kind, **{setting: value})
    img = scenes.render_rgba(scene)
    assert np.all(img[..., :3] == 0.0), img[..., :3].max()
    assert any(f"Sky Texture 'Sky Texture': {named}" in t and "rendered black (as in Cycles)" in t for t in said), said


def test_nan_sun_size_renders_the_sky_without_its_disc(scene, said):
    _sky_scene(scene, sun_disc=False)
    without = scenes.render_rgba(scene)
    assert without[..., :3].mean() > 1.0, "the sky lights the floor"
    assert not any("Sky Texture" in t for t in said), said
    sky = bpy.context.scene.world.node_tree.nodes['Sky Texture']
    sky.sun_disc, sky.sun_size = True, NAN
    img = scenes.render_rgba(scene)
    assert np.array_equal(img, without)
    assert any("Sky Texture 'Sky Texture': Sun Size is nan; its sun disc is not rendered" in t for t in said), said


def test_nan_sun_intensity_renders_the_disc_dark_as_cycles_and_is_named(scene, said):
    """Cycles 5.0.1 renders a NaN Sun Intensity as 0 (a floor under the sky: 2.2244, 2.2245 with
    0, 12.34 with 1), as DACRT did, but silently."""
    _sky_scene(scene, sun_intensity=0.0)
    dark = scenes.render_rgba(scene)
    assert not any("Sky Texture" in t for t in said), said
    sky = bpy.context.scene.world.node_tree.nodes['Sky Texture']
    sky.sun_intensity = NAN
    img = scenes.render_rgba(scene)
    assert np.array_equal(img, dark)
    assert any("Sky Texture 'Sky Texture': Sun Intensity is nan; its sun disc gives no light, as in Cycles" in t
               for t in said), said
