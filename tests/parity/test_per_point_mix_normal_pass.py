"""The Normal pass under a Mix Shader of a per-point factor (a Checker, a Noise, an image's
colour, or a Mix of one inside another) between a normal-mapped Diffuse BSDF and a closure
that takes a normal of its own (a Glossy BSDF, a metallic Principled: Cycles' valid specular
reflection normal): Cycles averages the closures' normals by their weights at each point, so
each side weighs by the factor there. The export had weighed both sides' own-normal closures
whole (0.043 mean off Cycles' pass per pixel, 17% of pixels more than 0.1, against 0.010 for a
constant factor) and said so; now the pass agrees as a constant factor's does (0.010-0.011),
and nothing is said. Two Diffuse BSDFs under the same factor are the control. With Alpha 0.6 on
the Principled side the Mix is a cut-out sum (closure.cutout_sum), whose pass weighs each side
by its own opacity and share at the point: both sides whole by the sum's opacity had been 0.039
off at 64 samples (0.047 at 16), now 0.008. A Layer Weight's factor inside such a sum had failed
the render (session-74 fuzz seed 204); now 0.005 off."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .normalpass import normal_pass_diff, normal_pass_scene, world_normal_map

pytestmark = pytest.mark.usefixtures('parity_addon')


def _factor(nt, kind):
    """A node whose first output varies over the sphere: a Checker, a Noise, or an 8 x 8 image
    of 0 and 1 squares on the UV map (a per-texel factor)."""
    if kind == 'checker':
        t = nt.nodes.new('ShaderNodeTexChecker')
        t.inputs['Scale'].default_value = 3.0
        return t.outputs['Fac']
    if kind == 'noise':
        t = nt.nodes.new('ShaderNodeTexNoise')
        t.inputs['Scale'].default_value = 3.0
        return t.outputs['Fac']
    px = np.ones((8, 8, 4), np.float32)
    px[..., :3] = ((np.arange(8)[:, None] + np.arange(8)[None, :]) % 2)[..., None]
    t = nt.nodes.new('ShaderNodeTexImage')
    t.image = scenes.float_image('Mask', px)
    return t.outputs['Color']


def _mix(nt, fac, a, b):
    mix = nt.nodes.new('ShaderNodeMixShader')
    if fac is not None:
        nt.links.new(fac, mix.inputs[0])
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    return mix


def _material(kind, other):
    """Mix(factor, normal-mapped Diffuse, normal-mapped `other`); kind 'nested': Mix(Checker,
    Diffuse, Mix(Noise, other, Diffuse)); kind 'facing': Mix(Noise, Mix(Layer Weight Facing,
    Diffuse, other), Mix(0.5, Diffuse, Transparent)), whose inner factor is a column per point (a
    view-reading chain's) that the outer cut-out sum weighs by a row per point: (n, n), the render
    had failed ("operands could not be broadcast together"; session-74 fuzz seed 204)."""
    mat = bpy.data.materials.new('Per-point mix')
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    nmap = world_normal_map(nt)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.5, 0.4, 0.3, 1.0)
    g = nt.nodes.new('ShaderNodeBsdfPrincipled' if other == 'alpha' else other)
    if g.type == 'BSDF_PRINCIPLED':
        g.inputs['Metallic'].default_value = 1.0
        g.inputs['Alpha'].default_value = 0.6 if other == 'alpha' else 1.0
    for bsdf in (d, g):
        nt.links.new(nmap.outputs[0], bsdf.inputs['Normal'])
    if kind in ('nested', 'facing'):
        d2 = nt.nodes.new('ShaderNodeBsdfDiffuse')
        d2.inputs['Color'].default_value = (0.2, 0.5, 0.3, 1.0)
        nt.links.new(nmap.outputs[0], d2.inputs['Normal'])
    if kind == 'nested':
        mix = _mix(nt, _factor(nt, 'checker'), d, _mix(nt, _factor(nt, 'noise'), g, d2))
    elif kind == 'facing':
        half = _mix(nt, None, d2, nt.nodes.new('ShaderNodeBsdfTransparent'))
        half.inputs[0].default_value = 0.5
        facing = nt.nodes.new('ShaderNodeLayerWeight').outputs['Facing']
        mix = _mix(nt, _factor(nt, 'noise'), _mix(nt, facing, d, g), half)
    else:
        mix = _mix(nt, _factor(nt, kind), d, g)
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('kind, other', [('checker', 'ShaderNodeBsdfGlossy'),
                                         ('noise', 'ShaderNodeBsdfPrincipled'),
                                         ('image', 'ShaderNodeBsdfGlossy'),
                                         ('nested', 'ShaderNodeBsdfGlossy'),
                                         ('checker', 'alpha'),
                                         ('facing', 'ShaderNodeBsdfPrincipled'),
                                         ('checker', 'ShaderNodeBsdfDiffuse')])
def test_per_point_mix_weighs_each_sides_normal_by_the_factor_as_cycles(tmp_path, said, kind, other):
    sc = normal_pass_scene()
    # (a see-through side: the passing paths' normals add noise, less of it at 64 samples)
    samples = 64 if other == 'alpha' or kind == 'facing' else 16
    diff = normal_pass_diff(tmp_path, sc, _material(kind, other), samples=samples)
    assert diff.mean() < 0.02 and np.mean(diff > 0.1) < 0.03, (diff.mean(), np.mean(diff > 0.1))
    assert not any('Normal pass' in s for s in said), said
