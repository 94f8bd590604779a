"""The Sheen BSDF's velvet (Ashikhmin) in the passes. Cycles' velvet is a glossy closure whose
bsdf_albedo is its weight, the colour: Glossy Color holds it, Diffuse Color 0, and, rough
(film/denoising_passes.h), Denoising Albedo holds it too. DACRT has no Glossy passes: the
velvet's light goes to the Diffuse passes, with its colour (Cycles' Glossy Color) as Diffuse
Color and Denoising Albedo, and the message says so. Both had been the view-averaged albedo
(0.17 x the colour at roughness 0.5), a Denoising Albedo 5x too dark for a denoiser."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

COLOR = (0.9, 0.6, 0.3)


def _velvet(name):
    mat, nt, out = scenes._material(name)
    node = nt.nodes.new('ShaderNodeBsdfSheen')
    node.distribution = 'ASHIKHMIN'
    node.inputs['Color'].default_value = (*COLOR, 1.0)
    node.inputs['Roughness'].default_value = 0.5
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 2.0), rotation=(math.radians(75), 0, 0), kind='PERSP')
    scenes.plane(size=6, location=(0, 0, 0), materials=[_velvet("Velvet")])
    back = scenes.plane(size=6, location=(0, 3, 3), materials=[scenes.diffuse("Back", (0.5, 0.5, 0.5))])
    back.rotation_euler = (math.radians(90), 0, 0)
    scenes.light('AREA', 150.0, location=(0.0, 1.0, 3.0), size=1.0)
    scenes.world((0.2, 0.3, 0.5), 1.0)
    vl = sc.view_layers[0]
    vl.use_pass_diffuse_direct = vl.use_pass_diffuse_indirect = vl.use_pass_diffuse_color = True
    vl.use_pass_glossy_color = vl.use_pass_environment = True
    vl.cycles.denoising_store_passes = True
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    return sc


def test_velvet_passes_follow_cycles(tmp_path, said):
    """On the velvet floor: DACRT's Diffuse Color is Cycles' Glossy Color (the colour), Cycles'
    Diffuse Color is 0; Denoising Albedo is Cycles' (within 1 %); DACRT's Combined is still
    Diffuse Color x (Direct + Indirect); the Sheen message names the Glossy passes."""
    sc = _scene()
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    c, d = out['CYCLES'], out['DACRT']

    def get(o, p):
        return np.stack([o[f"{name}.{p}.{ch}"] for ch in 'RGB'], -1).astype(np.float64)
    floor = (slice(0, 8), slice(4, 28))               # (row 0 at the bottom) velvet only
    want = np.array(COLOR)
    assert np.allclose(get(c, 'Glossy Color')[floor].mean(axis=(0, 1)), want, rtol=0.01)
    assert np.abs(get(c, 'Diffuse Color')[floor]).max() < 1e-6
    assert np.allclose(get(d, 'Diffuse Color')[floor].mean(axis=(0, 1)), want, rtol=0.01)
    assert np.allclose(get(d, 'Denoising Albedo')[floor].mean(axis=(0, 1)),
                       get(c, 'Denoising Albedo')[floor].mean(axis=(0, 1)), rtol=0.01)
    light = get(d, 'Diffuse Direct') + get(d, 'Diffuse Indirect')
    assert light[floor].mean() > 0.01
    assert np.allclose(get(d, 'Diffuse Color') * light + get(d, 'Environment'), get(d, 'Combined'),
                       rtol=1e-3, atol=1e-4)
    text = ' '.join(said)
    assert "Sheen BSDF as diffuse" in text and "Cycles: the Glossy passes" in text, said
