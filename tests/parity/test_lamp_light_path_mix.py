"""A light's node tree mixing two Emissions by Light Path Is Camera Ray (or Is Shadow Ray), against
Cycles: Cycles evaluates a light's shader for the light it casts with path flag PATH_RAY_EMISSION
alone (light_sample_shader_eval), so both flags read 0 there and the lamp lights with the Mix's
first shader. DACRT had read the factor at its own value 0.5, reported ("light Mix Shader factor
not computed (value from 'Light Path' node)"): an area lamp's scene 1.50x Cycles on a block.
Where the lamp has a surface the camera may see, DACRT shows that first
shader there too, as Cycles does (nothing said)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(kind, flag):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera(location=(0, -6, 2.5), rotation=(math.radians(70), 0, 0))
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    lamp = scenes.light(kind, 300.0, location=(0.5, -1.0, 2.5), name="Lamp",
                        **({'size': 1.5} if kind == 'AREA' else {'shadow_soft_size': 0.0}))
    ld = lamp.data
    ld.use_nodes = True
    nt = ld.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')
    e2 = nt.nodes.new('ShaderNodeEmission')
    e2.inputs['Color'].default_value = (0.2, 0.4, 1.0, 1.0)
    e2.inputs['Strength'].default_value = 3.0
    mix = nt.nodes.new('ShaderNodeMixShader')
    lp = nt.nodes.new('ShaderNodeLightPath')
    nt.links.new(lp.outputs[flag], mix.inputs[0])
    nt.links.new(em.outputs[0], mix.inputs[1])
    nt.links.new(e2.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.world((0.02, 0.02, 0.02), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 128
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc


@pytest.mark.parametrize('kind,flag', [('AREA', 'Is Camera Ray'), ('POINT', 'Is Camera Ray'),
                                       ('SPOT', 'Is Shadow Ray')])
def test_lamp_mixed_by_ray_kind_lights_as_cycles(kind, flag, tmp_path, said):
    sc = _scene(kind, flag)
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'])
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    assert c.min() > 0.01, c
    # per channel: the factor at 0.5 had made blue ~1.6x Cycles' (the second shader is blue x 3)
    np.testing.assert_allclose(d, c, rtol=0.03)
    assert not any("approximated" in t and "Light Path" in t for t in said), said
    # (nothing differs where the camera sees the lamp either: test_lamp_camera_mix_unsaid.py)
    assert not any("Is Camera Ray / Is Shadow Ray" in t for t in said), said
