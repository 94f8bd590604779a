"""An AOV Output in a material a Light Path mix hides from camera rays (Mix Shader of a Diffuse
and a white Transparent BSDF by Is Camera Ray): Cycles runs the shader at the camera hit, a
clear surface there, and writes the AOV, 1.0 per surface crossed (a plane 1.0, a sphere's two
faces 2.0). DACRT had left such triangles out of the camera's scene: the AOV read 0. Now the
export gives them a clear twin only camera rays see (export.assembly._camera_clear_aovs)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _hidden(name):
    mat, nt, mix, a, b = scenes.mix_shader_material(name, 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent')
    a.inputs['Color'].default_value = (0.8, 0.3, 0.1, 1.0)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'mask'
    aov.inputs['Value'].default_value = 1.0
    return mat


def test_camera_hidden_material_writes_its_aov(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 24
    layer = sc.view_layers[0]
    aov = layer.aovs.add()
    aov.name, aov.type = 'mask', 'VALUE'
    scenes.camera(location=(0, -6, 0), rotation=(math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=6.0)
    # left half: a hidden plane; right half: a hidden sphere (two faces) before a floor-like wall
    scenes.mesh("Plane", [(-3, 0, -2), (0, 0, -2), (0, 0, 2), (-3, 0, 2)], [(0, 1, 2, 3)],
                materials=[_hidden("HiddenPlane")])
    scenes.uv_sphere("Ball", radius=1.0, location=(1.5, 0, 0), materials=[_hidden("HiddenBall")])
    scenes.mesh("Wall", [(-4, 3, -3), (4, 3, -3), (4, 3, 3), (-4, 3, 3)], [(0, 1, 2, 3)],
                materials=[scenes.diffuse("Grey", (0.5, 0.5, 0.5))])
    scenes.light('SUN', 2.0, rotation=(math.radians(-70), 0, 0))
    scenes.world((0.2, 0.2, 0.2), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    name = layer.name
    out = {}
    for engine, exr in scenes.render_engines(sc, tmp_path).items():
        out[engine] = exr[f"{name}.mask.X"], np.stack([exr[f"{name}.Combined.{c}"] for c in 'RGB'], -1)
    (d_aov, d_rgb), (c_aov, c_rgb) = out['DACRT'], out['CYCLES']
    plane, ball = (slice(2, 22), slice(2, 22)), (slice(9, 15), slice(34, 38))
    assert c_aov[plane].mean() == pytest.approx(1.0, abs=1e-3) and c_aov[ball].mean() == pytest.approx(2.0, abs=1e-3)
    np.testing.assert_allclose(d_aov[plane].mean(), 1.0, atol=1e-3)
    np.testing.assert_allclose(d_aov[ball].mean(), 2.0, atol=1e-3)
    np.testing.assert_allclose(d_aov.mean(), c_aov.mean(), rtol=0.01)
    # the camera still sees through them, and the rest of the light is unchanged
    np.testing.assert_allclose(d_rgb.mean(axis=(0, 1)), c_rgb.mean(axis=(0, 1)), rtol=0.02)
