"""Lamps with Cast Shadow off that DACRT renders as Cycles does, unsaid
(tests/addon/test_shadowless_lamp_message.py): light samples light past the occluder, BSDF rays
toward the lamp stop at it, and MIS weighs the two by the light-selection pdf, so the image
agrees where both engines pick the lamp alike: alone (probability 1), or with Multiple
Importance off beside another lamp (light samples alone, weight 1). Per pixel and 4x4 block
(Welch tests, 4 seeds a side) and per channel (1%), a cube on a floor under a 3 m shadowless
area light (the unshadowed floor by the cube makes it show; beside a point light with MIS on
DACRT gives 1.01x Cycles' mean there, pixels by the cube 1.1x, which is said)."""
import math

import bpy
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(case):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 30
    scenes.camera(location=(5, -5, 4), rotation=(math.radians(58), 0, math.radians(45)))
    scenes.plane(size=20, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    scenes.cube('Box', size=1.2, location=(0, 0, 0.6), materials=[scenes.diffuse('box', (0.5, 0.6, 0.7))])
    lamp = scenes.light('AREA', 300, location=(0.5, 0.3, 2.0), name='Fill', size=3.0, use_shadow=False)
    lamp.data.cycles.use_multiple_importance_sampling = case != 'mis_off'
    if case == 'mis_off':
        scenes.light('POINT', 200, location=(-2, 1, 3), name='Key')
    scenes.black_world()
    rendering.matched(sc, 64, bounces=0)
    return sc


@pytest.mark.parametrize('case', ['alone', 'mis_off'])
def test_shadowless_area_light_matches_cycles(case, said):
    sc = _scene(case)
    rendering.assert_agrees(sc)
    assert not any("Cast Shadow off" in t for t in said), said
