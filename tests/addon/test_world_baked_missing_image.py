"""A world baked into a map of its directions (a Mix Shader whose factor is a Gradient, a colour
mixed by a procedural texture) where one part is an Environment Texture without an image: Cycles'
missing image is opaque magenta, and the bake computes on it; it is said as the unbaked world says
it ("Environment Texture without an image (magenta, as Cycles)"). The Mix Shader's bake had been
silent on it, and a colour mixing it with a texture had stood at the socket's own colour (said
"not evaluated")."""
import numpy as np

from . import scenes


def _missing_env(nt):
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = None
    return env


def _gradient(nt):
    g = nt.nodes.new('ShaderNodeTexGradient')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Normal'], g.inputs['Vector'])
    return g


def test_a_mix_shader_side_without_an_image_is_said(scene, exported):
    scenes.camera()
    w, nt, out = scenes.world_tree(scene)
    magenta, green = nt.nodes.new('ShaderNodeBackground'), nt.nodes.new('ShaderNodeBackground')
    nt.links.new(_missing_env(nt).outputs['Color'], magenta.inputs['Color'])
    green.inputs['Color'].default_value = (0.0, 1.0, 0.0, 1.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(_gradient(nt).outputs['Fac'], mix.inputs['Fac'])
    nt.links.new(magenta.outputs[0], mix.inputs[1])
    nt.links.new(green.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    data = exported()
    px = data.environment.pixels.reshape(-1, 3)
    # (1 - f) magenta + f green: red equals blue, and red + green is 1 in every texel
    np.testing.assert_allclose(px[:, 0], px[:, 2], atol=1e-6)
    np.testing.assert_allclose(px[:, 0] + px[:, 1], 1.0, atol=1e-5)
    assert px[:, 0].max() > 0.9 and px[:, 1].max() > 0.9
    assert any("Environment Texture without an image (magenta, as Cycles)" in t for _, t in data.messages), \
        data.messages


def test_a_colour_mixed_by_a_texture_with_a_missing_image_is_said(scene, exported):
    scenes.camera()
    w, nt, out = scenes.world_tree(scene)
    bg = nt.nodes.new('ShaderNodeBackground')
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    nt.links.new(_gradient(nt).outputs['Fac'], mix.inputs['Factor'])
    nt.links.new(_missing_env(nt).outputs['Color'], mix.inputs['A'])
    mix.inputs['B'].default_value = (0.0, 0.0, 0.0, 1.0)
    nt.links.new(mix.outputs['Result'], bg.inputs['Color'])
    nt.links.new(bg.outputs[0], out.inputs['Surface'])
    data = exported()
    assert data.environment is not None, (data.world, data.messages)
    px = data.environment.pixels.reshape(-1, 3)
    np.testing.assert_allclose(px[:, 0], px[:, 2], atol=1e-6)
    assert px[:, 0].max() > 0.9 and np.abs(px[:, 1]).max() < 1e-6
    assert not any("not evaluated" in t for _, t in data.messages), data.messages
    assert any("Environment Texture without an image (magenta, as Cycles)" in t for _, t in data.messages), \
        data.messages
