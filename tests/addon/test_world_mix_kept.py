"""Exports of an unchanged blended world (a world Mix Shader with a textured factor, an Add of two
maps: export/worldmix.py) reuse the blended map made before (worldkeep.kept_map): at an HDRI's
width it had been made again on every export (~5.8 s of CPU a 4096 x 2048 image beside a colour).
A change to either side (an image's texels, a colour, a Sky's parameters) or to the factor makes it
again, and the frame renders exactly as it does with nothing kept."""
import gc
import math
import weakref

import numpy as np
import pytest

from addon import scenedata as sd
from addon.export import worldkeep, worldmix
from addon.lights import envkeep

from . import scenes


@pytest.fixture(autouse=True)
def nothing_kept():
    worldkeep.forget()
    envkeep.forget()
    yield
    worldkeep.forget()
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
    worldkeep.forget()
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert not np.array_equal(before, fresh)          # (the change shows in the image)
    assert np.array_equal(after, fresh), np.abs(after - fresh).max()


def _part(px, key=None):
    return sd.Environment(px, np.ones(3, np.float32), np.eye(3), 'Linear', texels_key=key)


def _directions(width, height):
    from addon.export.world import _equirect_directions
    return _equirect_directions(width, height)


def test_texels_written_in_place_are_blended_again():
    """An image's array kept and then written in place (Blender's buffer, or a script) is not
    the same texels: made again; a read-only array given again is reused."""
    px = np.random.default_rng(2).uniform(0, 1, (512, 1024, 3)).astype(np.float32)
    colour = (np.array([0.1, 1.0, 0.2], np.float32), None)
    first = worldkeep.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    px[10:20] = 7.0
    second = worldkeep.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    assert second is not first and not np.array_equal(second.pixels, first.pixels)
    px.setflags(write=False)
    third = worldkeep.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024)
    assert worldkeep.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 1024) is third
    assert np.array_equal(third.pixels, second.pixels)
    assert not third.pixels.flags.writeable and third.texels_key is not None


def test_a_kept_writable_array_rewritten_to_new_bits_is_not_taken_for_them():
    """A kept writable array written in place to hold another array's bits: that other array
    is not the kept texels (the map was blended from the old bits). Kept by its bits' digest,
    not the array itself, which is not held."""
    rng = np.random.default_rng(3)
    old = rng.uniform(0, 1, (256, 512, 3)).astype(np.float32)
    new = rng.uniform(0, 1, (256, 512, 3)).astype(np.float32)
    colour = (np.array([0.1, 1.0, 0.2], np.float32), None)
    first = worldkeep.kept_map([(np.zeros(3, np.float32), _part(old)), colour], _directions, 512)
    old[:] = new
    second = worldkeep.kept_map([(np.zeros(3, np.float32), _part(new)), colour], _directions, 512)
    assert second is not first and not np.array_equal(second.pixels, first.pixels)
    gone = weakref.ref(old)
    del old
    gc.collect()
    assert gone() is None           # (the writable texels are not held)
    assert worldkeep.kept_map([(np.zeros(3, np.float32), _part(new.copy())), colour], _directions, 512) is second


def test_kept_maps_are_released_when_a_file_is_loaded():
    """A new file (load_post / load_factory_startup_post) drops the kept maps and the environment
    light's kept native maps: their memory is back."""
    import bpy
    px = np.random.default_rng(4).uniform(0, 1, (256, 512, 3)).astype(np.float32)
    colour = (np.array([0.1, 1.0, 0.2], np.float32), None)
    env = worldkeep.kept_map([(np.zeros(3, np.float32), _part(px)), colour], _directions, 512)
    envkeep.native_map(env, np.eye(3), 'Linear', np.ones(3, np.float32))
    assert envkeep._kept
    gone = weakref.ref(env.pixels)
    del env
    gc.collect()
    assert gone() is not None            # (kept)
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    gc.collect()
    assert gone() is None and not envkeep._kept


def test_a_map_over_the_byte_budget_is_not_kept_and_old_ones_make_room(monkeypatch):
    """At most _KEEP_BYTES of maps are kept: a bigger one is blended every time; a new one
    drops the least recently used until it fits."""
    colour = (np.array([0.1, 1.0, 0.2], np.float32), None)

    def parts(seed):
        px = np.random.default_rng(seed).uniform(0, 1, (64, 128, 3)).astype(np.float32)
        return [(np.zeros(3, np.float32), _part(px)), colour]
    map_bytes = 64 * 128 * 3 * 4
    monkeypatch.setattr(worldkeep, '_KEEP_BYTES', map_bytes - 1)
    a = parts(5)
    assert worldkeep.kept_map(a, _directions, 128) is not worldkeep.kept_map(a, _directions, 128)
    monkeypatch.setattr(worldkeep, '_KEEP_BYTES', 2 * map_bytes)
    a, b, c = parts(5), parts(6), parts(7)
    ma, mb = worldkeep.kept_map(a, _directions, 128), worldkeep.kept_map(b, _directions, 128)
    assert worldkeep.kept_map(a, _directions, 128) is ma         # (a now the most recently used)
    worldkeep.kept_map(c, _directions, 128)                      # (drops b)
    assert worldkeep.kept_map(a, _directions, 128) is ma
    assert worldkeep.kept_map(b, _directions, 128) is not mb
