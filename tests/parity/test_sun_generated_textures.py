"""A procedural texture with its Vector unlinked in a sun's node tree reads the Generated
coordinates, which for a sun are in Cycles its sampled direction of travel d (a unit vector)
read as a point in the sun's object space, M^-1 (d, 1) (export/lights.py _sun_generated): one
value for a sun of angle 0 wherever it stands, the mean over its cone otherwise. Against Cycles
on a floor lit by the sun alone.

They had been computed at (0, 0, 0), silently: a Gradient's Fac into the Strength of a sun at
(-2, 0, 3) lit nothing where Cycles lights the floor 0.764; a Noise colour on a rotated, moved
sun 1.19x Cycles; a Checker's colour where Cycles shows the other one (0.22-0.67 for 0.60); a
Noise on a sun of angle 0.2 1.07x.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(texture, output, into, location, rotation, angle, props):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    lamp = scenes.light('SUN', 3.0, location=location, rotation=rotation, name="Sun", angle=angle)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    tex = nt.nodes.new(texture)
    for k, v in props.items():
        tex.inputs[k].default_value = v
    nt.links.new(tex.outputs[output], next(n for n in nt.nodes if n.type == 'EMISSION').inputs[into])
    return sc


CASES = {
    'gradient_moved': ('ShaderNodeTexGradient', 'Fac', 'Strength', (-2.0, 0.0, 3.0), (0.0, 0.0, 0.0), 0.0, {}),
    'gradient_rotated': ('ShaderNodeTexGradient', 'Color', 'Color', (0.5, 0.0, 3.0), (0.4, 0.2, 0.0), 0.0, {}),
    'noise_rotated_moved': ('ShaderNodeTexNoise', 'Color', 'Color', (1.3, -0.7, 2.0), (0.3, -0.4, 1.0), 0.0,
                            {'Scale': 1.7}),
    'checker_scaled': ('ShaderNodeTexChecker', 'Color', 'Color', (0.3, 0.6, 2.0), (0.2, 0.1, 0.0), 0.0,
                       {'Scale': 2.0, 'Color2': (0.3, 0.6, 0.9, 1.0)}),
    'noise_angle': ('ShaderNodeTexNoise', 'Fac', 'Strength', (0.0, 0.0, 0.0), (0.6, 0.2, 0.0), 0.2, {}),
}


@pytest.mark.parametrize('case', list(CASES))
def test_sun_texture_at_its_generated_point_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(*CASES[case])
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    assert c.max() > 0.02, c
    np.testing.assert_allclose(d, c, rtol=0.02, atol=2e-4, err_msg=case)
    mine = [t for t in said if "light 'Sun'" in t]
    if CASES[case][5] == 0.0:       # one value over the sun: exact, nothing said
        assert not mine, said
    else:                           # the nodes after the texture see its mean over the cone: said
        assert [t for t in mine if "Noise Texture averaged over the sun's angle" in t], said


def test_sun_colour_texture_of_an_angle_is_averaged_over_its_cone(tmp_path, said):
    """A colour (not a Strength) from a texture that varies over a wide sun's cone: the mean of
    the texture over the cone's directions, said (not the Color socket's own value)."""
    sc = _scene('ShaderNodeTexNoise', 'Color', 'Color', (0.0, 0.0, 0.0), (0.6, 0.2, 0.0), 0.3, {'Scale': 3.0})
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    np.testing.assert_allclose(means['DACRT'], means['CYCLES'], rtol=0.03)
    assert [t for t in said if "light 'Sun'" in t and "Noise Texture averaged over the sun's angle" in t], said
    assert not [t for t in said if "own value" in t], said


def test_point_lamp_texture_that_varies_over_its_radius_is_said_where_not_scaling(tmp_path, said):
    """A point lamp of radius 0.8 with a Linear Gradient through a Power (not scaling the
    emission, so no direction profile: tests/parity/test_lamp_texture_coordinates.py): Cycles
    reads it at the point sampled on the lamp's disc (0.0084 where the centre's value, 0, is
    black): computed at the centre, said."""
    sc = _scene('ShaderNodeTexGradient', 'Fac', 'Strength', (0.0, 0.0, 2.0), (0.0, 0.0, 0.0), 0.0, {})
    lamp = sc.objects['Sun']
    lamp.data.type = 'POINT'
    lamp.data.shadow_soft_size = 0.8
    nt = lamp.data.node_tree
    power = nt.nodes.new('ShaderNodeMath')
    power.operation = 'POWER'
    power.inputs[1].default_value = 2.0
    nt.links.new(nt.nodes['Gradient Texture'].outputs['Fac'], power.inputs[0])
    nt.links.new(power.outputs[0], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Strength'])
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "d.exr", sc)
    assert [t for t in said if "light 'Sun'" in t and "Gradient Texture computed at the lamp's centre" in t], said
