"""Exports of an unchanged blended world (a world Mix Shader with a textured factor, an Add of two
maps: export/worldmix.py) reuse the blended map made before (worldmix.kept_map): at an HDRI's
width it had been made again on every export (~5.8 s of CPU a 4096 x 2048 image beside a colour).
A change to either side (an image's texels, a colour, a Sky's parameters) or to the factor makes it
again, and the frame renders exactly as it does with nothing kept."""
import math

import numpy as np
import pytest

from addon import scenedata as sd
from addon.export import worldmix
from addon.lights import envkeep

from . import scenes


@pytest.fixture(autouse=True)
def nothing_kept():
    worldmix.forget()
    envkeep.forget()
    yield
    worldmix.forget()
    envkeep.forget()


def _image():
    h, w = 16, 32
    px = np.ones((h, w, 4), np.float32)
    px[..., 0] = np.linspace(0.1, 3.0, w)[None, :]
    px[..., 1] = np.linspace(0.2, 1.5, h)[:, None]
    px[..., 2] = 0.3
    return scenes.float_image("Sides", px)


def _mixed_world(scene, other='colour'):
    """A Gradient (of the Normal) mixing a Background of an Environment Texture with a
    Background of a colour or of a Preetham Sky Texture, over a diffuse plane; 1 spp."""
    scenes.camera(location=(0, -4, 1.5), rotation=(math.radians(75), 0, 0))
    scenes.plane(size=4, materials=[scenes.diffuse('floor', (0.5, 0.5, 0.5))])
    w, nt, out = scenes.world_tree(scene)
    image_bg, other_bg = nt.nodes.new('ShaderNodeBackground'), nt.nodes.new('ShaderNodeBackground')
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = _image()
    nt.links.new(env.outputs['Color'], image_bg.inputs['Color'])
    other_bg.inputs['Color'].default_value = (0.1, 1.0, 0.2, 1.0)
    if other == 'sky':
        sky = nt.nodes.new('ShaderNodeTexSky')
        sky.sky_type, sky.sun_direction, sky.turbidity = 'PREETHAM', (0.3, 0.5, 0.8), 3.0
        nt.links.new(sky.outputs[0], other_bg.inputs['Color'])
    mix, gradient = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeTexGradient')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Normal'], gradient.inputs['Vector'])
    nt.links.new(gradient.outputs['Fac'], mix.inputs['Fac'])
    nt.links.new(image_bg.outputs[0], mix.inputs[1])
    nt.links.new(other_bg.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scene.dacrt.samples, scene.dacrt.max_bounces = 1, 2
    return env, other_bg, gradient, nt


def test_frames_of_one_blended_world_blend_it_once(scene, calls_to):
    _mixed_world(scene)
    blends = calls_to(worldmix, 'blended_map')
    films = [scenes.render_rgba(scene) for _ in range(3)]
    assert len(blends) == 1, blends
    assert np.array_equal(films[0], films[1]) and np.array_equal(films[0], films[2])


def _texels(env, other, gradient, nt):
    img = env.image
    px = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(px)
    img.pixels.foreach_set(px * np.float32(0.5))
    img.update()
    img.pack()


def _sky(env, other, gradient, nt):
    sky = next(n for n in nt.nodes if n.type == 'TEX_SKY')
    sky.sun_direction = (-0.6, 0.2, 0.4)


CHANGES = {
    'texels': ('colour', _texels),
    'colour': ('colour', lambda env, other, gradient, nt: setattr(other.inputs['Color'], 'default_value',
                                                                   (1.0, 0.2, 0.1, 1.0))),
    'strength': ('colour', lambda env, other, gradient, nt: setattr(other.inputs['Strength'], 'default_value',
                                                                     3.0)),
    'factor': ('colour', lambda env, other, gradient, nt: setattr(gradient, 'gradient_type', 'QUADRATIC')),
    'sky': ('sky', _sky),
}


@pytest.mark.parametrize('change', CHANGES)
def test_a_changed_blended_world_renders_as_with_nothing_kept(scene, change, calls_to):
    other, apply = CHANGES[change]
    nodes = _mixed_world(scene, other)
    blends = calls_to(worldmix, 'blended_map')
    before = scenes.render_rgba(scene)
    apply(*nodes)
    after = scenes.render_rgba(scene)
    assert len(blends) == 2, blends
    worldmix.forget()
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert not np.array_equal(before, fresh)          # (the change shows in the image)
    assert np.array_equal(after, fresh), np.abs(after - fresh).max()


def _part(px, key=None):
    return sd.Environment(px, np.ones(3, np.float32), np.eye(3), 'Linear', texels_key=key)


def _directions(width):
    from addon.export.world import _equirect_directions
    return _equirect_directions(width)


def test_texels_written_in_place_are_blended_again():
    """An image's array kept and then written in place (Blender's buffer, or a script) is not
    the same texels: made again; a read-only array given again is reused."""
    px = np.random.default_rng(2).uniform(0, 1, (512, 1024, 3)).astype(np.float32)
    colour = (np.array([0.1, 1.0, 0.2], np.float32), None)
    first = worldmix.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    px[10:20] = 7.0
    second = worldmix.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    assert second is not first and not np.array_equal(second.pixels, first.pixels)
    px.setflags(write=False)
    third = worldmix.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    assert worldmix.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024) is third
    assert np.array_equal(third.pixels, second.pixels)
    assert not third.pixels.flags.writeable and third.texels_key is not None
