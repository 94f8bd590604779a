"""The Geometry node's outputs as an Environment Texture's Vector in the world, as Cycles reads
them (shader_setup_from_background: P = D, N = Ng = I = -D): Position is the view direction,
Normal, True Normal and Incoming its opposite, straight into the map and through a Mapping
rotation, with nothing reported. They had been read as +D and reported as approximations
("environment coordinates from 'Geometry' Position read as the view direction"): Position
right but said to be wrong, Normal and Incoming the map's other side (red mean 0.886 where
Cycles shows 0.314). The camera sees only the world: measured within 0.3% of Cycles per 8 x 8
block at 16 samples (the noise of each pixel's points in the map; image means equal to 4 digits)."""
import math

import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

W, H = 64, 32
SIGNS = {'Position': 1, 'Normal': -1, 'True Normal': -1, 'Incoming': -1}


def _env_image():
    u, v = np.meshgrid((np.arange(64) + 0.5) / 64, (np.arange(32) + 0.5) / 32)
    px = np.ones((32, 64, 4), np.float32)
    px[..., 0] = 0.2 + 0.8 * (0.5 + 0.5 * np.sin(2 * np.pi * u))
    px[..., 1] = 0.1 + 0.9 * v
    px[..., 2] = 0.2 + 0.8 * (0.5 + 0.5 * np.cos(4 * np.pi * u))
    return scenes.float_image("Env", px)


def environment_world():
    """A panoramic camera looking at a world of _env_image, a box-filtered 16-spp direct-light
    setting for both engines; returns (world node tree, its Environment Texture node) for the
    caller to link a vector into (also test_wavelength_rotate's)."""
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    cam = scenes.camera((0, 0, 0), (math.radians(80), 0, math.radians(30)), kind='PANO')
    cam.data.panorama_type = 'EQUIRECTANGULAR'
    world = bpy.data.worlds.new("World")
    sc.world = world
    nt = world.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = _env_image()
    nt.links.new(env.outputs['Color'], nt.nodes['Background'].inputs['Color'])
    sc.render.resolution_x, sc.render.resolution_y = W, H
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    return nt, env


def _scene(output, through_mapping):
    nt, env = environment_world()
    geometry = nt.nodes.new('ShaderNodeNewGeometry')
    if through_mapping:
        mapping = nt.nodes.new('ShaderNodeMapping')
        mapping.inputs['Rotation'].default_value = (math.radians(20), 0.0, math.radians(50))
        nt.links.new(geometry.outputs[output], mapping.inputs['Vector'])
        nt.links.new(mapping.outputs['Vector'], env.inputs['Vector'])
    else:
        nt.links.new(geometry.outputs[output], env.inputs['Vector'])


@pytest.mark.parametrize('through_mapping', (False, True), ids=('direct', 'mapping'))
@pytest.mark.parametrize('output', tuple(SIGNS))
def test_geometry_output_as_world_direction(output, through_mapping, tmp_path, said):
    _scene(output, through_mapping)
    c = sunplane.render_rgb('CYCLES', tmp_path).astype(np.float64)
    d = sunplane.render_rgb('DACRT', tmp_path).astype(np.float64)
    blocks = lambda im: im.reshape(H // 8, 8, W // 8, 8, 3).mean((1, 3))
    err = np.abs(blocks(d) / blocks(c) - 1).max()
    assert err < 0.01, (err, c.reshape(-1, 3).mean(0).round(4), d.reshape(-1, 3).mean(0).round(4))
    assert not [t for t in said if 'world approximated' in t or 'Geometry' in t], said


def test_geometry_output_that_is_no_direction_is_still_reported(tmp_path, said):
    """Parametric is no direction in the world: still read as the view direction and said."""
    import bpy
    _scene('Position', False)
    nt = bpy.context.scene.world.node_tree
    geometry = next(n for n in nt.nodes if n.type == 'NEW_GEOMETRY')
    env = next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT')
    nt.links.new(geometry.outputs['Parametric'], env.inputs['Vector'])
    sunplane.render_rgb('DACRT', tmp_path)
    assert any("'Geometry' Parametric read as the view direction" in t for t in said), said
