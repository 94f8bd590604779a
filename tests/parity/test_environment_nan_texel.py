"""A NaN texel in a world's Environment Texture (Linear), against Cycles. Cycles' bilinear lookup
is NaN in that channel wherever it blends the texel in (two texels by two around its centre),
and its film's ensure_finite drops it: black there in that channel. DACRT's export had zeroed
the texel, so its neighbours' blends still lit most of that area (red means; green and blue,
0.5 and 0.4, equal):
- seen by the camera: 0.4492 where Cycles shows 0.2846 (1.58x), now 0.2845;
- lighting a diffuse plane: 0.3914 where Cycles gives 0.3673 (1.066x), now 0.3672.
The native lookups now read 0 in the channel of every blend that takes the texel in, as Cycles,
the other channels untouched, and the message says so."""
import math

import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

H, W, I, J = 8, 16, 5, 3          # the map and its NaN texel's row (from the bottom) and column


def _scene(seen):
    import bpy
    from mathutils import Vector
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    px = np.full((H, W, 4), 0.5, np.float32)
    px[..., 3] = 1.0
    px[I, J, 0] = np.nan
    world = bpy.data.worlds.new("World")
    sc.world = world
    nt = world.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = scenes.float_image("Bad", px)
    nt.links.new(env.outputs['Color'], nt.nodes['Background'].inputs['Color'])
    if seen:
        # toward the texel's centre (module doc of lights/environment.py: u = 0.5 - phi / 2 pi,
        # v = 1 - theta / pi), a 60-degree view across the texels around it
        theta, phi = math.pi * (1.0 - (I + 0.5) / H), math.pi * (1.0 - 2.0 * (J + 0.5) / W)
        d = Vector((math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)))
        cam = scenes.camera((0, 0, 0), (0, 0, 0), lens=31.2)
        cam.rotation_euler = d.to_track_quat('-Z', 'Y').to_euler()
        sc.render.resolution_x, sc.render.resolution_y = 24, 24
        samples, bounces = 16, 0
    else:
        scenes.plane(size=2.0, materials=[scenes.diffuse('grey', (0.8, 0.8, 0.8))])
        scenes.camera((0, 0, 2.5), (0, 0, 0), lens=50)
        sc.render.resolution_x, sc.render.resolution_y = 16, 12
        samples, bounces = 256, 1
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = bounces
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    sc.view_settings.view_transform = 'Standard'


@pytest.mark.parametrize('seen', [True, False], ids=['seen', 'lighting-a-plane'])
def test_a_nan_texel_blacks_out_every_blend_taking_it_in_as_cycles(seen, tmp_path, monkeypatch):
    from tests.reports import recorded_reports
    _scene(seen)
    said = recorded_reports(monkeypatch)
    c = sunplane.render_rgb('CYCLES', tmp_path).reshape(-1, 3).mean(0).astype(np.float64)
    d = sunplane.render_rgb('DACRT', tmp_path).reshape(-1, 3).mean(0).astype(np.float64)
    # red darkened as Cycles' (seen: the camera's pixel footprints blend alike; lit: noise),
    # green and blue as without the NaN
    assert abs(d[0] / c[0] - 1) < (0.02 if seen else 0.015), (c.round(4), d.round(4))
    assert np.abs(d[1:] / c[1:] - 1).max() < (0.005 if seen else 0.015), (c.round(4), d.round(4))
    assert c[0] < (0.9 if seen else 0.97) * c[1], "the NaN texel no longer darkens Cycles' red"
    assert any("image 'Bad': 1 pixel(s) not finite: the lookups that blend them in read 0 in those channels "
               "(black there, as in Cycles)" in t for t in said), said
