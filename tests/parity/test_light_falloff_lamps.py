"""A Light Falloff feeding a point, spot or area light's Emission, applied as Cycles'
svm_node_light_falloff computes it at each ray's length t to the lamp's point (lights/base.py
Lamp.falloff, native lamps.h falloff_factor): the Linear output x t, Constant x t^2, a Smooth s
x t^2 / (s + t^2), in light samples and where rays meet the lamp; against Cycles by rings
round the lamp (the falloff's shape, not only its mean).

They had been read as the Quadratic output without smoothing, said ("Light Falloff Linear
(smooth 0) as Quadratic without smoothing"): Linear 0.405x Cycles, Constant 0.144x, Quadratic
Smooth 2 1.41x (its centre 1.66x).
"""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(kind, output, smooth, **props):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=8.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    lamp = scenes.light(kind, 100.0, location=(0.5, 0.0, 1.5), name="Lamp", **props)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    falloff = nt.nodes.new('ShaderNodeLightFalloff')
    falloff.inputs['Smooth'].default_value = smooth
    nt.links.new(falloff.outputs[output], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Strength'])
    return sc


CASES = {
    'point_linear': ('POINT', 'Linear', 0.0, dict(shadow_soft_size=0.1)),
    'point_constant': ('POINT', 'Constant', 0.0, dict(shadow_soft_size=0.1)),
    'point_quadratic_smooth': ('POINT', 'Quadratic', 2.0, dict(shadow_soft_size=0.1)),
    'point_delta_linear_smooth': ('POINT', 'Linear', 0.5, dict(shadow_soft_size=0.0)),
    'sphere_point_constant': ('POINT', 'Constant', 0.3, dict(shadow_soft_size=0.4, use_soft_falloff=False)),
    'spot_constant_smooth': ('SPOT', 'Constant', 1.0, dict(spot_size=math.radians(100.0))),
    'area_linear_smooth': ('AREA', 'Linear', 0.5, dict(size=0.8)),
}


@pytest.mark.parametrize('case', list(CASES))
def test_lamp_light_falloff_agrees_with_cycles(case, tmp_path, said):
    kind, output, smooth, props = CASES[case]
    sc = _scene(kind, output, smooth, **props)
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    # rings round the point below the lamp (pixel (27, 24)): the falloff's shape
    r = np.hypot(*np.meshgrid(np.arange(48) - 27.0, np.arange(48) - 24.0))
    for lo, hi in ((0, 6), (6, 14), (14, 40)):
        ring = (r >= lo) & (r < hi)
        if c[ring].mean() > 0.05 * c.max():
            np.testing.assert_allclose(d[ring].mean(), c[ring].mean(), rtol=0.02, err_msg=f"{case}: ring {lo}-{hi}")
    np.testing.assert_allclose(d.mean(), c.mean(), rtol=0.01, err_msg=case)
    assert not [t for t in said if "Light Falloff" in t], said
