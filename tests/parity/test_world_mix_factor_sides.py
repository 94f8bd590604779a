"""A world Mix Shader whose factor is a texture of the view direction (a Gradient) between shaders
that are not two Backgrounds of constant or procedural colour: a Light Path mix (Is Camera Ray:
the camera sees one world, the ball is lit by another), a Background of an Environment Texture;
and an Add Shader of two Environment Textures. Each side is exported as the world is, for the same
rays, and the two blended per direction into one map (export/world.py _factor_mix,
export/worldmix.py); a factor of Is Camera Ray x the Gradient computes per ray kind (the camera
sees the mix, the ball is lit by the image alone), against Cycles: an equirectangular camera's image by quarters of rows and
columns, and a diffuse ball lit by that world.

The factor had stood at its own value 0.5, said ("world Mix Shader factor not computed ... its own
value 0.5 used"; fuzz seeds 200, 208, 215, 221, 223, 227, 241, 246, 250: 0.71-1.31x Cycles per
channel), the Light Path output inside the factor's chain at its socket's own value, and the
second of two added maps had been ignored, said."""

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image(name, turn):
    h, w = 16, 32
    px = np.ones((h, w, 4), np.float32)
    px[..., 0] = np.roll(np.linspace(0.1, 3.0, w), turn)[None, :]
    px[..., 1] = np.linspace(0.2, 1.5, h)[:, None]
    px[..., 2] = 0.3
    return scenes.float_image(name, px)


def _background(nt, color, strength=1.0, image=None):
    bg = nt.nodes.new('ShaderNodeBackground')
    bg.inputs['Color'].default_value, bg.inputs['Strength'].default_value = color + (1.0,), strength
    if image is not None:
        env = nt.nodes.new('ShaderNodeTexEnvironment')
        env.image = image
        nt.links.new(env.outputs['Color'], bg.inputs['Color'])
    return bg


def _scene(case):
    sc, world = scenes.panorama_world("Sides", samples=32)
    nt = world.node_tree
    nt.nodes.remove(nt.nodes['Background'])
    out = nt.nodes['World Output']
    if case == 'two_images_added':
        add = nt.nodes.new('ShaderNodeAddShader')
        nt.links.new(_background(nt, (1, 1, 1), 0.5, _image("A", 0)).outputs[0], add.inputs[0])
        nt.links.new(_background(nt, (1, 1, 1), 1.0, _image("B", 11)).outputs[0], add.inputs[1])
        nt.links.new(add.outputs[0], out.inputs['Surface'])
        return sc
    if case == 'light_path':
        first = nt.nodes.new('ShaderNodeMixShader')
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], first.inputs['Fac'])
        nt.links.new(_background(nt, (1.0, 0.5, 0.2)).outputs[0], first.inputs[1])
        nt.links.new(_background(nt, (0.2, 0.4, 1.0), 2.0).outputs[0], first.inputs[2])
    else:
        first = _background(nt, (1, 1, 1), 1.0, _image("A", 0))
    mix = nt.nodes.new('ShaderNodeMixShader')
    tex = nt.nodes.new('ShaderNodeTexGradient')
    coordinates = nt.nodes.new('ShaderNodeTexCoord')
    nt.links.new(coordinates.outputs['Normal'], tex.inputs['Vector'])
    nt.links.new(tex.outputs['Fac'], mix.inputs['Fac'])
    if case == 'camera_ray_times_gradient':     # (the camera sees the mix, the ball is lit by the image)
        times = nt.nodes.new('ShaderNodeMath')
        times.operation = 'MULTIPLY'
        nt.links.new(tex.outputs['Fac'], times.inputs[0])
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], times.inputs[1])
        nt.links.new(times.outputs[0], mix.inputs['Fac'])
    nt.links.new(first.outputs[0], mix.inputs[1])
    nt.links.new(_background(nt, (0.1, 1.0, 0.2), 1.5).outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return sc


@pytest.mark.parametrize('case', ['light_path', 'image', 'camera_ray_times_gradient', 'two_images_added'])
def test_world_mix_of_maps_and_light_path_worlds_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(case)
    scenes.panorama_agrees(sc, tmp_path, case)
    assert not [t for t in said if "factor not computed" in t or "second ignored" in t], said
    baked = "Mix Shader factor from" if case != 'two_images_added' else "two environment maps in the world summed"
    assert [t for t in said if baked in t and "x 512 map" in t], said
