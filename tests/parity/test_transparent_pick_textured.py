"""Behind a sheet of Alpha below the Pass Alpha Threshold whose colour varies over it (a
Checker, an image, a colour attribute), the share of camera paths that pass it agrees with
Cycles. Cycles picks between the transparent closure and the others by their sample weights,
the diffuse closure's its colour at the point; the pick had weighed the material's constant
factor (the Alpha times 1, for these dark colours 3-20x the texel's weight), so too many
paths stopped: the Normal pass (written by the paths that pass, its Z their share) 0.55 where
Cycles gives 0.90 (Checker), 0.35 against 0.95 (attribute); fuzz 9386, a sphere of Alpha 0.49
and a Checker base, had its Normal pass 0.97x Cycles' on channel means."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.normalpass import passing_share

pytestmark = pytest.mark.usefixtures('parity_addon')


def _passing_share(tmp_path, engine, kind):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 16, 12
    cam = scenes.camera(location=(0, 0, 5))
    cam.data.type = 'ORTHO'
    cam.data.ortho_scale = 2.0
    mat = scenes.principled('P', (0.2, 0.2, 0.2))
    nt = mat.node_tree
    p = nt.nodes['Principled BSDF']
    p.inputs['Alpha'].default_value = 0.45
    p.inputs['Specular IOR Level'].default_value = 0.0
    if kind == 'checker':
        tex = nt.nodes.new('ShaderNodeTexChecker')
        tex.inputs['Scale'].default_value = 7.0
        tex.inputs['Color1'].default_value = (0.05, 0.1, 0.05, 1.0)
        tex.inputs['Color2'].default_value = (0.3, 0.2, 0.1, 1.0)
        colour = tex.outputs['Color']
    elif kind == 'image':
        px = np.zeros((4, 4, 4), np.float32)
        px[..., 0], px[..., 1], px[..., 2], px[..., 3] = 0.1, 0.15, 0.05, 1.0
        px[::2, ::2, :3] = 0.02
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = scenes.float_image('Img', px)
        colour = tex.outputs['Color']
    else:
        colour = scenes.colour_attribute(nt, 'Col')
    nt.links.new(colour, p.inputs['Base Color'])
    sheet = scenes.plane('Sheet', size=4, materials=[mat])
    if kind == 'attribute':
        attr = sheet.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
        for i, c in enumerate([(0.02, 0.05, 0.1, 1.0), (0.3, 0.1, 0.05, 1.0), (0.05, 0.05, 0.05, 1.0),
                               (0.1, 0.2, 0.1, 1.0)]):
            attr.data[i].color = c
    return passing_share(tmp_path, sc, engine)


@pytest.mark.parametrize('kind', ['checker', 'image', 'attribute'])
def test_share_of_paths_passing_a_textured_sheet_matches_cycles(tmp_path, kind):
    cycles = _passing_share(tmp_path, 'CYCLES', kind)
    dacrt = _passing_share(tmp_path, 'DACRT', kind)
    # (24576 paths: the share's noise is about 0.001-0.003)
    assert abs(dacrt - cycles) < 0.008, (cycles, dacrt)
