"""Frames of an unchanged Sky Texture world reuse its native environment map (lights/envkeep.py):
the map's tables and the bright-texel check are made once, not every frame (~35-60 ms of CPU
of a small frame), and a frame after any change of what the map is made from (the sky's
parameters, the Background's strength, the Mapping rotation of its Vector) renders exactly
as it does with nothing kept."""
import math

import dacrt
import numpy as np
import pytest

from addon.lights import envkeep

from . import scenes


@pytest.fixture(autouse=True)
def nothing_kept():
    envkeep.forget()
    yield
    envkeep.forget()


def _sky_world(scene):
    """A Preetham sky (its map is the quickest to make) through a Mapping node into a
    Background, over a diffuse plane; 1 spp, 2 bounces."""
    scenes.camera(location=(0, -4, 1.5), rotation=(math.radians(75), 0, 0))
    scenes.plane(size=4, materials=[scenes.diffuse('floor', (0.5, 0.5, 0.5))])
    w, nt, out = scenes.world_tree(scene)
    bg = nt.nodes.new('ShaderNodeBackground')
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sky_type, sky.sun_direction, sky.turbidity = 'PREETHAM', (0.3, 0.5, 0.8), 3.0
    coords, mapping = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeMapping')
    nt.links.new(coords.outputs['Generated'], mapping.inputs['Vector'])
    nt.links.new(mapping.outputs['Vector'], sky.inputs['Vector'])
    nt.links.new(sky.outputs[0], bg.inputs['Color'])
    nt.links.new(bg.outputs[0], out.inputs['Surface'])
    scene.dacrt.samples, scene.dacrt.max_bounces = 1, 2
    return sky, bg, mapping



def test_frames_of_one_sky_build_its_map_once(scene, monkeypatch, calls_to):
    _sky_world(scene)
    builds = calls_to(dacrt.lamps, 'environment_map')
    scans = calls_to(dacrt.lamps, 'texel_stats')
    films = [scenes.render_rgba(scene) for _ in range(3)]
    assert len(builds) == 1, builds
    assert len(scans) <= 1, scans
    assert np.array_equal(films[0], films[1]) and np.array_equal(films[0], films[2])


CHANGES = {
    'strength': lambda sky, bg, mapping: setattr(bg.inputs['Strength'], 'default_value', 2.5),
    'rotation': lambda sky, bg, mapping: setattr(mapping.inputs['Rotation'], 'default_value',
                                                 (0.0, 0.0, math.radians(70))),
    'sun': lambda sky, bg, mapping: setattr(sky, 'sun_direction', (-0.6, 0.2, 0.4)),
}


@pytest.mark.parametrize('change', CHANGES)
def test_a_changed_sky_renders_as_with_nothing_kept(scene, change):
    renders_as_with_nothing_kept(scene, CHANGES[change], _sky_world(scene))


def renders_as_with_nothing_kept(scene, change, nodes):
    """Render, apply change(*nodes), render again: the second image is what a render with
    nothing kept (envkeep forgotten) gives, and differs from the first."""
    before = scenes.render_rgba(scene)
    change(*nodes)
    after = scenes.render_rgba(scene)
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert not np.array_equal(before, fresh)          # (the change shows in the image)
    assert np.array_equal(after, fresh), np.abs(after - fresh).max()
