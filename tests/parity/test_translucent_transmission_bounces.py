"""A Translucent BSDF's bounce counts against Transmission Max Bounces, as Cycles counts a
diffuse transmission (path_state_next: LABEL_TRANSMIT): the surface after the (n+1)-th such
bounce only emits where the limit is n. Glass passes keep the same count: a surface after n
transmissions is passed (refracted) while n <= the limit, so two clear panes before an emitter
are seen through at limit 1 (they had been black there, Cycles 2.0; and seen only from 2). A closed sphere of a 50% Mix of a green Translucent and a
red Diffuse under an area light, three bounces; the light that crosses its inside is cut there.
Before: DACRT went on whatever the limit (1.21x Cycles in green at 0 transmission bounces,
1.034x at 1); and with the limit 0 a path that had passed a transparent surface (no transmission
at all) stopped at its next surface as if past it."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(bounces, veil=False):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera(location=(0, -5, 0.5), rotation=(math.radians(84), 0, 0))
    mat, nt, mix, a, b = scenes.mix_shader_material("Leaf", 'ShaderNodeBsdfTranslucent', 'ShaderNodeBsdfDiffuse')
    a.inputs['Color'].default_value = (0.2, 0.9, 0.3, 1.0)
    b.inputs['Color'].default_value = (0.9, 0.2, 0.1, 1.0)
    scenes.uv_sphere(radius=1.0, segments=32, rings=16, materials=[mat])
    scenes.plane("Floor", size=10, location=(0, 0, -1), materials=[scenes.diffuse("Grey", (0.5, 0.5, 0.5))])
    if veil:            # a 50% Transparent veil before the camera: transparent passes, no transmission
        vm, _, _, _, _ = scenes.mix_shader_material("Veil", 'ShaderNodeBsdfTransparent', 'ShaderNodeBsdfDiffuse')
        scenes.plane("Veil", size=6, location=(0, -3, 0.5), materials=[vm]).rotation_euler = (math.radians(90), 0, 0)
    scenes.black_world()
    bpy.ops.object.light_add(type='AREA', location=(2, -2, 3), rotation=(math.radians(40), math.radians(30), 0))
    lamp = bpy.context.active_object.data
    lamp.energy, lamp.size = 300.0, 2.0
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 3
    sc.cycles.glossy_bounces = 0
    sc.cycles.transmission_bounces = sc.dacrt.transmission_max_bounces = bounces
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc



@pytest.mark.parametrize('bounces,veil', [(0, False), (1, False), (2, False), (0, True)])
def test_translucent_bounces_end_at_the_transmission_limit(bounces, veil):
    sc = _scene(bounces, veil)
    cycles, dacrt = rendering.assert_agrees(sc)
    assert cycles.mean() > 0.05


def _panes(bounces):
    """Two clear glass panes (IOR 1.0001) before an emitting backdrop, nothing else lit."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 24
    scenes.camera(location=(0, -4, 1.0), rotation=(math.radians(90), 0, 0))
    mat, nt, out = scenes._material("Glass")
    glass = nt.nodes.new('ShaderNodeBsdfGlass')
    glass.inputs['IOR'].default_value, glass.inputs['Roughness'].default_value = 1.0001, 0.0
    nt.links.new(glass.outputs[0], out.inputs['Surface'])
    for y in (-1.5, -1.0):
        scenes.plane(f"Pane {y}", size=3, location=(0, y, 1.0), materials=[mat]).rotation_euler = (math.radians(90), 0, 0)
    glow = scenes.emission("Glow", (1.0, 0.5, 0.2), 2.0)
    scenes.plane("Back", size=6, location=(0, 1.5, 1.0), materials=[glow]).rotation_euler = (math.radians(90), 0, 0)
    scenes.black_world()
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.transmission_bounces = sc.dacrt.transmission_max_bounces = bounces
    return sc


@pytest.mark.parametrize('bounces', [0, 1, 2])
def test_glass_panes_are_passed_while_the_transmissions_are_within_the_limit(bounces):
    sc = _panes(bounces)
    means = {engine: scenes.seeded_rgb(sc, engine, 1).mean(axis=(0, 1, 2)) for engine in ('CYCLES', 'DACRT')}
    assert (means['CYCLES'][0] > 1.9) == (bounces > 0) and (means['CYCLES'][0] < 1e-3) == (bounces == 0)
    np.testing.assert_allclose(means['DACRT'], means['CYCLES'], rtol=0.01, atol=1e-4)
