"""A scene Cycles renders at Max Bounces (Total) 0 with a cut-out in it, against Cycles after
Copy Settings from Cycles (which sets Transmission Max Bounces to min(Total, Transmission) = 0).

Transmission Max Bounces counts glass passes only; at 0 it had also cut every path vertex of
a batch where any ray met a Transparent BSDF or cut-out (the pass counters exist from then
on, all 0, and 0 < 0 failed): a card mixing Diffuse and Transparent over a floor under a grey
world rendered the floor and the card's reflection black, 0.24x Cycles' image mean."""
import bpy
import numpy as np
import pytest
from mathutils import Vector

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _card_over_floor():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 48, 36, 100
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    scenes.plane("Floor", size=10.0, materials=[scenes.diffuse("Floor", (0.8, 0.8, 0.8))])
    card = scenes.mix_shader_material("Card", 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent', fac=0.5)[0]
    scenes.plane("Card", size=1.5, location=(1.0, 0.5, 1.0), materials=[card])
    scenes.world((0.5, 0.5, 0.5))
    cam = scenes.camera(location=(4.0, -6.0, 5.0))
    cam.rotation_euler = (Vector((0.0, 0.0, 0.5)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    rendering.matched(sc, 32, bounces=0)
    bpy.ops.dacrt.copy_cycles_settings()
    return sc


def test_cutout_at_total_bounces_zero_agrees_with_cycles(tmp_path, said):
    sc = _card_over_floor()
    assert sc.dacrt.transmission_max_bounces == 0
    img = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        img[engine] = rendering.render_combined(sc, tmp_path / f"{engine}.exr")[..., :3].astype(np.float64)
    c, d = img['CYCLES'], img['DACRT']
    np.testing.assert_allclose(d.mean(), c.mean(), rtol=0.01)
    # the floor's bottom rows, away from the card and its shadow: the world's light, ~0.8 x 0.5
    np.testing.assert_allclose(d[:6].mean(), c[:6].mean(), rtol=0.01)
    assert c[:6].mean() == pytest.approx(0.4, rel=0.02)
    assert not [t for t in said if 'approximated' in t], said
