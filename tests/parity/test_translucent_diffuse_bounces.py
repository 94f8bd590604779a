"""A Translucent BSDF's bounce is no diffuse bounce in Cycles (a transmission one: against
Transmission and Total alone), against Cycles: three white translucent sheets over an emissive
floor render alike at Diffuse 0, 1 and 12 under Total 12 (0.504 in Cycles 5.0). DACRT had
counted each translucent bounce against Max Bounces (copied from Diffuse), so the floor's light
was cut after the first sheets: 0.0 at Diffuse 0 and 1."""
import bpy
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _sheets_over_emitter():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 8
    sc.render.resolution_percentage = 100
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    scenes.plane("Floor", size=200.0, materials=[scenes.emission("Floor", (1, 1, 1), 1.0)])
    mat, nt, out = scenes._material("Sheet")
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTranslucent').outputs[0], out.inputs['Surface'])
    for i in range(3):
        scenes.plane(f"Sheet{i}", size=200.0, location=(0, 0, 0.2 + 0.2 * i), materials=[mat])
    scenes.world((0.0, 0.0, 0.0))
    scenes.camera(location=(0.0, 0.0, 3.0), kind='ORTHO', ortho_scale=0.5)
    rendering.matched(sc, 64, bounces=4)
    return sc


@pytest.mark.parametrize('diffuse', [0, 1])
def test_translucent_bounces_do_not_use_up_diffuse_bounces_as_in_cycles(tmp_path, diffuse):
    sc = _sheets_over_emitter()
    c = sc.cycles
    c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 12, diffuse, diffuse, 12
    bpy.ops.dacrt.copy_cycles_settings()
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        means[engine] = float(rendering.render_combined(sc, tmp_path / f"{engine}.exr")[..., :3].mean())
    assert means['CYCLES'] > 0.3, means
    assert means['DACRT'] == pytest.approx(means['CYCLES'], rel=0.03), means
