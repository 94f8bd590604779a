"""A Ray Portal BSDF whose Position and Direction are unlinked: Cycles continues the ray where
it hit, in its own direction, times the portal's colour, and shadow rays do not pass it: a
Transparent BSDF of that colour with opaque shadows. It had rendered as a white diffuse: a
plate over a floor under a sun (0.699, 0.615, 0.573) where Cycles gives (0.608, 0.568, 0.549)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_unlinked_ray_portal_matches_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 32
    mat = bpy.data.materials.new("Portal")
    nt = mat.node_tree
    nt.nodes.clear()
    portal = nt.nodes.new('ShaderNodeBsdfRayPortal')
    portal.inputs['Color'].default_value = (1.0, 0.5, 0.25, 1.0)
    nt.links.new(portal.outputs[0], nt.nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    scenes.plane("Floor", size=4, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    scenes.mesh("Plate", [(-1.5, -0.5, 1), (1.5, -0.5, 1), (1.5, 0.5, 1), (-1.5, 0.5, 1)], [(0, 1, 2, 3)],
                materials=[mat])
    scenes.light('SUN', 3.0, rotation=(0, math.radians(45), 0))
    scenes.world((0.2, 0.2, 0.2), 1.0)
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    layer = sc.view_layers[0].name
    px = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1)
          for e, exr in scenes.render_engines(sc, tmp_path).items()}
    # the floor through the plate (tinted, in its own shadow) and in the open; the whole image
    for region in ((slice(13, 19), slice(4, 28)), (slice(2, 9), slice(13, 19)), (slice(None), slice(None))):
        d, c = (px[e][region].mean(axis=(0, 1)) for e in ('DACRT', 'CYCLES'))
        np.testing.assert_allclose(d, c, rtol=0.02, atol=0.003)
