"""An Environment Texture on Texture Coordinate Camera, against Cycles. In Cycles' background
shader Camera is the direction turned into the camera's frame (svm_texco_camera: worldtocamera of
P + the camera's position, P = D), a rotation of the direction (an axis flip with it): exported
as the map's rotation (mapping.environment_rotation's to_camera), through a Mapping node's too.
It had been read as the view direction, said ("environment coordinates from 'Texture Coordinate'
Camera read as the view direction"): quarters of the view up to 10x off Cycles in a channel.

The scenes: the procedural-world set-up (an equirectangular camera at the origin, a grey ball
that the world lights) and the same with a perspective camera away from the origin, turned, so
that the camera frame is no axis permutation of the world's.
"""

import math

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image():
    h, w = 32, 64
    px = np.zeros((h, w, 4), np.float32)
    px[..., 3] = 1.0
    u, v = np.meshgrid(np.linspace(0, 1, w), np.linspace(0, 1, h))
    px[..., 0] = 0.1 + 2.0 * u ** 2
    px[..., 1] = 0.1 + v
    px[..., 2] = 0.2 + 0.8 * (np.sin(6 * u) > 0) * v
    return scenes.float_image("CameraMap", px)


def _scene(camera, mapped):
    sc, world = scenes.panorama_world("EnvironmentOnCamera", samples=16)
    if camera == 'PERSP':
        old = sc.camera
        scenes.camera(location=(2.0, -3.0, 1.0), rotation=(math.radians(80), 0.3, math.radians(25)), lens=24.0)
        old.users_collection[0].objects.unlink(old)
    nt = world.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = _image()
    coords = nt.nodes.new('ShaderNodeTexCoord')
    if mapped:
        mapping = nt.nodes.new('ShaderNodeMapping')
        mapping.inputs['Rotation'].default_value = (0.2, -0.3, 0.9)
        nt.links.new(coords.outputs['Camera'], mapping.inputs['Vector'])
        nt.links.new(mapping.outputs[0], env.inputs['Vector'])
    else:
        nt.links.new(coords.outputs['Camera'], env.inputs['Vector'])
    nt.links.new(env.outputs['Color'], nt.nodes['Background'].inputs['Color'])
    return sc


@pytest.mark.parametrize('camera, mapped', [('PANO', False), ('PANO', True), ('PERSP', False), ('PERSP', True)])
def test_environment_on_camera_coordinates_agrees_with_cycles(camera, mapped, tmp_path, said):
    sc = _scene(camera, mapped)
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c.mean() > 0.05
    for axis in (0, 1):         # quarters of rows, then of columns
        for part in np.array_split(np.arange(d.shape[axis]), 4):
            np.testing.assert_allclose(np.take(d, part, axis).mean(axis=(0, 1)),
                                       np.take(c, part, axis).mean(axis=(0, 1)), rtol=0.03, atol=0.003,
                                       err_msg=f"axis {axis} {part[0]}-{part[-1]}")
    assert np.abs(d - c).mean() < 0.03 * c.mean() + 0.003, np.abs(d - c).mean()
    assert not [t for t in said if "read as the view direction" in t], said
