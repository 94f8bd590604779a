"""A camera that sees only a Sky Texture world (no geometry), rendered by Cycles and by DACRT
under the fair settings: the scene of the sky ground parity tests."""
import math
import os
from types import SimpleNamespace

import numpy as np

from tests.addon import scenes

from . import rendering


def sky_view(resolution, pitch, lens=50.0, **sky_values):
    """A fresh file: a camera at the origin pitched `pitch` degrees from straight down, of
    `lens` mm, and a world of a Sky Texture of `sky_values` into a Background. The camera."""
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = resolution
    sc.render.resolution_percentage = 100
    vs = sc.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = 'Standard', 'None', 0.0, 1.0
    cam = scenes.camera(location=(0, 0, 0), rotation=(math.radians(pitch), 0, 0), lens=lens)
    w, nt, out = scenes.world_tree()
    bg = nt.nodes.new('ShaderNodeBackground')
    nt.links.new(bg.outputs[0], out.inputs['Surface'])
    sky = nt.nodes.new('ShaderNodeTexSky')
    for key, value in sky_values.items():
        setattr(sky, key, value)
    nt.links.new(sky.outputs[0], bg.inputs['Color'])
    rendering.fair_scene_settings(sc)
    return cam


def both_engines(tmp_path, samples, filter_type, filter_width):
    """{engine: (H, W, 3) float64 RGB, row 0 at the bottom} of the current scene."""
    import bpy
    sc = bpy.context.scene
    img = {}
    for engine, setup in (('CYCLES', rendering.set_cycles), ('DACRT', rendering.set_dacrt)):
        setup(sc, SimpleNamespace(cycles_samples=samples, dacrt_samples=samples, bounces=1, clamp=(0.0, 0.0),
                                  filter_type=filter_type, filter_width=filter_width), 0)
        img[engine] = rendering.render_combined(sc, os.path.join(tmp_path, f'{engine}.exr'))[..., :3].astype(np.float64)
    return img
