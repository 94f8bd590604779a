"""A sun's Texture Coordinate UV as Cycles gives it per light sample (distant_light_uv: a disc of
radius 1/2 about (0.5, 0.5) over its cone, lampcoordinates._sun_uv), the texture's mean over the
cone lighting the floor. Against Cycles on a floor lit by the sun alone, by the image's mean.

It had stood at (0.5, 0.5) for any angle, said past 0.1 rad: a Checker whose centre cell is dark
into the Strength read 0 and the sun was skipped (below: 0 where Cycles lights the floor 0.435;
fuzz 1651, 0.91-0.94x Cycles with a second sun). Also a Gradient on a turned, scaled sun of angle
1 rad and a Separate XYZ of the UV into the Color, whose means over the disc are those at (0.5, 0.5).
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(case):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    lamp = scenes.light('SUN', 3.0, rotation=(0.3, -0.2, 0.7), name="Sun", angle=CASES[case])
    lamp.scale = (1.0, 1.6, 1.0)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    emission = next(n for n in nt.nodes if n.type == 'EMISSION')
    uv = nt.nodes.new('ShaderNodeTexCoord').outputs['UV']
    if case.startswith('gradient'):
        tex = nt.nodes.new('ShaderNodeTexGradient')
        nt.links.new(uv, tex.inputs['Vector'])
        nt.links.new(tex.outputs['Fac'], emission.inputs['Strength'])
    elif case.startswith('checker'):
        tex = nt.nodes.new('ShaderNodeTexChecker')
        tex.inputs['Scale'].default_value = 3.0
        tex.inputs['Color1'].default_value = (1.0, 1.0, 1.0, 1.0)
        tex.inputs['Color2'].default_value = (0.0, 0.0, 0.0, 1.0)
        nt.links.new(uv, tex.inputs['Vector'])
        nt.links.new(tex.outputs['Fac'], emission.inputs['Strength'])
    else:
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(uv, sep.inputs[0])
        comb = nt.nodes.new('ShaderNodeCombineXYZ')
        nt.links.new(sep.outputs['Y'], comb.inputs['X'])
        nt.links.new(sep.outputs['X'], comb.inputs['Z'])
        comb.inputs['Y'].default_value = 0.5
        nt.links.new(comb.outputs[0], emission.inputs['Color'])
    return sc


CASES = {'gradient_wide': 1.0, 'checker_dark_centre': 0.479, 'separate_uv': 0.8, 'gradient_sharp': 0.0}


@pytest.mark.parametrize('case', list(CASES))
def test_sun_uv_over_its_cone_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(case)
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    assert c.max() > 0.02, c
    # (4%: the texture's mean over the cone stands in, said, where Cycles weighs each direction
    # by the floor's cosine toward it; a Gradient on the UV, whose mean is the value at (0.5, 0.5),
    # is 2.7% off so, before and after)
    np.testing.assert_allclose(d, c, rtol=0.04, atol=2e-4, err_msg=case)
    assert not [t for t in said if "reads the sun's UV" in t], said
    assert bool([t for t in said if "averaged over the sun's angle" in t]) == (CASES[case] > 0), said
