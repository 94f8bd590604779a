"""View-dependent Mix Shader factors (Fresnel, Layer Weight) against Cycles.

DACRT renders such a factor as its average over view directions weighted by cos
(addon/fresnel.py). An orthographic view of a smooth sphere sees each viewing cosine mu on a
share 2 mu dmu of its disk, so the mean over the disk of what Cycles computes per pixel is that
average exactly: a sphere emitting Mix(factor; A, B) has the same image mean in both engines,
and the same colour (the ratio of its channels does not depend on how much of the image the
disk covers). Before, the factor was read as the socket's own value (0.5), whose colour the
test also shows to be far from Cycles'.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

A = np.array([0.2, 0.6, 1.0])          # emission of the Mix Shader's first input (strength 1)
B = np.array([2.0, 0.6, 0.2])          # of its second (factor 1)


def _factor_node(nt, kind):
    """The node and output feeding the Mix Shader's factor."""
    if kind == 'fresnel':
        n = nt.nodes.new('ShaderNodeFresnel')
        n.inputs['IOR'].default_value = 1.45
        return n.outputs['Fac']
    n = nt.nodes.new('ShaderNodeLayerWeight')
    n.inputs['Blend'].default_value = 0.5 if kind == 'layer_fresnel' else 0.3
    return n.outputs['Fresnel' if kind == 'layer_fresnel' else 'Facing']


def _scene(kind):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 64
    scenes.camera(location=(0, -5, 0), rotation=(np.pi / 2, 0, 0), kind='ORTHO', ortho_scale=2.4)
    mat, nt, mix, *emitters = scenes.mix_shader_material("Coat", 'ShaderNodeEmission', 'ShaderNodeEmission')
    for e, colour in zip(emitters, (A, B)):
        e.inputs['Color'].default_value = (*colour, 1.0)
        e.inputs['Strength'].default_value = 1.0
    nt.links.new(_factor_node(nt, kind), mix.inputs['Fac'])
    scenes.uv_sphere(radius=1.0, segments=96, rings=48, smooth=True, materials=[mat])
    scenes.black_world()
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc


@pytest.mark.parametrize('kind', ['layer_fresnel', 'layer_facing', 'fresnel'])
def test_view_dependent_mix_factor_matches_cycles_on_average(kind, tmp_path):
    sc = _scene(kind)
    layer = sc.view_layers[0].name
    means = {}
    for engine, exr in scenes.render_engines(sc, tmp_path).items():
        means[engine] = np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
    d, c = means['DACRT'], means['CYCLES']
    assert c.min() > 0.05, c
    np.testing.assert_allclose(d, c, rtol=0.01)
    # the factor the colour implies (R / B is the same however much of the image the disk covers)
    ratio = lambda m: m[0] / m[2]                           # noqa: E731
    half = (A + B) / 2                                      # the socket's own value, 0.5
    assert abs(ratio(c) / (half[0] / half[2]) - 1) > 0.1, "the test must tell 0.5 from the average"
    assert abs(ratio(d) / ratio(c) - 1) < 0.01
