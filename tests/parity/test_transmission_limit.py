"""Where Transmission Max Bounces stops a path, against Cycles: Cycles 5.0 still shades the
surface a path meets after its last allowed glass pass, so a floor seen through one pane of
glass is lit at Transmission 1 as at 12, and only at 0 does the pane hide it (its reflection
alone). DACRT's glass is a stand-in (unbent, its shadows let through: said), so the levels
differ; where the limit falls must not. DACRT had needed one bounce more: the floor behind
the pane was black at 1 too (image 0.042 where Cycles gives 0.307; 0.404 at 12)."""
import bpy
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _pane_over_floor():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    sc.render.resolution_percentage = 100
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    scenes.plane("Floor", size=10.0, materials=[scenes.diffuse("Floor", (0.8, 0.8, 0.8))])
    mat, nt, out = scenes._material("Glass")
    glass = nt.nodes.new('ShaderNodeBsdfGlass')
    glass.inputs['Roughness'].default_value = 0.0
    glass.inputs['IOR'].default_value = 1.45
    nt.links.new(glass.outputs[0], out.inputs['Surface'])
    scenes.plane("Pane", size=2.0, location=(0.0, 0.0, 0.5), materials=[mat])
    scenes.world((0.5, 0.5, 0.5))
    scenes.camera(location=(0.0, 0.0, 3.0), kind='ORTHO', ortho_scale=1.0)
    rendering.matched(sc, 16, bounces=4)
    sc.cycles.max_bounces, sc.cycles.diffuse_bounces, sc.cycles.glossy_bounces = 12, 4, 4
    return sc


def test_the_transmission_limit_falls_where_cycles_puts_it(tmp_path):
    sc = _pane_over_floor()
    means = {}
    for limit in (0, 1, 12):
        sc.cycles.transmission_bounces = limit
        bpy.ops.dacrt.copy_cycles_settings()
        assert sc.dacrt.transmission_max_bounces == limit
        for engine in ('CYCLES', 'DACRT'):
            sc.render.engine = engine
            img = rendering.render_combined(sc, tmp_path / f"{engine}-{limit}.exr")
            means[engine, limit] = float(img[..., :3].mean())
    for engine in ('CYCLES', 'DACRT'):
        lit = means[engine, 12]
        assert means[engine, 1] == pytest.approx(lit, rel=0.03), (engine, means)
        assert means[engine, 0] < 0.2 * lit, (engine, means)
