"""The Normal pass under a Mix Shader of a per-point factor (a Checker) between a Diffuse and a
Glossy BSDF, both normal-mapped: the export weighs the Glossy's own normal (Cycles' valid
specular reflection normal) at the Mix's whole weight, not by the factor per point, so the pass
is off Cycles' there (0.043 mean per pixel, 17% of pixels more than 0.1, against 0.010 for a
constant factor), and the material says so. Two Diffuse BSDFs under the same factor have no
such closure: their pass agrees with Cycles, and nothing is said. Before, the Glossy's case was
off without a word."""

import bpy
import pytest

from .normalpass import normal_pass_diff, normal_pass_scene, world_normal_map

pytestmark = pytest.mark.usefixtures('parity_addon')


def _checker_mix(other):
    mat = bpy.data.materials.new('Checker mix')
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.5, 0.4, 0.3, 1.0)
    g = nt.nodes.new(other)
    mix = nt.nodes.new('ShaderNodeMixShader')
    checker = nt.nodes.new('ShaderNodeTexChecker')
    checker.inputs['Scale'].default_value = 3.0
    nt.links.new(checker.outputs['Fac'], mix.inputs[0])
    nt.links.new(d.outputs[0], mix.inputs[1])
    nt.links.new(g.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    nmap = world_normal_map(nt)
    nt.links.new(nmap.outputs[0], d.inputs['Normal'])
    nt.links.new(nmap.outputs[0], g.inputs['Normal'])
    return mat


@pytest.mark.parametrize('other', ['ShaderNodeBsdfGlossy', 'ShaderNodeBsdfDiffuse'])
def test_per_point_mix_normal_pass_is_said_where_it_differs(tmp_path, said, other):
    sc = normal_pass_scene()
    diff = normal_pass_diff(tmp_path, sc, _checker_mix(other))
    text = ' '.join(said)
    told = "'Checker mix'" in text and "Normal pass under Mix Shader 'Mix Shader'" in text
    if other == 'ShaderNodeBsdfGlossy':
        assert diff.mean() > 0.025 and told, (diff.mean(), said)
    else:
        assert diff.mean() < 0.02 and not told, (diff.mean(), said)
