"""An equirectangular world seen exactly at a pole: every ray of an orthographic camera looking
straight down is (0, 0, -1), where u rests on the signs of the zero x and y alone. Cycles
(direction_to_equirectangular, atan2f(dir.y, dir.x)) reads u = 0.5 there: its camera sums
products, one of them +0, so its zeros are +0. DACRT's orthographic direction is -forward,
(-0, -0, -1), and atan2(-0, -0) = -pi read the u = 0 seam column instead: a map whose pole row
varies along u rendered blue 0.3315 where Cycles shows 0.2521 (1.31x), at every camera turn
about Z. The lookup now reads a -0 as +0 (native/cpp/environment.cpp, lights/environment.py):
the same column as Cycles; a camera looking up (no exact zeros) was and is equal."""
import math

import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')


def _pole_image():
    """(h, w, 4): x, y and a blue that varies along u in the pole rows."""
    h, w = 30, 60
    y, x = np.mgrid[0:h, 0:w] / np.array([h, w])[:, None, None]
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = np.stack([x, y, 0.5 + 0.5 * np.sin(8 * x + 5 * y)], -1) * 2
    return px


def _scene(rotation):
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    scenes.camera((0, 0, 10), rotation, kind='ORTHO')
    world = bpy.data.worlds.new("World")
    sc.world = world
    nt = world.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = scenes.float_image("Pole", _pole_image())
    nt.links.new(env.outputs['Color'], nt.nodes['Background'].inputs['Color'])
    nt.nodes['Background'].inputs['Strength'].default_value = 0.3
    sc.render.resolution_x, sc.render.resolution_y = 8, 6
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    sc.view_settings.view_transform = 'Standard'


@pytest.mark.parametrize('rotation', [(0, 0, 0), (0, 0, math.pi / 2), (0, 0, math.pi), (math.pi, 0, 0)],
                         ids=['down', 'down-turned-90', 'down-turned-180', 'up'])
def test_orthographic_camera_at_the_pole_reads_cycles_column(rotation, tmp_path):
    _scene(rotation)
    c = sunplane.render_rgb('CYCLES', tmp_path).reshape(-1, 3).mean(0).astype(np.float64)
    d = sunplane.render_rgb('DACRT', tmp_path).reshape(-1, 3).mean(0).astype(np.float64)
    assert np.abs(d / c - 1).max() < 0.005, (c.round(4), d.round(4))


def test_signed_zeros_read_one_column():
    """The map's own eval: every sign of the zero x and y at either pole reads what +0 reads
    (Cycles' atan2f(+0, +0) = 0, u = 0.5), natively and in the readable definition."""
    import dacrt
    rgb = np.ascontiguousarray(_pole_image()[..., :3])
    env = dacrt.lamps.environment_map(rgb)
    for z in (-1.0, 1.0):
        D = np.array([[0.0, -0.0, 0.0, -0.0], [0.0, 0.0, -0.0, -0.0], [z] * 4], np.float32)
        L, _ = env.eval(D)
        assert np.array_equal(L, np.repeat(L[:, :1], 4, axis=1)), L
        # u = 0.5: between the middle columns; the pole rows wrap (REPEAT) into the other pole's
        row = (rgb[0] + rgb[-1]) / 2
        np.testing.assert_allclose(L[:, 0], (row[29] + row[30]) / 2, rtol=1e-5)
