"""Light Tree off: the light bounced by many small lamps agrees with Cycles'.

30 point lamps (40 W, radius 0.1, scattered by a fixed seed, two of them inside the sphere) over
a Lambertian sphere and floor, black world, 2 bounces, Light Tree off in both engines (Cycles
then picks each lamp with probability 1/30; DACRT's global choice follows what each lamp gives
the points the camera sees, mixed with 20% of the uniform split).

A tester had found DACRT's bounced light 0.90x Cycles' here with the tree off (whole image
0.982x in red; 0.998x with the tree on) and suspected the light choice at bounce vertices. It
was DACRT's Clamp Indirect, left at Blender's default of 10 while Cycles' was turned off: with
1/30 selection probabilities a light sample near a lamp is large and clamped, with the tree far
fewer are. With the fair settings (both clamps off, as here) DACRT is 1.000x Cycles (64x48,
512 / 1024 spp: 1.2706 / 1.2703 red). At Clamp Indirect 10 in both, DACRT is 1.013x, and
0.9997x with its choice left uniform, as Cycles' is: the clamped means differ because the
choices differ (README, Clamping)."""
import math
import random

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

PASSES = ('Combined', 'Diffuse Direct', 'Diffuse Indirect', 'Diffuse Color')


def _scene():
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scenes.camera((0, -6, 3), (math.radians(64), 0, 0), lens=50)
    m = scenes.diffuse("D", (0.8, 0.5, 0.3))
    scenes.uv_sphere("S", 1.0, location=(0, 0, 1), materials=(m,))
    scenes.plane("F", size=10, materials=(m,))
    scenes.black_world()
    rnd = random.Random(1)
    for _ in range(30):
        p = (rnd.uniform(-4, 4), rnd.uniform(-3, 4), rnd.uniform(0.5, 3))
        scenes.light('POINT', 40.0, location=p, shadow_soft_size=0.1)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 48, 36, 100
    sc.view_settings.view_transform = 'Standard'
    c, d = sc.cycles, sc.dacrt
    c.device, c.use_denoising, c.use_adaptive_sampling = 'CPU', False, False
    c.samples, d.samples = 1024, 512
    c.max_bounces = c.diffuse_bounces = d.max_bounces = 2
    # the fair settings: both engines' clamps off (DACRT's own Clamp Indirect defaults to 10)
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    d.sample_clamp_direct = d.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.pixel_filter_type = d.filter_type = 'BOX'
    c.filter_width = d.filter_width = 1.0
    c.use_light_tree = d.use_light_tree = False
    for ob in bpy.data.objects:
        ob.shadow_terminator_geometry_offset = 0.0
    vl = sc.view_layers[0]
    vl.use_pass_diffuse_direct = vl.use_pass_diffuse_indirect = vl.use_pass_diffuse_color = True
    return sc


def test_tree_off_bounced_light_matches_cycles(tmp_path):
    """Combined within 0.6% of Cycles' and the bounced light (Diffuse Color x Indirect) within
    3% (the report's 0.90x was 10% off; measured 1.00x)."""
    sc = _scene()
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name

    def get(o, p):
        return np.stack([o[f"{name}.{p}.{ch}"] for ch in 'RGB'], -1).astype(np.float64)
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        px = {p: get(out[engine], p) for p in PASSES}
        means[engine] = {'Combined': px['Combined'].mean(axis=(0, 1)),
                         'Direct': (px['Diffuse Color'] * px['Diffuse Direct']).mean(axis=(0, 1)),
                         'Indirect': (px['Diffuse Color'] * px['Diffuse Indirect']).mean(axis=(0, 1))}
    c, d = means['CYCLES'], means['DACRT']
    ratio = {k: d[k][0] / c[k][0] for k in c}       # red: the brightest channel
    print({k: round(float(v), 4) for k, v in ratio.items()})
    assert c['Indirect'][0] > 0.1 * c['Combined'][0], "the scene must bounce a fair share of its light"
    assert ratio['Combined'] == pytest.approx(1.0, abs=0.006), ratio
    assert ratio['Direct'] == pytest.approx(1.0, abs=0.01), ratio
    assert ratio['Indirect'] == pytest.approx(1.0, abs=0.03), ratio
