"""Each pixel's sample 0 goes where Cycles' does: its filter table (addon/filter.py, a port of
util_cdf_inverted) is centred on entry 511 of 1024, so a lookup at u = 0.5 lands half a table
step right of and above the pixel centre. The Depth, Position and index passes keep sample 0,
without noise: a floor seen at a grazing angle, whose depth changes by about 2 per pixel row,
had its Depth 0.1% off Cycles' at a Gaussian filter of width 10 (fuzz seed 31004, an offset of
0.0031 pixels), where DACRT's table had been centred on entry 511.5."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize("kind,width", [('GAUSSIAN', 10.0), ('BLACKMAN_HARRIS', 1.5)])
def test_sample_zero_depth_of_a_grazing_floor_is_cycles(kind, width, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 24, 16
    scenes.plane("Floor", size=60.0, location=(0, 0, -1), materials=(scenes.diffuse("F", (0.5, 0.5, 0.5)),))
    scenes.camera((0.3, -6.5, 1.0), (math.radians(80), 0, 0.05), kind='ORTHO', ortho_scale=5.0)
    scenes.black_world()
    rendering.matched(sc, 1)
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = kind
    sc.cycles.filter_width = sc.dacrt.filter_width = width
    sc.view_layers[0].use_pass_z = True
    layer = sc.view_layers[0].name
    depth = {e: exr[f"{layer}.Depth.Z"].astype(np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    floor = depth['CYCLES'] < 1e3
    assert floor.mean() > 0.9
    rows = np.diff(depth['CYCLES'][floor.all(axis=1)], axis=0).mean()
    assert abs(rows) > 0.5                              # (grazing: the depth changes fast per row)
    off = np.abs(depth['DACRT'] - depth['CYCLES'])[floor]
    # (within float rounding; the half step alone is 0.0031 x the row step at Gaussian 10)
    assert off.max() < 2e-5 * depth['CYCLES'][floor].max(), (off.max(), rows)
