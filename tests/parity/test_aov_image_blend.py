"""An AOV Output fed by an 8-bit sRGB image (Linear interpolation, on the UV map) writes what
Cycles writes: Cycles blends the image's stored bytes and decodes the blend, so the AOV is the
sRGB decode of the blended bytes. The export had baked the decoded (linear) texels and blended
those, 1.17-1.29x Cycles' mean AOV per channel over this cube (1.05-1.07x in the fuzz scene),
nothing said (session-74 fuzz seed 3007);
'Closest' (one texel read) and a Non-Color image were right. Now the lookup decodes after the
blend, as the Diffuse colour's does: within 0.1%."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(tmp_path, interpolation):
    """A cube of a Diffuse BSDF whose AOV 'a' is an 8 x 8 random 8-bit PNG (4-pixel blocks) on
    its UV map, seen at 48 x 36 with a Box filter of 1 pixel, 16 samples."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 36
    mat = scenes.diffuse('M', (0.5, 0.5, 0.5))
    nt = mat.node_tree
    px = np.repeat(np.repeat((np.random.default_rng(5).random((8, 8, 3)) * 255).astype(np.uint8), 4, 0), 4, 1)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.load(scenes.write_image(tmp_path / 'blocks.png', px))
    tex.interpolation = interpolation
    out = nt.nodes.new('ShaderNodeOutputAOV')
    out.aov_name = 'a'
    nt.links.new(tex.outputs['Color'], out.inputs['Color'])
    scenes.cube('Cube', size=1.8, materials=(mat,)).rotation_euler = (0, 0, 0.6)
    scenes.camera(location=(0, -6.5, 1.3), rotation=(math.radians(80), 0, 0), lens=40)
    scenes.world((0.2, 0.2, 0.2))
    vl = sc.view_layers[0]
    aov = vl.aovs.add()
    aov.name, aov.type = 'a', 'COLOR'
    vl.use_pass_object_index = True
    bpy.data.objects['Cube'].pass_index = 1
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    return sc


@pytest.mark.parametrize('interpolation', ['Linear', 'Closest'])
def test_aov_of_an_srgb_image_decodes_after_the_blend_as_cycles(tmp_path, said, interpolation):
    got = scenes.render_engines(_scene(tmp_path, interpolation), tmp_path)
    cube = np.rint(got['CYCLES']['ViewLayer.Object Index.X']) == 1
    assert cube.sum() > 150
    means = {e: np.array([ch[f'ViewLayer.a.{c}'][cube].mean() for c in 'RGB']) for e, ch in got.items()}
    assert np.allclose(means['DACRT'], means['CYCLES'], rtol=0.005), means
    assert not any("AOV 'a'" in s for s in said), said
