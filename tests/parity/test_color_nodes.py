"""Colour nodes on an image agree with Cycles: a plane textured with a 2x2 Closest image
through chains of colour nodes, lit by a sun (direct light only, so each texel's radiance is
albedo x E / pi with almost no noise), seen from above by an orthographic camera; the mean of
each texel's interior pixels must agree within 2% (the sun's own sampling noise is ~0.5%)."""

import numpy as np
import pytest

from addon import nodegraph
from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

PX = np.ones((2, 2, 4), np.float32)
PX[0, 0, :3], PX[0, 1, :3], PX[1, 0, :3], PX[1, 1, :3] = (0.25, 0.5, 0.75), (0.9, 0.1, 0.2), (0.05, 0.6, 0.3), \
    (0.7, 0.7, 0.1)
PX[0, 1, 3], PX[1, 1, 3] = 0.3, 0.6
TEXELS = [(slice(2, 6), slice(2, 6)), (slice(2, 6), slice(10, 14)), (slice(10, 14), slice(2, 6)),
          (slice(10, 14), slice(10, 14))]


def _after(nt, kind, socket, **inputs):
    n = nt.nodes.new(kind)
    for k, v in inputs.items():
        n.inputs[k].default_value = v
    nt.links.new(socket, n.inputs['Color'])
    return n.outputs['Color']


def multiply_hue(nt, tex):
    m = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], (0.3, 0.8, 0.5), 0.6).outputs['Result']
    return _after(nt, 'ShaderNodeHueSaturation', m, Hue=0.3, Saturation=1.4, Value=0.9, Fac=0.8)


def overlay_invert(nt, tex):
    m = scenes.mix_node(nt, 'OVERLAY', tex.outputs['Color'], (0.3, 0.8, 0.5), 0.6).outputs['Result']
    return _after(nt, 'ShaderNodeInvert', m, Fac=0.7)


def gamma_contrast(nt, tex):
    g = _after(nt, 'ShaderNodeGamma', tex.outputs['Color'], Gamma=2.2)
    return _after(nt, 'ShaderNodeBrightContrast', g, Bright=0.1, Contrast=0.5)


def ramp(nt, tex):
    r = nt.nodes.new('ShaderNodeValToRGB')
    r.color_ramp.elements[0].color = (0.1, 0.2, 0.8, 1)
    r.color_ramp.elements[1].color = (1, 0.5, 0, 1)
    r.color_ramp.elements.new(0.4).color = (0, 1, 0, 1)
    nt.links.new(tex.outputs['Color'], r.inputs['Fac'])
    return r.outputs['Color']


def alpha_mask(nt, tex):
    """The float image's alpha mixes its colour (then unassociated, as Cycles does) over red."""
    m = nt.nodes.new('ShaderNodeMix')
    m.data_type = 'RGBA'
    nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
    nodegraph.input_by_id(m, 'A_Color').socket.default_value = (0.8, 0.1, 0.1, 1)
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'B_Color').socket)
    return m.outputs['Result']


def separate_math_combine(nt, tex):
    """Channels through Math and Map Range, recombined as HSV; the Clamp node on the way."""
    sep = nt.nodes.new('ShaderNodeSeparateColor')
    nt.links.new(tex.outputs['Color'], sep.inputs['Color'])
    p = nt.nodes.new('ShaderNodeMath')
    p.operation = 'POWER'
    p.inputs[1].default_value = 0.5
    nt.links.new(sep.outputs['Red'], p.inputs[0])
    w = nt.nodes.new('ShaderNodeMath')
    w.operation, w.use_clamp = 'MULTIPLY_ADD', True
    w.inputs[1].default_value, w.inputs[2].default_value = 1.7, 0.1
    nt.links.new(sep.outputs['Green'], w.inputs[0])
    r = nt.nodes.new('ShaderNodeMapRange')
    r.interpolation_type = 'SMOOTHSTEP'
    r.inputs['From Min'].default_value, r.inputs['From Max'].default_value = 0.8, 0.1
    r.inputs['To Min'].default_value, r.inputs['To Max'].default_value = 0.2, 0.9
    nt.links.new(sep.outputs['Blue'], r.inputs['Value'])
    c = nt.nodes.new('ShaderNodeClamp')
    c.clamp_type = 'RANGE'
    c.inputs['Min'].default_value, c.inputs['Max'].default_value = 0.85, 0.3
    nt.links.new(r.outputs['Result'], c.inputs['Value'])
    comb = nt.nodes.new('ShaderNodeCombineColor')
    comb.mode = 'HSV'
    nt.links.new(p.outputs[0], comb.inputs['Red'])
    nt.links.new(w.outputs[0], comb.inputs['Green'])
    nt.links.new(c.outputs[0], comb.inputs['Blue'])
    return comb.outputs['Color']


def hsl_stepped(nt, tex):
    """HSL separation, a stepped Map Range on lightness and a Wrap, recombined as HSL."""
    sep = nt.nodes.new('ShaderNodeSeparateColor')
    sep.mode = 'HSL'
    nt.links.new(tex.outputs['Color'], sep.inputs['Color'])
    r = nt.nodes.new('ShaderNodeMapRange')
    r.interpolation_type = 'STEPPED'
    r.inputs['Steps'].default_value = 6.0       # no texel's lightness on a step edge (k / 7)
    r.inputs['To Max'].default_value = 0.8
    nt.links.new(sep.outputs['Blue'], r.inputs['Value'])
    h = nt.nodes.new('ShaderNodeMath')
    h.operation = 'WRAP'
    h.inputs[1].default_value, h.inputs[2].default_value = 0.4, -0.1
    nt.links.new(sep.outputs['Red'], h.inputs[0])
    comb = nt.nodes.new('ShaderNodeCombineColor')
    comb.mode = 'HSL'
    nt.links.new(h.outputs[0], comb.inputs['Red'])
    nt.links.new(sep.outputs['Green'], comb.inputs['Green'])
    nt.links.new(r.outputs['Result'], comb.inputs['Blue'])
    return comb.outputs['Color']


def rgb_curves(nt, tex):
    """RGB Curves on the texels x 1.6 (some beyond the curves' range [0, 1]: extrapolated): an
    S on the combined curve, a lifted red curve, a green curve ending at x = 0.8, factor 0.9."""
    c = nt.nodes.new('ShaderNodeRGBCurve')
    m = c.mapping
    comb = m.curves[3]
    comb.points.new(0.3, 0.15)
    comb.points.new(0.7, 0.85)
    m.curves[0].points[0].location = (0.0, 0.2)
    m.curves[1].points[1].location = (0.8, 0.9)
    m.update()
    c.inputs['Fac'].default_value = 0.9
    brighter = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], (1.6, 1.6, 1.6), 1.0)
    nt.links.new(brighter.outputs['Result'], c.inputs['Color'])
    return c.outputs['Color']


def _texels(engine, tmp_path):
    rgb = sunplane.render_rgb(engine, tmp_path)
    return np.array([rgb[s].reshape(-1, 3).mean(0) for s in TEXELS])


@pytest.mark.parametrize('chain', [multiply_hue, overlay_invert, gamma_contrast, ramp, alpha_mask,
                                   separate_math_combine, hsl_stepped, rgb_curves],
                         ids=lambda c: c.__name__)
def test_color_nodes_agree_with_cycles(chain, tmp_path):
    sunplane.build(PX, lambda nt, tex, d: nt.links.new(chain(nt, tex), d.inputs['Color']), 16, 64)
    dacrt, cycles = _texels('DACRT', tmp_path), _texels('CYCLES', tmp_path)
    assert cycles.max() > 0.05
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.02, (dacrt.round(3).tolist(), cycles.round(3).tolist())


@pytest.mark.parametrize('kelvin', [1000.0, 2700.0, 6500.0, 10000.0])
def test_blackbody_emission_agrees_with_cycles(kelvin, tmp_path):
    """An Emission coloured by a Blackbody node, seen straight on (pixels = its colour, no
    noise): the export computes Cycles' blackbody fit (colornodes.blackbody) and agrees to
    float32 rounding. Before, the colour was the Emission socket's own white."""
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 8
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=1.0)
    mat = scenes.emission("Glow", (1, 1, 1), 1.0)
    nt = mat.node_tree
    bb = nt.nodes.new('ShaderNodeBlackbody')
    bb.inputs['Temperature'].default_value = kelvin
    nt.links.new(bb.outputs[0], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Color'])
    scenes.plane("Panel", size=4, materials=[mat])
    scenes.black_world()
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.use_denoising = False
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'])
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    np.testing.assert_allclose(means['DACRT'], means['CYCLES'], rtol=1e-4, atol=1e-5)
    assert np.abs(means['CYCLES'] - 1.0).max() > 0.03, "a white panel could pass for it"
