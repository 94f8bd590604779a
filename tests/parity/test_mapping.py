"""Mapping nodes on image texture coordinates agree with Cycles: a plane textured with a 4x4
Closest image read through Mapping nodes (tiled, rotated, moved; Point, Texture and Vector
types, a chain of two, one with nothing in its Vector input, and one whose Location, Rotation
and Scale come from RGB, Value, Math, Combine XYZ and Combine Color nodes), lit by a sun (direct light
only), seen from above by an orthographic camera. The 64x64 renders are averaged over 8x8
pixel blocks (1024 samples a block, so texel edges crossing a block cost little noise); every
block must agree within 2.5% of the brightest one (measured: 0.6-1.1%). With the mapping
ignored, the largest block differences are 73-102% of the brightest block."""
import math

import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

RES, BLOCK = 64, 8
PX = np.ones((4, 4, 4), np.float32)
PX[..., :3] = np.random.default_rng(3).uniform(0.05, 0.95, (4, 4, 3))


def _mapping(nt, kind, loc=(0, 0, 0), rot=(0, 0, 0), scale=(1, 1, 1)):
    m = nt.nodes.new('ShaderNodeMapping')
    m.vector_type = kind
    for name, v in (('Location', loc), ('Rotation', rot), ('Scale', scale)):
        if name in m.inputs:
            m.inputs[name].default_value = v
    return m


def point(nt, uv):
    m = _mapping(nt, 'POINT', (0.1, 0.2, 0.3), (0, 0, math.radians(30)), (2, 3, 1))
    nt.links.new(uv, m.inputs['Vector'])
    return m.outputs[0]


def texture(nt, uv):
    m = _mapping(nt, 'TEXTURE', (0.3, -0.1, 0.5), (math.radians(20), math.radians(10), math.radians(-40)),
                 (0.5, 1.5, 2))
    nt.links.new(uv, m.inputs['Vector'])
    return m.outputs[0]


def chain(nt, uv):
    a = _mapping(nt, 'VECTOR', rot=(0, 0, math.radians(15)), scale=(1.5, 1.5, 1))
    b = _mapping(nt, 'POINT', (0.25, 0, 0), (0, math.radians(25), 0), (1, 2, 1))
    nt.links.new(uv, a.inputs['Vector'])
    nt.links.new(a.outputs[0], b.inputs['Vector'])
    return b.outputs[0]


def unlinked(nt, uv):
    """Nothing in the Mapping's Vector input: every point reads the texel at its mapped value."""
    return _mapping(nt, 'POINT', (0.3, 0.6, 0)).outputs[0]


def driven(nt, uv):
    """Scale from Combine XYZ of a Value node and a Math node, Location from an RGB node, the Z
    rotation from a Math node through Combine Color: constants Cycles computes, which the export
    evaluates."""
    m = _mapping(nt, 'POINT', (5, 5, 5), (1, 1, 1), (9, 9, 9))
    value = nt.nodes.new('ShaderNodeValue')
    value.outputs[0].default_value = 2.5
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.15, 0.4, 0.0, 1.0)
    angle = nt.nodes.new('ShaderNodeMath')
    angle.operation = 'MULTIPLY'
    angle.inputs[0].default_value, angle.inputs[1].default_value = 0.2, math.pi
    combine = nt.nodes.new('ShaderNodeCombineColor')    # (0, 0, angle) as a colour on a vector
    nt.links.new(angle.outputs[0], combine.inputs['Blue'])
    scale = nt.nodes.new('ShaderNodeCombineXYZ')            # (2.5, 2.5 * 0.6, 1)
    ratio = nt.nodes.new('ShaderNodeMath')
    ratio.operation = 'MULTIPLY'
    ratio.inputs[1].default_value = 0.6
    nt.links.new(value.outputs[0], scale.inputs['X'])
    nt.links.new(value.outputs[0], ratio.inputs[0])
    nt.links.new(ratio.outputs[0], scale.inputs['Y'])
    scale.inputs['Z'].default_value = 1.0
    nt.links.new(scale.outputs[0], m.inputs['Scale'])
    nt.links.new(rgb.outputs[0], m.inputs['Location'])
    nt.links.new(combine.outputs[0], m.inputs['Rotation'])
    nt.links.new(uv, m.inputs['Vector'])
    return m.outputs[0]


def _wire(coordinates):
    def wire(nt, tex, diffuse):
        nt.links.new(coordinates(nt, nt.nodes.new('ShaderNodeTexCoord').outputs['UV']), tex.inputs['Vector'])
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])
    return wire


def _blocks(engine, tmp_path):
    rgb = sunplane.render_rgb(engine, tmp_path)
    return rgb.reshape(RES // BLOCK, BLOCK, RES // BLOCK, BLOCK, 3).mean((1, 3))


@pytest.mark.parametrize('coordinates', [point, texture, chain, unlinked, driven], ids=lambda c: c.__name__)
def test_mapped_texture_agrees_with_cycles(coordinates, tmp_path):
    sunplane.build(PX, _wire(coordinates), RES, 16)
    dacrt, cycles = _blocks('DACRT', tmp_path), _blocks('CYCLES', tmp_path)
    assert cycles.max() > 0.05
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.025, (err, dacrt[..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())
