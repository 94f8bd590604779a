"""A smooth-shaded Translucent BSDF lit from behind agrees with Cycles. Cycles gives the
Translucent closure maybe_ensure_valid_specular_reflection of its normal, a smooth one too
where the view's mirror reflection dips below the face (near a coarse mesh's edges), and its
light samples the bump shadowing term where that normal differs from the smooth one, at the
surfaces paths pass (mixed with a Transparent BSDF) as at those they stop at. The
transmission's normal had been raised only under a bump or normal map: a smooth-shaded cube
0.956x Cycles' mean, its edges 0.6-0.8x; 0.962x mixed 0.4 with a Transparent BSDF."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering as fair

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('clear', [0.0, 0.4])
def test_smooth_translucent_cube_lit_from_behind_matches_cycles(tmp_path, clear):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 30
    scenes.camera(location=(0, -6, 1), rotation=(1.4, 0, 0))
    mat = bpy.data.materials.new('T')
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    bsdf = nt.nodes.new('ShaderNodeBsdfTranslucent')
    bsdf.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    if clear:
        mix = nt.nodes.new('ShaderNodeMixShader')
        mix.inputs[0].default_value = clear
        nt.links.new(bsdf.outputs[0], mix.inputs[1])
        nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0], mix.inputs[2])
        bsdf = mix
    nt.links.new(bsdf.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 1), rotation=(0.3, 0.2, 0.5))
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(mat)
    scenes.light('SUN', 3.0, rotation=(-1.2, 0.0, 0.3))
    scenes.world((0.0, 0.0, 0.0), 1.0)
    means = fair.engine_means(sc, tmp_path, 'cube', samples=128, bounces=2)
    ratio = means['DACRT'] / means['CYCLES']
    # (1200 pixels at 128 samples: the mean's noise is about 0.3%)
    assert np.all(np.abs(ratio - 1.0) < 0.02), (means, ratio)
