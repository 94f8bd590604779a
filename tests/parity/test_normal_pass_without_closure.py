"""The Normal pass where a bent surface has no closure agrees with Cycles: a Principled BSDF
bent by a World-space Normal Map, its Base Color a Checker of black and grey, Specular IOR
Level 0. Where the colour is black Cycles allocates no closure (under CLOSURE_WEIGHT_CUTOFF)
and its average normal is the unbent sd->N. Mean per-pixel difference from Cycles within 0.03
(fuzz 9020: the black squares had kept the bent normal, 0.43 off on average)."""

import numpy as np
import pytest

from tests.addon import scenes

from .normalpass import normal_pass_diff, normal_pass_scene, world_normal_map

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_normal_pass_where_the_colour_is_black_matches_cycles(tmp_path):
    sc = normal_pass_scene()
    mat = scenes.principled('P', (0.5, 0.5, 0.5))
    nt = mat.node_tree
    p = nt.nodes['Principled BSDF']
    p.inputs['Specular IOR Level'].default_value = 0.0
    checker = nt.nodes.new('ShaderNodeTexChecker')
    checker.inputs['Scale'].default_value = 3.0
    checker.inputs['Color1'].default_value = (0.0, 0.0, 0.0, 1.0)
    checker.inputs['Color2'].default_value = (0.6, 0.6, 0.6, 1.0)
    nt.links.new(checker.outputs['Color'], p.inputs['Base Color'])
    nmap = world_normal_map(nt)
    nt.links.new(nmap.outputs['Normal'], p.inputs['Normal'])
    diff = normal_pass_diff(tmp_path, sc, mat, smooth=False)
    assert diff.mean() < 0.03, (diff.mean(), np.mean(diff > 0.1))
