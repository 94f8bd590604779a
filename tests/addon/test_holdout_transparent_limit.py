"""A holdout seen through a clear sheet after Transparent Max Bounces is used up: Cycles ends
the path at that surface (black, alpha 1), it holds nothing out; DACRT had held it out all the
same (alpha 0.2, one minus the sheet's 0.8). Measured in Cycles 5.0 for a plain Holdout and for
the camera-only matte Mix(Diffuse, Holdout, Is Camera Ray): limit 0 and 1 black at alpha 1,
limit 8 alpha 0.2. Closed form here: the plate's pixels seen through the sheet."""
import math

import numpy as np
import pytest

from . import scenes


@pytest.mark.parametrize('kind', ['holdout', 'camera-only matte'])
def test_a_holdout_past_the_transparent_limit_ends_the_path(scene, kind):
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.render.film_transparent = True
    mat, nt, mix, a, b = scenes.mix_shader_material("Matte", 'ShaderNodeBsdfDiffuse', 'ShaderNodeHoldout')
    if kind == 'holdout':
        mix.inputs['Fac'].default_value = 1.0
    else:
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    clear, cnt, cout = scenes._material("Clear")
    t = cnt.nodes.new('ShaderNodeBsdfTransparent')
    t.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    cnt.links.new(t.outputs[0], cout.inputs['Surface'])
    scenes.plane("Floor", size=4)
    scenes.plane("Plate", size=1, location=(0, 0, 1), materials=[mat])
    scenes.plane("Sheet", size=4, location=(0, 0, 2), materials=[clear])
    scenes.light('SUN', 3.0, rotation=(0, math.radians(45), 0))
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    scene.dacrt.samples, scene.dacrt.max_bounces, scene.dacrt.filter_type = 8, 1, 'BOX'
    alpha = {}
    for limit in (0, 1, 8):
        scene.dacrt.transparent_max_bounces = limit
        px = scenes.render_rgba(scene)[13:19, 13:19]
        alpha[limit] = float(px[..., 3].mean())
        if limit < 8:
            assert np.abs(px[..., :3]).max() == 0.0, (limit, px[..., :3].max())
    assert alpha[0] == pytest.approx(1.0) and alpha[1] == pytest.approx(1.0), alpha
    assert alpha[8] == pytest.approx(0.2, abs=1e-5), alpha
