"""The Diffuse passes of a surface whose glossy closures DACRT renders as diffuse (a
Principled's specular layer, metal, coat; Glossy BSDFs) hold those closures' colour and light,
where Cycles writes them to its Glossy passes: said for the view layer, naming the surfaces
(export/settings.py glossy_in_diffuse_passes). The material message had said the layer was
rendered as diffuse but not that Diffuse Color follows it: a Principled floor's Diffuse Color
1.16x Cycles' without a word (fuzz seed 219, session 74). Against Cycles on a plane that fills
the view, at 4 spp (the pass is the first surface's colour: no noise on a flat plane)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

_SAID = "the glossy layers and BSDFs rendered as diffuse here"


def _plane(surface, diffuse_color=True):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 8, 6
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.use_denoising = False
    mat, nt, out = scenes._material('M')
    node = nt.nodes.new('ShaderNodeBsdfPrincipled' if surface == 'principled' else 'ShaderNodeBsdfDiffuse')
    node.inputs['Base Color' if surface == 'principled' else 'Color'].default_value = (0.6, 0.3, 0.2, 1.0)
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    scenes.plane("Floor", size=8.0, materials=[mat])
    scenes.camera(location=(0, 0, 3))
    scenes.world((0.5, 0.5, 0.5))
    sc.view_layers[0].use_pass_diffuse_color = diffuse_color
    return sc


@pytest.mark.parametrize('surface', ['principled', 'diffuse'])
def test_diffuse_color_holding_a_glossy_layer_is_said(surface, tmp_path, said):
    sc = _plane(surface)
    layer = sc.view_layers[0].name
    colour = {e: np.array([exr[f"{layer}.Diffuse Color.{c}"].mean() for c in 'RGB'])
              for e, exr in scenes.render_engines(sc, tmp_path).items()}
    ratio = colour['DACRT'] / colour['CYCLES']
    named = [t for t in said if _SAID in t]
    if surface == 'principled':
        # (the default specular layer's albedo, ~0.07, added here; Cycles dims the base by it)
        assert (ratio > 1.03).all(), ratio
        assert len(named) == 1 and "'M'" in named[0] and 'Diffuse Color' in named[0], said
    else:
        np.testing.assert_allclose(ratio, 1.0, rtol=0.01)
        assert not named, said


def test_not_said_without_the_diffuse_passes(said):
    sc = _plane('principled', diffuse_color=False)
    sc.render.engine = 'DACRT'
    bpy.ops.render.render()
    assert not [t for t in said if _SAID in t], said
    assert [t for t in said if "Principled specular layer as diffuse" in t], said
