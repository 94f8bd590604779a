"""A world Mix Shader whose factor is read from an image of the view direction: an Image Texture
on Texture Coordinate Generated (Sphere projection) or on Normal through Math (one minus its
Alpha), and an Environment Texture's colour (a float socket: Cycles' colour-to-float, the
luminance), between two Backgrounds of constant colour. The factor is computed per direction
and the two sides blended into one map (export/world.py _factor_mix, export/worldmix.py),
against Cycles: an equirectangular camera's image by eighths and a diffuse ball lit by that
world.

The factor had stood at its own value 0.5, said ("world Mix Shader factor not computed (an
image); its own value 0.5 used"; 0.84-1.30x Cycles by eighths): only procedural textures were
compiled there."""

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _factor_image():
    h, w = 16, 32
    px = np.ones((h, w, 4), np.float32)
    u, v = np.meshgrid(np.linspace(0, 1, w), np.linspace(0, 1, h))
    px[..., 0] = 0.1 + 0.9 * u ** 2
    px[..., 1] = v
    px[..., 2] = 0.5 * (1 - u)
    px[..., 3] = 1 - 0.8 * v
    return scenes.float_image("Fac", px)


def _scene(case):
    sc, world = scenes.panorama_world("ImageFactor", samples=32)
    nt = world.node_tree
    nt.nodes.remove(nt.nodes['Background'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    for i, (color, strength) in enumerate((((1.0, 0.5, 0.2), 1.0), ((0.1, 0.4, 1.0), 2.0))):
        bg = nt.nodes.new('ShaderNodeBackground')
        bg.inputs['Color'].default_value, bg.inputs['Strength'].default_value = color + (1.0,), strength
        nt.links.new(bg.outputs[0], mix.inputs[1 + i])
    coordinates = nt.nodes.new('ShaderNodeTexCoord')
    if case == 'environment':
        tex = nt.nodes.new('ShaderNodeTexEnvironment')
        tex.image = _factor_image()
        nt.links.new(tex.outputs['Color'], mix.inputs['Fac'])
    else:
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = _factor_image()
        if case == 'image_sphere':
            tex.projection = 'SPHERE'
            nt.links.new(coordinates.outputs['Generated'], tex.inputs['Vector'])
            nt.links.new(tex.outputs['Color'], mix.inputs['Fac'])
        else:                       # Normal (-D): one minus the Alpha
            tex.extension = 'EXTEND'
            nt.links.new(coordinates.outputs['Normal'], tex.inputs['Vector'])
            minus = nt.nodes.new('ShaderNodeMath')
            minus.operation = 'SUBTRACT'
            minus.inputs[0].default_value = 1.0
            nt.links.new(tex.outputs['Alpha'], minus.inputs[1])
            nt.links.new(minus.outputs[0], mix.inputs['Fac'])
    nt.links.new(mix.outputs[0], nt.nodes['World Output'].inputs['Surface'])
    return sc


@pytest.mark.parametrize('case', ['image_sphere', 'image_alpha_on_normal', 'environment'])
def test_world_mix_factor_from_an_image_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(case)
    scenes.panorama_agrees(sc, tmp_path, case)
    assert not [t for t in said if "factor not computed" in t], said
    assert [t for t in said if "Mix Shader factor from" in t and "x 512 map" in t], said
