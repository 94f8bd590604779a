"""A Light Falloff's outputs into an emitting mesh's Strength, against Cycles: Cycles
(svm_node_light_falloff) leaves Quadratic at its Strength input, so the panel emits that. DACRT
had read the Emission Strength's own value (1) instead: 0.14x Cycles' image mean with Strength 8,
reported as "value from 'Light Falloff' node; its own value used"; with a Checker colour the
per-point compile gave up on the whole emission.
Linear and Constant scale the Strength by the ray's length d and d^2, and Smooth > 0 by
d^2 / (smooth + d^2): at each hit's ray length (camera and bounce rays) and each light sample's
distance (procedurals._falloff, the emitters' callers giving the lengths: viewside.Facing), as
Cycles evaluates the emitter's shader there; light samples and BSDF hits weigh each other (MIS)
as for any emitter. Before: Linear 0.11x Cycles' image mean (its own value, said), Constant
0.077x, Quadratic Smooth 1 1.09x (read as 0, said)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(textured, smooth=0.0, through_math=False):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
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


def _per_ray_scene(output, smooth, strength, textured, mixed):
    """_scene's panel (48 x 36, 32 samples) emitting Light Falloff `output` of that Strength and
    Smooth; mixed: a 50% Mix Shader of a Diffuse and that Emission."""
    sc = _scene(textured, smooth)
    sc.render.resolution_x, sc.render.resolution_y = 48, 36
    sc.cycles.samples = sc.dacrt.samples = 32
    nt = bpy.data.materials['Panel'].node_tree
    fo, em = nt.nodes['Light Falloff'], nt.nodes['Emission']
    fo.inputs['Strength'].default_value = strength
    nt.links.new(fo.outputs[output], em.inputs['Strength'])
    if mixed:
        out = nt.nodes['Material Output']
        mix, diffuse = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(diffuse.outputs[0], mix.inputs[1])
        nt.links.new(em.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return sc



@pytest.mark.parametrize('output,smooth,strength,textured,mixed', [
    ('Linear', 0.0, 2.0, False, False), ('Constant', 0.0, 0.5, True, False), ('Quadratic', 1.0, 8.0, False, False),
    ('Linear', 2.0, 3.0, False, True), ('Constant', 0.5, 1.0, True, True)])
def test_falloff_at_each_rays_length_matches_cycles(output, smooth, strength, textured, mixed, said):
    """Per pixel (Welch tests per pixel and 4x4 block, 4 seeds a side) and per channel (1%): the
    panel seen by the camera, the floor it lights by light samples and BSDF hits."""
    sc = _per_ray_scene(output, smooth, strength, textured, mixed)
    cycles, dacrt = rendering.assert_agrees(sc)
    assert cycles[:, :18].mean() > 0.025         # (the floor, rows from the bottom: 0.012 by the world)
    assert not any("Light Falloff" in t or "approximated" in t for t in said), said
