"""A faint spot beside a far brighter area light whose Spread may or may not reach its pool
(fuzz seed 10, README "Many lights: the light tree"): the spot's light group agrees with
Cycles over the pool. Cycles splits each node of its light tree by the mean of the shares by the
children's largest and smallest importances, so the spot, which surely reaches the pool, gets
about half the light samples there even where the area light's largest importance is ~3000x
its own; DACRT had weighed the largest alone, a small share for the spot: unbiased, but at 64
spp 92% of the pool's pixels got no spot sample and the few that did weighed thousands of times
more (the pool's spot-group mean 1.17x Cycles' in that run; 0.027 against 0.159 in seed 10 at
4 x 2048 spp, where the spot's share was below 1e-3)."""
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def build():
    """A grey floor seen from above; a 200 W spot 3 m over it aiming down (cone 40 degrees, a
    pool of ~1.1 m radius) in light group 'spot'; a 1.2 m square area light of 150 kW (~3000x
    the spot's on-axis intensity) 3 m to the side, its Spread 106 degrees, tilted so the pool
    lies 45-85 degrees off its normal: its sphere may reach most of the pool, and nowhere
    surely."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 36
    scenes.plane("Floor", size=12.0, materials=[scenes.diffuse("Grey", (0.5, 0.5, 0.5))])
    scenes.camera(location=(0.0, 0.0, 6.0), lens=50.0)
    vl = sc.view_layers[0]
    vl.lightgroups.add(name="spot")
    spot = scenes.light('SPOT', 200.0, (0.0, 0.0, 3.0), name="Spot", spot_size=np.radians(40.0), spot_blend=0.1,
                        shadow_soft_size=0.0)
    spot.lightgroup = "spot"
    scenes.light('AREA', 150_000.0, (3.0, 0.0, 1.0), (0.0, np.radians(136.6), 0.0), name="Panel", size=1.2,
                 spread=np.radians(106.0))
    scenes.black_world(sc)
    rendering.fair_scene_settings(sc)
    return sc


def test_faint_spot_beside_a_bright_area_light_matches_cycles(tmp_path):
    sc = build()
    vl = sc.view_layers[0]
    spec = SimpleNamespace(cycles_samples=64, dacrt_samples=64, bounces=0, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    spot = {}
    for engine, exr in rendering.render_layers(sc, spec, tmp_path).items():
        spot[engine] = np.mean([exr[f"{vl.name}.Combined_spot.{c}"] for c in "RGB"], axis=0).astype(np.float64)
    c, d = spot['CYCLES'], spot['DACRT']
    pool = c > 0.3 * np.quantile(c, 0.99)
    assert 100 < pool.sum() < 0.9 * c.size
    ratio = d[pool].mean() / c[pool].mean()
    # a pool pixel with no spot sample at all (DACRT had left most of them so)
    unlit = (d[pool] == 0).mean()
    assert abs(ratio - 1.0) < 0.08 and unlit < 0.05, (ratio, unlit)
