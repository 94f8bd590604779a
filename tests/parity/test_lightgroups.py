"""Light Groups agree with Cycles: the Cornell box's area light in one group, an added point
light in another, a world seen through the box's open front in a third, and an emissive panel
in a fourth; each Combined_<group> pass's channel means within 1.5% of Cycles' (4 bounces, so
every group holds direct and bounced light)."""
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

GROUPS = ("key", "fill", "sky", "panel")


def test_light_groups_match_cycles(tmp_path):
    sc = rendering.small_cornell()
    vl = sc.view_layers[0]
    for name in GROUPS:
        vl.lightgroups.add(name=name)
    bpy.data.objects["CeilingLight"].lightgroup = "key"
    scenes.light('POINT', 40.0, (0.6, -0.6, 1.4), name="Fill").lightgroup = "fill"
    panel = scenes.plane("Panel", size=0.4, location=(-0.99, 0.2, 1.3),
                         materials=[scenes.emission("Panel", (0.3, 0.6, 1.0), 6.0)])
    panel.rotation_euler = (0.0, np.pi / 2, 0.0)             # on the left wall, facing +x
    panel.lightgroup = "panel"
    scenes.world((0.4, 0.5, 0.7), 1.0)
    sc.world.lightgroup = "sky"
    spec = SimpleNamespace(cycles_samples=256, dacrt_samples=256, bounces=4, clamp=(0.0, 0.0),
                           filter_type='BLACKMAN_HARRIS', filter_width=1.5)
    means = {}
    for engine, exr in rendering.render_layers(sc, spec, tmp_path).items():
        for g in GROUPS:
            means[engine, g] = np.array([exr[f"{vl.name}.Combined_{g}.{c}"].mean() for c in "RGB"], np.float64)
        means[engine, 'combined'] = np.array([exr[f"{vl.name}.Combined.{c}"].mean() for c in "RGB"], np.float64)
    for g in GROUPS:
        c, d = means['CYCLES', g], means['DACRT', g]
        assert c.min() > 0.005, (g, c)
        assert np.all(np.abs(d / c - 1) < 0.015), (g, d, c)
    # every emitter is in a group: the groups add up to Combined in both engines
    for engine in ('CYCLES', 'DACRT'):
        total = sum(means[engine, g] for g in GROUPS)
        assert np.allclose(total, means[engine, 'combined'], rtol=2e-3), (engine, total, means[engine, 'combined'])
