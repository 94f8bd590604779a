"""A holdout behind a thin transparent sheet leaves the sheet's Depth, as in Cycles: sample 0's
Depth (film/data_passes.h) is overwritten at every surface its camera ray meets until the pass
is done, and a holdout ends the path before it writes any pass (shade_surface.h), so a ray that
passed the sheet (Alpha 0.25, under the Pass Alpha Threshold) and met a holdout keeps the
sheet's depth. It had been written as the background's (1e10) in the ~75% of pixels whose sample
0 passed (fuzz 9012: Depth 1.8x Cycles' mean, pixels 200x). Orthographic, straight down: every
pixel's Depth is the sheet's, 4 from the camera."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_depth_of_a_sheet_over_a_holdout_matches_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 16, 12
    cam = scenes.camera(location=(0, 0, 5), rotation=(0, 0, 0))
    cam.data.type, cam.data.ortho_scale = 'ORTHO', 3.0
    sheet = scenes.principled("Sheet", (0.7, 0.5, 0.3))
    sheet.node_tree.nodes['Principled BSDF'].inputs['Alpha'].default_value = 0.25
    scenes.plane("Sheet", size=10, location=(0, 0, 1.0), materials=[sheet])
    held, nt, out = scenes._material("Held")
    nt.links.new(nt.nodes.new('ShaderNodeHoldout').outputs[0], out.inputs['Surface'])
    scenes.plane("Held", size=10, location=(0, 0, 0.0), materials=[held])
    scenes.world((0.3, 0.4, 0.6), 1.0)
    sc.view_layers[0].use_pass_z = True
    sc.view_layers[0].pass_alpha_threshold = 0.5
    sc.cycles.samples = sc.dacrt.samples = 4
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        got[engine] = scenes.read_exr(scenes.render_exr(str(tmp_path / f"{engine}.exr"), sc,
                                                        multilayer=True))['ViewLayer.Depth.Z']
    c, d = got['CYCLES'], got['DACRT']
    assert np.allclose(c, 4.0, atol=1e-3), np.unique(c)        # Cycles: the sheet's, everywhere
    assert np.allclose(d, c, atol=1e-3), (np.mean(np.abs(d - c) > 1e-3), np.unique(d)[:4])
