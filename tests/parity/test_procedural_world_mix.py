"""A world Mix Shader whose factor comes from procedural textures of the view direction (a
Gradient's Fac, a Noise's), between two Backgrounds of constant or procedural colour: (1 - f) A
+ f B baked into the environment map (export/world.py _procedural_mix) that the environment
light blends and samples, against Cycles: an equirectangular camera's image by quarters of
rows and columns, and a diffuse ball lit by that world.

The factor had stood at its own value, said ("world Mix Shader factor not computed ... its own
value 0.5 used"): a Gradient's mix of an orange and a blue Background 0.55x-5.5x Cycles by
quarters.
"""

import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(factor, second):
    sc, world = scenes.panorama_world("Mixed", samples=32)
    nt = world.node_tree
    bg = nt.nodes['Background']
    bg.inputs['Color'].default_value = (1.0, 0.3, 0.1, 1.0)
    other = nt.nodes.new('ShaderNodeBackground')
    other.inputs['Color'].default_value = (0.1, 0.3, 1.0, 1.0)
    other.inputs['Strength'].default_value = 2.0
    if second == 'noise':
        nt.links.new(nt.nodes.new('ShaderNodeTexNoise').outputs['Color'], other.inputs['Color'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    tex = nt.nodes.new('ShaderNodeTexGradient' if factor == 'gradient' else 'ShaderNodeTexNoise')
    if factor == 'noise':
        tex.inputs['Scale'].default_value = 2.0
    nt.links.new(tex.outputs['Fac'], mix.inputs['Fac'])
    nt.links.new(bg.outputs[0], mix.inputs[1])
    nt.links.new(other.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], nt.nodes['World Output'].inputs['Surface'])
    return sc


@pytest.mark.parametrize('factor, second', [('gradient', 'constant'), ('noise', 'noise')],
                         ids=['gradient', 'noise-of-noise'])
def test_world_mix_by_texture_factor_agrees_with_cycles(factor, second, tmp_path, said):
    sc = _scene(factor, second)
    scenes.panorama_agrees(sc, tmp_path, factor)
    assert not [t for t in said if "factor not computed" in t], said
    assert [t for t in said if "Mix Shader factor from" in t and "baked into a 1024 x 512 map" in t], said
