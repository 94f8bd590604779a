"""A Light Falloff's Quadratic output into an emitting mesh's Strength, against Cycles: Cycles
(svm_node_light_falloff) leaves Quadratic at its Strength input, so the panel emits that. DACRT
had read the Emission Strength's own value (1) instead: 0.14x Cycles' image mean with Strength 8,
reported as "value from 'Light Falloff' node; its own value used"; with a Checker colour the
per-point compile gave up on the whole emission. Smooth > 0 scales by d^2 / (smooth + d^2) at
the ray's length d, which the export cannot know: read as 0, and said."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(textured, smooth=0.0, through_math=False):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera(location=(0, -6, 2.5), rotation=(math.radians(70), 0, 0))
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    mat, nt, out = scenes._material("Panel")
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    fo = nt.nodes.new('ShaderNodeLightFalloff')
    fo.inputs['Strength'].default_value = 8.0 if not through_math else 4.0
    fo.inputs['Smooth'].default_value = smooth
    if through_math:        # a chain after it: Math x 2
        m = nt.nodes.new('ShaderNodeMath')
        m.operation, m.inputs[1].default_value = 'MULTIPLY', 2.0
        nt.links.new(fo.outputs['Quadratic'], m.inputs[0])
        nt.links.new(m.outputs[0], em.inputs['Strength'])
    else:
        nt.links.new(fo.outputs['Quadratic'], em.inputs['Strength'])
    if textured:
        ck = nt.nodes.new('ShaderNodeTexChecker')
        ck.inputs['Color1'].default_value = (1.0, 0.3, 0.1, 1.0)
        ck.inputs['Color2'].default_value = (0.1, 0.4, 1.0, 1.0)
        ck.inputs['Scale'].default_value = 3.0
        nt.links.new(ck.outputs['Color'], em.inputs['Color'])
    panel = scenes.plane("Panel", size=1.5, location=(0, 0, 1.2), materials=[mat])
    panel.rotation_euler = (math.radians(20), 0, 0)
    scenes.world((0.02, 0.02, 0.02), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 128
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 2
    sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc


def _means(sc, tmp_path, engines=('CYCLES', 'DACRT')):
    layer = sc.view_layers[0].name
    return {e: np.array([[exr[f"{layer}.Combined.{c}"][rows].mean() for c in 'RGB']
                         for rows in (slice(None), slice(0, 24), slice(24, None))])
            for e, exr in scenes.render_engines(sc, tmp_path, engines).items()}


@pytest.mark.parametrize('case', ['plain', 'through_math', 'checker'])
def test_quadratic_falloff_emission_matches_cycles(case, tmp_path, said):
    sc = _scene(textured=case == 'checker', through_math=case == 'through_math')
    means = _means(sc, tmp_path)
    d, c = means['DACRT'], means['CYCLES']
    # whole image, bottom half (the lit floor), top half (the panel): measured within 0.3%
    np.testing.assert_allclose(d, c, rtol=0.02)
    assert c[0].min() > 0.05
    assert not any("Light Falloff" in t or "approximated" in t for t in said), said


def test_smoothed_falloff_is_said(tmp_path, said):
    """Smooth 1 depends on each ray's length: read as Quadratic without smoothing, reported."""
    sc = _scene(textured=False, smooth=1.0)
    _means(sc, tmp_path, ('DACRT',))
    text = next(t for t in said if "'Panel'" in t)
    assert "Light Falloff Quadratic Smooth 1 read as 0" in text, text
