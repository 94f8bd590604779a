"""The Mist pass agrees with Cycles: blocks on a floor seen by perspective and orthographic
cameras, under the world's mist settings (each falloff) and without a world (Cycles' film
defaults). Mist depends only on where each camera ray first meets a surface, so both engines
converge to the same pixel-filtered value; at 64 spp the remaining difference is the pixel
filter's sampling noise at edges (measured ~0.0004 mean, < 0.05 at worst)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(kind, falloff):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 32
    scenes.camera(location=(0, -6, 2), rotation=(math.radians(75), 0, 0), kind=kind)
    scenes.plane(size=30, materials=[scenes.diffuse("Floor", (0.8, 0.5, 0.3))])
    scenes.cube(size=1, location=(1, 0, 0.5), materials=[scenes.diffuse("Block", (0.2, 0.7, 0.2))])
    scenes.uv_sphere(radius=0.6, location=(-1.2, 1.5, 0.6), materials=[scenes.diffuse("Ball", (0.7, 0.2, 0.2))])
    if falloff is not None:
        scenes.world((0.3, 0.4, 0.6), 1.0)
        m = sc.world.mist_settings
        m.start, m.depth, m.falloff = 2.0, 9.0, falloff
    sc.view_layers[0].use_pass_mist = True
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc


@pytest.mark.parametrize('kind,falloff', [('PERSP', 'QUADRATIC'), ('ORTHO', 'LINEAR'),
                                          ('PERSP', 'INVERSE_QUADRATIC'), ('PERSP', None)])
def test_mist_pass_matches_cycles(kind, falloff, tmp_path):
    sc = _scene(kind, falloff)
    mist = {engine: exr[f"{sc.view_layers[0].name}.Mist.Z"]
            for engine, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = mist['DACRT'], mist['CYCLES']
    assert d.shape == c.shape == (32, 48)
    assert 0.05 < c.mean() < 0.95 and c.std() > 0.05, "the mist must vary across the view"
    diff = np.abs(d - c)
    assert diff.mean() < 0.003 and diff.max() < 0.1, (diff.mean(), diff.max())
