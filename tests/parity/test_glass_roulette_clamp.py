"""Cycles' default Clamp Indirect (10) behind glass, against Cycles: the white box of
test_glass_total_bounces lit by a 200 W point lamp 0.2 m under its ceiling (the ceiling's light
samples run far past the clamp), seen through the camera-only IOR-1 pane, Total 4. Cycles counts
the pass as a bounce, so its Russian roulette starts one vertex earlier behind the pane; the
roulette is unbiased but the clamp cuts the divided throughputs. DACRT rouletted by vertex index:
1.010-1.014x Cycles over 4 seeds (without the pane 0.998-1.004x; clamps off 0.995-1.003x with
it), now 0.9995-0.9998x."""
import bpy
import pytest

from tests.addon import scenes

from . import rendering
from .test_glass_total_bounces import _box_with_pane

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_clamp_indirect_behind_a_pane_matches_cycles(tmp_path):
    sc = _box_with_pane()
    bpy.data.objects.remove(bpy.data.objects['Panel'])
    scenes.light('POINT', 200.0, location=(0.5, 0.5, 1.8)).data.shadow_soft_size = 0.0
    c = sc.cycles
    c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 4, 4, 4, 12
    c.sample_clamp_indirect = 10.0
    bpy.ops.dacrt.copy_cycles_settings()
    assert sc.dacrt.sample_clamp_indirect == 10.0
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        means[engine] = float(rendering.render_combined(sc, tmp_path / f"{engine}.exr")[..., :3].mean())
    assert means['DACRT'] == pytest.approx(means['CYCLES'], rel=0.006), means
