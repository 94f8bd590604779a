"""Light Path ray-type mixes seen through glass, against Cycles. The ray past a Glass BSDF is a
transmission ray, whose Is Camera Ray and Is Shadow Ray are 0: it sees the factor-0 shader, as
bounce rays do. A material the mix makes visible to camera rays only, or shadow rays only, is
clear to it (export.assembly: NO_TRANSMISSION). DACRT had shown a camera-only emitter, a
shadow-only plate and a camera-only holdout matte through the pane (the integrator's
transmission scene took any visible triangle): emitter (0.49, 0.88, 2.03) where Cycles shows the
world 0.3, the matte a black alpha-0 hole where Cycles shows the world."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

CASES = {   # Light Path output, first shader (factor 0), second (factor 1)
    'camera_only_emitter': ('Is Camera Ray', 'ShaderNodeBsdfTransparent', 'ShaderNodeEmission'),
    'shadow_only_plate': ('Is Shadow Ray', 'ShaderNodeBsdfTransparent', 'ShaderNodeBsdfDiffuse'),
    'camera_only_holdout': ('Is Camera Ray', 'ShaderNodeBsdfTransparent', 'ShaderNodeHoldout'),
    # the usual light plane hidden from the camera: transmission rays see its emission
    'hidden_emitter': ('Is Camera Ray', 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent'),
}


def _panel_material(output, first, second):
    mat, nt, mix, a, b = scenes.mix_shader_material("Panel", first, second)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
    for node in (a, b):
        if node.type == 'EMISSION':
            node.inputs['Color'].default_value = (0.2, 0.4, 1.0, 1.0)
            node.inputs['Strength'].default_value = 3.0
        elif node.type == 'BSDF_DIFFUSE':
            node.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    return mat


def _glass(ior=1.0):
    mat = bpy.data.materials.new("Glass")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    glass = nt.nodes.new('ShaderNodeBsdfGlass')
    glass.inputs['IOR'].default_value = ior
    glass.inputs['Roughness'].default_value = 0.0
    nt.links.new(glass.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('case', sorted(CASES))
def test_ray_type_mix_behind_glass_matches_cycles(case, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 32
    # ortho camera at y = -5 looking along +y; the panel (at y = 2) fills the view, a clear
    # IOR-1 pane (at y = 0, no bending in either engine) covers its left half
    scenes.camera(location=(0, -5, 0), rotation=(math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=3.0)
    scenes.mesh("Panel", [(-2, 2, -2), (2, 2, -2), (2, 2, 2), (-2, 2, 2)], [(0, 1, 2, 3)],
                materials=[_panel_material(*CASES[case])])
    scenes.mesh("Pane", [(-3, 0, -3), (0, 0, -3), (0, 0, 3), (-3, 0, 3)], [(0, 1, 2, 3)], materials=[_glass()])
    scenes.light('SUN', 2.0, rotation=(math.radians(-60), 0, 0))
    scenes.world((0.3, 0.3, 0.3), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.transmission_bounces = 4
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    layer = sc.view_layers[0].name
    halves = {}
    for engine, exr in scenes.render_engines(sc, tmp_path).items():
        px = np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1)
        w = px.shape[1]
        halves[engine] = (px[:, 4:w // 2 - 4].mean(axis=(0, 1)), px[:, w // 2 + 4:w - 4].mean(axis=(0, 1)))
    for (d, c), side in zip(zip(halves['DACRT'], halves['CYCLES']), ('behind the pane', 'seen directly')):
        np.testing.assert_allclose(d, c, rtol=0.02, atol=0.004, err_msg=side)
