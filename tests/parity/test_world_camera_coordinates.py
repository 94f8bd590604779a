"""A world textured on Texture Coordinate Camera, Window or Reflection, against Cycles. In Cycles'
background shader (svm_node_tex_coord with no object) Reflection is wi = -D, Camera is D turned
into the camera's frame (worldtocamera of D + the camera's position) and Window is D's place on
the view (camera_world_to_ndc: a perspective camera adds its position to P = D, a panorama
projects the direction): all functions of the direction, baked as the other coordinates
(export/world.py _baked). They had stood at the socket's own value, said (fuzz 1401, 1409, 1419,
1420, 1444, 1467).

The scenes: the procedural-world set-up (an equirectangular camera at the origin, a grey ball
that the world lights), and the same with a perspective camera away from the origin, turned and
shifted, so that Window and Camera differ from the world direction and the ball's light comes
from directions behind the camera too. An orthographic camera's rays read Window at their
origins in Cycles (per pixel), which is said.
"""

import math

import numpy as np
import pytest

from addon.export.world import ORTHO_WINDOW_SAID
from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(coordinate, texture, output, camera):
    sc, world = scenes.panorama_world("WorldCoordinates", samples=16)
    if camera != 'PANO':
        old = sc.camera
        cam = scenes.camera(location=(2.0, -3.0, 1.0), rotation=(math.radians(80), 0.3, math.radians(25)),
                            lens=28.0, kind=camera, ortho_scale=7.0)
        cam.data.shift_x, cam.data.shift_y = 0.15, -0.1
        old.users_collection[0].objects.unlink(old)
    nt = world.node_tree
    tex = nt.nodes.new(texture[0])
    for k, v in texture[1].items():
        setattr(tex, k, v)
    coords, mapping = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeMapping')
    mapping.inputs['Rotation'].default_value = (0.2, -0.3, 0.4)
    nt.links.new(coords.outputs[coordinate], mapping.inputs['Vector'])
    nt.links.new(mapping.outputs[0], tex.inputs['Vector'])
    nt.links.new(tex.outputs[output], nt.nodes['Background'].inputs['Color'])
    return sc


_LINEAR = ('ShaderNodeTexGradient', {'gradient_type': 'LINEAR'})
_NOISE = ('ShaderNodeTexNoise', {})
CASES = {
    'window_pano': ('Window', _LINEAR, 'Color', 'PANO'),
    'camera_pano': ('Camera', _NOISE, 'Color', 'PANO'),
    'reflection_pano': ('Reflection', _NOISE, 'Color', 'PANO'),
    'window_persp': ('Window', _LINEAR, 'Color', 'PERSP'),
    'camera_persp': ('Camera', _NOISE, 'Color', 'PERSP'),
    'reflection_persp': ('Reflection', ('ShaderNodeTexGradient', {'gradient_type': 'QUADRATIC'}), 'Fac', 'PERSP'),
}


@pytest.mark.parametrize('case', list(CASES))
def test_world_on_camera_window_reflection_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(*CASES[case])
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c.mean() > 0.02
    for axis in (0, 1):         # quarters of rows, then of columns
        for part in np.array_split(np.arange(d.shape[axis]), 4):
            np.testing.assert_allclose(np.take(d, part, axis).mean(axis=(0, 1)),
                                       np.take(c, part, axis).mean(axis=(0, 1)), rtol=0.03, atol=0.003,
                                       err_msg=f"{case}: axis {axis} {part[0]}-{part[-1]}")
    assert np.abs(d - c).mean() < 0.03 * c.mean() + 0.003, np.abs(d - c).mean()
    assert not [t for t in said if "not evaluated" in t], said
    assert [t for t in said if "baked into a 1024 x 512 map" in t], said
    assert not [t for t in said if ORTHO_WINDOW_SAID in t], said


def test_orthographic_camera_on_window_is_said(tmp_path, said):
    """Cycles' orthographic camera rays read Window at their origins; DACRT's at their direction:
    said there, and only there (the perspective case above asserts it is not)."""
    sc = _scene('Window', _LINEAR, 'Color', 'ORTHO')
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "ortho.exr", sc)
    assert [t for t in said if ORTHO_WINDOW_SAID in t], said
