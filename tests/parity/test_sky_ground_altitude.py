"""The Multiple Scattering sky's ground (below the horizon) at Altitude 0 as Cycles renders it.

Cycles computes each table row's view ray length to the ground in float32
(ray_sphere_intersection): c = r0^2 - R^2 with r0^2 ~ 4e7 km^2 is rounded to a multiple of 4,
12 where it is 12.74 at Altitude 0 (clamped to 1 m), so its ground paths, and the ground's
light, are ~6% shorter and dimmer than float64 gives. DACRT computed them in float64: the ground
rendered 1.057-1.071x Cycles' at 0 m (0.999x at 100 m, where c is ~1275 +- 4).

The camera sees only the sky, pitched 5 degrees up (the bottom third is ground, -10 to -1.5
degrees), sun at 30 degrees: each channel's mean over three bands of ground rows within 1.5% of
Cycles' (measured within 0.5%), at 0 and 100 m; the sky above within 0.5%."""
import math
import os
from types import SimpleNamespace

import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('altitude', (0.0, 100.0))
def test_ground_below_the_horizon(altitude, tmp_path):
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 64, 48, 100
    vs = sc.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = 'Standard', 'None', 0.0, 1.0
    scenes.camera(location=(0, 0, 0), rotation=(math.radians(95), 0, 0), lens=50)
    w, nt, out = scenes.world_tree()
    bg = nt.nodes.new('ShaderNodeBackground')
    nt.links.new(bg.outputs[0], out.inputs['Surface'])
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sky_type, sky.sun_elevation, sky.altitude = 'MULTIPLE_SCATTERING', math.radians(30), altitude
    nt.links.new(sky.outputs[0], bg.inputs['Color'])
    rendering.fair_scene_settings(sc)
    rows = {}
    for engine, setup in (('CYCLES', rendering.set_cycles), ('DACRT', rendering.set_dacrt)):
        setup(sc, SimpleNamespace(cycles_samples=16, dacrt_samples=16, bounces=1, clamp=(0.0, 0.0),
                                  filter_type='BLACKMAN_HARRIS', filter_width=1.5), 0)
        img = rendering.render_combined(sc, os.path.join(tmp_path, f'{engine}.exr'))
        rows[engine] = img[..., :3].astype(np.float64).mean(axis=1)          # (rows, 3), row 0 at the bottom
    c, d = rows['CYCLES'], rows['DACRT']
    for band in (slice(0, 5), slice(5, 10), slice(10, 14)):
        ratio = d[band].mean(0) / c[band].mean(0)
        assert np.abs(ratio - 1).max() < 0.015, (band, ratio.round(4).tolist())
    ratio = d[20:].mean(0) / c[20:].mean(0)
    assert np.abs(ratio - 1).max() < 0.005, ratio.round(4).tolist()
