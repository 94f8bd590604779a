"""A world Background whose Strength comes from procedural textures of the view direction (a
Spherical Gradient's bright spot, a Noise), its Color a constant or a Gradient too: the product
baked into the environment map (export/world.py _procedural_strength) that the environment light
blends and samples, against Cycles: an equirectangular camera's image by quarters of rows and a
diffuse ball lit by that world.

The Strength had stood at the socket's own value, said ("world Background Strength driven by
nodes; its own value used"): a world dimmed to 0 outside a Gradient's spot rendered its colour
(0.9, 0.6, 0.3) in the top rows where Cycles' are black, a Noise strength 2.07x Cycles' there,
a Noise times a Gradient 2.03x.
"""

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(strength, color):
    sc, world = scenes.panorama_world("Lit", samples=32)
    nt = world.node_tree
    bg = nt.nodes['Background']
    bg.inputs['Color'].default_value = (0.9, 0.6, 0.3, 1.0)
    if strength == 'spot':          # a bright spot round a direction, 0 elsewhere
        coords, mapping = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeMapping')
        mapping.inputs['Location'].default_value = (0.3, -0.8, -0.5)
        mapping.inputs['Scale'].default_value = (1.5, 1.5, 1.5)
        tex = nt.nodes.new('ShaderNodeTexGradient')
        tex.gradient_type = 'SPHERICAL'
        power = nt.nodes.new('ShaderNodeMath')
        power.operation, power.inputs[1].default_value = 'MULTIPLY', 40.0
        nt.links.new(coords.outputs['Generated'], mapping.inputs['Vector'])
        nt.links.new(mapping.outputs[0], tex.inputs['Vector'])
        nt.links.new(tex.outputs['Fac'], power.inputs[0])
        nt.links.new(power.outputs[0], bg.inputs['Strength'])
    else:
        tex = nt.nodes.new('ShaderNodeTexNoise')
        tex.inputs['Scale'].default_value = 3.0
        nt.links.new(tex.outputs['Fac'], bg.inputs['Strength'])
    if color == 'gradient':
        grad = nt.nodes.new('ShaderNodeTexGradient')
        nt.links.new(grad.outputs['Color'], bg.inputs['Color'])
    return sc


@pytest.mark.parametrize('strength, color', [('spot', 'constant'), ('noise', 'constant'), ('noise', 'gradient')],
                         ids=['spot', 'noise', 'noise-times-gradient'])
def test_world_strength_from_textures_agrees_with_cycles(strength, color, tmp_path, said):
    sc = _scene(strength, color)
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c.mean() > 0.005
    for part in np.array_split(np.arange(d.shape[0]), 4):
        np.testing.assert_allclose(d[part].mean(axis=(0, 1)), c[part].mean(axis=(0, 1)), rtol=0.03, atol=0.002,
                                   err_msg=f"{strength} x {color}: rows {part[0]}-{part[-1]}")
    # the ball (the image's centre), lit by the world: the light's direction and amount
    ball = (slice(13, 19), slice(29, 35))
    np.testing.assert_allclose(d[ball].mean(axis=(0, 1)), c[ball].mean(axis=(0, 1)), rtol=0.05, atol=0.002,
                               err_msg=f"{strength} x {color}: ball")
    assert not [t for t in said if "Strength driven by nodes" in t], said
    assert [t for t in said if "Strength from" in t and "baked into a 1024 x 512 map" in t], said


def test_world_strength_from_textures_over_an_image_is_said(tmp_path, said):
    """An Environment Texture's colour times a texture Strength is not baked: said, true."""
    sc = _scene('noise', 'constant')
    nt = sc.world.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = scenes.float_image("Sky", np.full((8, 16, 4), 0.5, np.float32))
    nt.links.new(env.outputs['Color'], nt.nodes['Background'].inputs['Color'])
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "d.exr", sc)
    assert [t for t in said if "Background Strength driven by nodes; its own value used" in t], said
