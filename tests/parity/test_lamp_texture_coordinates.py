"""A procedural texture on Texture Coordinate Normal, Object or UV in a light's node tree, where
Cycles' shader reads one value over the lamp (export/lights.py _lamp_coordinates, measured
against Cycles with Strength = a coordinate's component): Object as Generated (a sun's direction
of travel as a point in its object space, a point or spot lamp's centre), Normal (0, 0, -1) for
a sun and an area light, UV (0.5, 0.5, 0) for a sun. Against Cycles.

They had stood at the input's own value, said: a Checker on a sun's Normal into its Strength lit
at 1 where Cycles lit nothing (fuzz 1024, 1.28x), a Noise on a point lamp's Object 1.96x (fuzz
1078). A point lamp's Normal and UV vary with the direction to the shaded point: still said.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(kind, texture, coordinate, output, into, props):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=8.0)
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    lamp = scenes.light(kind, 3.0 if kind == 'SUN' else 100.0, location=(0.5, 0.0, 1.5), rotation=(0.3, 0.1, 0.0),
                        name="Lamp")
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    coords = nt.nodes.new('ShaderNodeTexCoord')
    emission = next(n for n in nt.nodes if n.type == 'EMISSION')
    if texture is None:         # the coordinate read as a value: Strength = 2 + 0.5 component
        separate = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(coords.outputs[coordinate], separate.inputs[0])
        math = nt.nodes.new('ShaderNodeMath')
        math.operation = 'MULTIPLY_ADD'
        math.inputs[1].default_value, math.inputs[2].default_value = 0.5, 2.0
        nt.links.new(separate.outputs[output], math.inputs[0])
        nt.links.new(math.outputs[0], emission.inputs[into])
        return sc
    tex = nt.nodes.new(texture)
    for k, v in props.items():
        tex.inputs[k].default_value = v
    nt.links.new(coords.outputs[coordinate], tex.inputs['Vector'])
    nt.links.new(tex.outputs[output], emission.inputs[into])
    return sc


CASES = {
    # Checker at (0, 0, -4): its colour 2's Fac 0, the sun dark in Cycles (fuzz 1024)
    'sun_checker_normal': ('SUN', 'ShaderNodeTexChecker', 'Normal', 'Fac', 'Strength', {'Scale': 4.0}),
    'sun_noise_object': ('SUN', 'ShaderNodeTexNoise', 'Object', 'Color', 'Color', {'Scale': 1.7}),
    'sun_gradient_uv': ('SUN', 'ShaderNodeTexGradient', 'UV', 'Fac', 'Strength', {}),
    'sun_normal_z': ('SUN', None, 'Normal', 'Z', 'Strength', {}),
    'area_checker_normal': ('AREA', 'ShaderNodeTexChecker', 'Normal', 'Color', 'Color',
                            {'Scale': 1.5, 'Color2': (0.3, 0.6, 0.9, 1.0)}),
    'area_normal_z': ('AREA', None, 'Normal', 'Z', 'Strength', {}),
    'point_noise_object': ('POINT', 'ShaderNodeTexNoise', 'Object', 'Fac', 'Strength', {'Scale': 3.0}),  # (fuzz 1078)
    'spot_checker_object': ('SPOT', 'ShaderNodeTexChecker', 'Object', 'Color', 'Color',
                            {'Color1': (0.9, 0.2, 0.1, 1.0)}),
}


@pytest.mark.parametrize('case', list(CASES))
def test_lamp_texture_on_a_constant_coordinate_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(*CASES[case])
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    np.testing.assert_allclose(d, c, rtol=0.03, atol=2e-4, err_msg=case)
    assert not [t for t in said if "not evaluated for a light" in t], said


@pytest.mark.parametrize('coordinate', ['Normal', 'UV'])
def test_point_lamp_texture_on_a_varying_coordinate_is_still_said(coordinate, said):
    """A point lamp's Normal and UV vary with the direction to the shaded point in Cycles (a
    Normal's Z from -0.99 to -0.07 over this floor): not one value, so the input's own value
    stands, said."""
    sc = _scene('POINT', 'ShaderNodeTexChecker', coordinate, 'Color', 'Color', {'Scale': 3.0})
    sc.render.engine = 'DACRT'
    sc.dacrt.samples = 1
    bpy.ops.render.render()
    assert [t for t in said if "light 'Lamp'" in t and "'Checker Texture' node, not evaluated for a light" in t], said
