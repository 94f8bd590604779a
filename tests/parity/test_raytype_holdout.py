"""The 'held out but casts shadows' matte: Mix(Diffuse, Holdout, Is Camera Ray). Cycles holds
the surface out for camera rays (alpha 0, black) while bounce and shadow rays see the Diffuse:
it shadows and lights the floor. DACRT had read the factor at its own value, a 50% mix at
alpha 1; now camera rays see a holdout twin of its triangles (export.assembly._clear_twins)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_camera_holdout_matte_matches_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 32
    mat, nt, mix, a, b = scenes.mix_shader_material("Matte", 'ShaderNodeBsdfDiffuse', 'ShaderNodeHoldout')
    a.inputs['Color'].default_value = (0.9, 0.2, 0.1, 1.0)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    scenes.plane("Floor", size=4, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    # a plate 1 m above the floor at x 0.5..1.5 (pixels 20-27); the sun casts its shadow at
    # x -0.5..0.5 (pixels 12-19)
    scenes.mesh("Plate", [(0.5, -0.5, 1), (1.5, -0.5, 1), (1.5, 0.5, 1), (0.5, 0.5, 1)], [(0, 1, 2, 3)],
                materials=[mat])
    scenes.light('SUN', 3.0, rotation=(0, math.radians(45), 0))
    scenes.world((0.1, 0.1, 0.1), 1.0)
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 2
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    layer = sc.view_layers[0].name
    px = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1)
          for e, exr in scenes.render_engines(sc, tmp_path).items()}
    regions = {'plate': (slice(13, 19), slice(21, 27)), 'shadow': (slice(13, 19), slice(13, 19)),
               'open floor': (slice(13, 19), slice(2, 9))}
    c_plate = px['CYCLES'][regions['plate']].mean(axis=(0, 1))
    assert np.allclose(c_plate, 0.0, atol=1e-3), c_plate          # held out: black, alpha 0
    for name, region in regions.items():
        d, c = (px[e][region].mean(axis=(0, 1)) for e in ('DACRT', 'CYCLES'))
        np.testing.assert_allclose(d, c, rtol=0.03, atol=0.003, err_msg=name)
    np.testing.assert_allclose(px['DACRT'].mean(axis=(0, 1)), px['CYCLES'].mean(axis=(0, 1)), rtol=0.02)
