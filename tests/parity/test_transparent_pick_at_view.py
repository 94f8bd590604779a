"""Behind a sheet of Alpha below the Pass Alpha Threshold, the share of camera paths that pass
it agrees with Cycles when the sheet has a specular layer or metal. Cycles picks between its
transparent closure and the others by their sample weights, a microfacet closure's its
weight x its albedo estimate at the view (bsdf_microfacet_estimate_albedo), not averaged over
views. The Normal pass (Pass Alpha Threshold 0.5 above the sheet's Alpha 0.438) is written by
the paths that pass, so its Z is the passing share. Before, the pick weighed the layer's
albedo averaged over views: straight on with Specular IOR Level 0.5, 0.956 against Cycles'
0.972."""
import math

import bpy
import pytest

from tests.addon import scenes
from tests.parity.normalpass import passing_share

pytestmark = pytest.mark.usefixtures('parity_addon')


def _passing_share(tmp_path, engine, metallic, tilt):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 16, 12
    d = 5.0
    cam = scenes.camera(location=(0, -d * math.sin(tilt), d * math.cos(tilt)), rotation=(tilt, 0, 0))
    cam.data.type = 'ORTHO'
    cam.data.ortho_scale = 2.0
    mat = scenes.principled('P', (0.2, 0.2, 0.2))
    p = mat.node_tree.nodes['Principled BSDF']
    p.inputs['Alpha'].default_value = 0.438
    p.inputs['Metallic'].default_value = metallic
    p.inputs['Roughness'].default_value = 0.3
    p.inputs['Specular IOR Level'].default_value = 0.5
    scenes.plane('Sheet', size=40, materials=[mat])
    return passing_share(tmp_path, sc, engine)


@pytest.mark.parametrize('metallic, tilt', [(0.0, 0.0), (0.0, 1.4), (0.5, 0.0)])
def test_share_of_paths_passing_a_specular_sheet_matches_cycles(tmp_path, metallic, tilt):
    cycles = _passing_share(tmp_path, 'CYCLES', metallic, tilt)
    dacrt = _passing_share(tmp_path, 'DACRT', metallic, tilt)
    # (24576 paths: the share's noise is about 0.001)
    assert abs(dacrt - cycles) < 0.006, (cycles, dacrt)
