"""A procedural texture with its Vector unlinked in a point, spot or sun light's node tree reads
the Generated coordinates, which a light has none of in Cycles (0 there): one value over the
lamp, computed at (0, 0, 0) (export/lights.py _at_lamp_coordinates), against Cycles. An area
light's vary over its surface in Cycles: the texture's mean over it there, said.

They had stood at the input's own value, said: a Gradient on a point lamp lit the floor 0.137
where Cycles renders it black, a Checker on a spot 4.6x Cycles.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def lamp_over_floor(kind):
    """(scene, the lamp's node tree): a grey floor seen from above (orthographic, 32 x 32, 32
    spp, no bounces) under a lamp of kind named 'Lamp' with its nodes on."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
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
    return sc, lamp.data.node_tree


def assert_means_agree(sc, tmp_path, said, case):
    """Both engines' Combined means per channel within 3% (or 2e-4), with no "not evaluated
    for a light" message."""
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    np.testing.assert_allclose(d, c, rtol=0.03, atol=2e-4, err_msg=case)
    assert not [t for t in said if "not evaluated for a light" in t], said


def _scene(kind, texture, output, into, props):
    sc, nt = lamp_over_floor(kind)
    tex = nt.nodes.new(texture)
    for k, v in props.items():
        if k in tex.inputs:
            tex.inputs[k].default_value = v
        else:
            setattr(tex, k, v)
    nt.links.new(tex.outputs[output], next(n for n in nt.nodes if n.type == 'EMISSION').inputs[into])
    return sc


CASES = {
    'point_gradient': ('POINT', 'ShaderNodeTexGradient', 'Color', 'Color', {}),          # black in both
    'spot_checker': ('SPOT', 'ShaderNodeTexChecker', 'Color', 'Color', {'Scale': 3.0}),
    'sun_checker': ('SUN', 'ShaderNodeTexChecker', 'Color', 'Color', {'Color2': (0.3, 0.6, 0.9, 1.0)}),
    'point_noise_strength': ('POINT', 'ShaderNodeTexNoise', 'Fac', 'Strength', {'Scale': 2.0}),
    'point_voronoi': ('POINT', 'ShaderNodeTexVoronoi', 'Color', 'Color', {}),
    'spot_wave': ('SPOT', 'ShaderNodeTexWave', 'Color', 'Color', {'Phase Offset': 1.0}),
}


@pytest.mark.parametrize('case', list(CASES))
def test_lamp_texture_at_generated_zero_agrees_with_cycles(case, tmp_path, said):
    assert_means_agree(_scene(*CASES[case]), tmp_path, said, case)


def test_area_lamp_texture_is_averaged_and_said(tmp_path, said):
    """An area light's Generated coordinates vary over it in Cycles (a Checker of Scale 3 there
    averages its colours: 0.5x a white lamp): not one value, so the texture's mean over the
    surface stands in, said (tests/parity/test_lamp_texture_coordinates.py compares it)."""
    sc = _scene('AREA', 'ShaderNodeTexChecker', 'Color', 'Color', {'Scale': 3.0})
    sc.render.engine = 'DACRT'
    sc.dacrt.samples = 1
    bpy.ops.render.render()
    assert [t for t in said if "light 'Lamp'" in t and "Checker Texture averaged over the area light's surface" in t], \
        said
