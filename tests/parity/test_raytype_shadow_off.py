"""Light Path ray-type mixes on a material whose Settings > Transparent Shadows is off: Cycles
stops shadow rays at such a surface as at an opaque one (no SD_HAS_TRANSPARENT_SHADOW), whatever
side of the mix the shadow ray would see. A plate hidden from shadow rays (Mix(Diffuse,
Transparent, Is Shadow Ray)) then casts its full shadow (Cycles 0.0, DACRT had 0.54: no shadow),
and so does a sphere seen by the camera only (Mix(Transparent, Diffuse, Is Camera Ray))."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

CASES = {   # Light Path output, first shader (factor 0), second (factor 1)
    'no_shadow_plate': ('Is Shadow Ray', 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent'),
    'camera_only_plate': ('Is Camera Ray', 'ShaderNodeBsdfTransparent', 'ShaderNodeBsdfDiffuse'),
}


@pytest.mark.parametrize('case', sorted(CASES))
def test_ray_type_mix_with_transparent_shadows_off_casts_shadows(case, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 32
    output, first, second = CASES[case]
    mat, nt, mix, a, b = scenes.mix_shader_material("Plate", first, second)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
    mat.use_transparent_shadow = False
    scenes.plane("Floor", size=4, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    # a plate 1 m above the floor at x 0.5..1.5; the sun (light towards -x, 45 degrees down)
    # casts its shadow at x -0.5..0.5
    scenes.mesh("Plate", [(0.5, -0.5, 1), (1.5, -0.5, 1), (1.5, 0.5, 1), (0.5, 0.5, 1)], [(0, 1, 2, 3)],
                materials=[mat])
    scenes.light('SUN', 3.0, rotation=(0, math.radians(45), 0))
    scenes.world((0, 0, 0), 0.0)
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    layer = sc.view_layers[0].name
    shadow, open_floor = {}, {}
    for engine, exr in scenes.render_engines(sc, tmp_path).items():
        px = np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1)
        # ortho 4 m over 32 px: the shadow is pixels 12-19 in x and y; open floor at x < 8
        shadow[engine], open_floor[engine] = px[13:19, 13:19].mean(), px[13:19, 2:9].mean()
    assert shadow['CYCLES'] < 0.01 and open_floor['CYCLES'] > 0.3
    assert shadow['DACRT'] < 0.01
    np.testing.assert_allclose(open_floor['DACRT'], open_floor['CYCLES'], rtol=0.01)
