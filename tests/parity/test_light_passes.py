"""Light passes agree with Cycles (film/light_passes.h): a box with an emissive panel in view,
an area lamp, a sky seen through its open side and a block. Cycles files camera-seen emitters
under Emission and the world under Environment, vertex 0's light samples and what its BSDF rays
find under Diffuse Direct, the rest under Diffuse Indirect, both divided by Diffuse Color; with
transparent film the Environment pass still holds the sky. Each pass's channel means agree
within 2% (of the brightest channel) and its mean per-pixel difference is small against its
level."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

PASSES = ('Diffuse Direct', 'Diffuse Indirect', 'Diffuse Color', 'Emission', 'Environment')


def _scene(transparent):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 30
    sc.render.film_transparent = transparent
    scenes.camera(location=(0, -7, 2.2), rotation=(math.radians(80), 0, 0), kind='PERSP')
    white = scenes.diffuse("White", (0.75, 0.75, 0.75))
    scenes.plane(size=4, location=(0, 0, 0), materials=[white])
    back = scenes.plane(size=4, location=(0, 2, 2), materials=[scenes.diffuse("Back", (0.7, 0.5, 0.3))])
    back.rotation_euler = (math.radians(90), 0, 0)
    wall = scenes.plane(size=4, location=(-2, 0, 2), materials=[scenes.diffuse("Wall", (0.3, 0.6, 0.4))])
    wall.rotation_euler = (0, math.radians(90), 0)
    scenes.cube("Block", size=1.0, location=(0.6, 0.3, 0.5), materials=[white])
    panel = scenes.plane(size=0.6, location=(-1.2, 1.98, 2.6), materials=[scenes.emission("Panel", (1.0, 0.8, 0.6), 6.0)])
    panel.rotation_euler = (math.radians(90), 0, 0)
    light_and_passes(sc, 256)
    sc.view_layers[0].use_pass_emit = True
    return sc


def light_and_passes(sc, samples):
    """The box's area lamp and sky, the Diffuse and Environment passes on, both engines at
    `samples` spp, 3 bounces, no clamp or denoising (test_rough_diffuse_passes shares them)."""
    scenes.light('AREA', 120.0, location=(0.8, -0.5, 3.5), size=1.0)
    scenes.world((0.25, 0.35, 0.6), 1.0)
    vl = sc.view_layers[0]
    vl.use_pass_diffuse_direct = vl.use_pass_diffuse_indirect = vl.use_pass_diffuse_color = True
    vl.use_pass_environment = True
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 3
    sc.cycles.sample_clamp_indirect = sc.dacrt.sample_clamp_indirect = 0.0


def _blocks(a):
    """Means over 10 x 10-pixel blocks of an (30, 40, 3) image."""
    return a.reshape(3, 10, 4, 10, 3).mean(axis=(1, 3))


@pytest.mark.parametrize('transparent', [False, True])
def test_light_passes_match_cycles(transparent, tmp_path):
    """Emission, Environment and Diffuse Color, and the light itself (Diffuse Color x Direct,
    x Indirect): channel means within 2% of the pass's level, 10 x 10 blocks within 5% (10%
    for indirect light). The divided passes are compared where the colour is not small: their
    mean over all pixels follows the noise of the edge pixels' tiny colours."""
    sc = _scene(transparent)
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name

    def get(o, p):
        return np.stack([o[f"{name}.{p}.{ch}"] for ch in 'RGB'], -1).astype(np.float64)
    c = {p: get(out['CYCLES'], p) for p in PASSES}
    d = {p: get(out['DACRT'], p) for p in PASSES}
    for key in ('Direct', 'Indirect'):
        c[key] = c['Diffuse Color'] * c[f'Diffuse {key}']
        d[key] = d['Diffuse Color'] * d[f'Diffuse {key}']
    for p, block_tol in (('Emission', 0.05), ('Environment', 0.05), ('Diffuse Color', 0.05), ('Direct', 0.05),
                         ('Indirect', 0.10)):
        level = float(c[p].mean(axis=(0, 1)).max())
        assert level > 1e-2, (p, 'the scene must exercise every pass')
        assert np.allclose(d[p].mean(axis=(0, 1)), c[p].mean(axis=(0, 1)), atol=0.02 * level), \
            (p, d[p].mean(axis=(0, 1)), c[p].mean(axis=(0, 1)))
        assert np.abs(_blocks(d[p]) - _blocks(c[p])).max() < block_tol * level, p
    colored = (c['Diffuse Color'] > 0.2).all(axis=-1)
    assert colored.mean() > 0.5
    for p in ('Diffuse Direct', 'Diffuse Indirect'):
        assert d[p][colored].mean() == pytest.approx(c[p][colored].mean(), rel=0.03), p
