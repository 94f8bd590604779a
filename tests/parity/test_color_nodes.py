"""Colour nodes on an image agree with Cycles: a plane textured with a 2x2 Closest image
through chains of colour nodes, lit by a sun (direct light only, so each texel's radiance is
albedo x E / pi with almost no noise), seen from above by an orthographic camera; the mean of
each texel's interior pixels must agree within 2% (the sun's own sampling noise is ~0.5%)."""
import math

import bpy
import numpy as np
import pytest

from addon import nodegraph
from tests.addon import scenes

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


def _build(chain):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    mat, nt, out = scenes._material("Nodes")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Texels", PX)
    tex.interpolation = 'Closest'
    nt.links.new(chain(nt, tex), d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.light('SUN', 2.0)
    scenes.black_world()
    sc.render.resolution_x = sc.render.resolution_y = 16
    sc.cycles.device = 'CPU'
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0


def _texels(engine, tmp_path):
    bpy.context.scene.render.engine = engine
    r = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr"))
    rgb = np.stack([r['R'], r['G'], r['B']], -1)
    return np.array([rgb[s].reshape(-1, 3).mean(0) for s in TEXELS])


@pytest.mark.parametrize('chain', [multiply_hue, overlay_invert, gamma_contrast, ramp, alpha_mask],
                         ids=lambda c: c.__name__)
def test_color_nodes_agree_with_cycles(chain, tmp_path):
    _build(chain)
    dacrt, cycles = _texels('DACRT', tmp_path), _texels('CYCLES', tmp_path)
    assert cycles.max() > 0.05
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.02, (dacrt.round(3).tolist(), cycles.round(3).tolist())
