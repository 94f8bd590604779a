"""Glass passes count against Cycles' Light Paths > Total, against Cycles: a camera-only pane
of IOR-1 glass (Cycles refracts it straight, so both engines see the same floor) over the floor
of a white box lit by a ceiling panel. Cycles 5.0 gives the floor behind the pane at Total K
what it gives without the pane at K - 1 (K = 2: 0.3451 and 0.3449; K = 4: 0.4468, 0.4471 at
3). DACRT had counted the pass against Transmission alone and rendered the pane as absent,
1.19x Cycles at K = 2 (0.4105), 1.08x at 4; a Total copied from Cycles now takes it."""
import bpy
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

_WALLS = (((2, 0, 1), (0, 1.5708, 0)), ((-2, 0, 1), (0, 1.5708, 0)),
          ((0, 2, 1), (1.5708, 0, 0)), ((0, -2, 1), (1.5708, 0, 0)))


def _box_with_pane():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    sc.render.resolution_percentage = 100
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    white = scenes.diffuse("White", (0.8, 0.8, 0.8))
    scenes.plane("Floor", size=4.0, materials=[white])
    for i, (location, rotation) in enumerate(_WALLS):
        scenes.plane(f"Wall{i}", size=4.0, location=location, materials=[white]).rotation_euler = rotation
    scenes.plane("Ceiling", size=4.0, location=(0, 0, 2.0), materials=[white])
    scenes.plane("Panel", size=0.8, location=(0.5, 0.5, 1.99), materials=[scenes.emission("Panel", (1, 1, 1), 10.0)])
    mat, nt, out = scenes._material("Glass")
    glass = nt.nodes.new('ShaderNodeBsdfGlass')
    glass.inputs['Roughness'].default_value = 0.0
    glass.inputs['IOR'].default_value = 1.0
    nt.links.new(glass.outputs[0], out.inputs['Surface'])
    pane = scenes.plane("Pane", size=1.0, location=(0, 0, 1.0), materials=[mat])
    for ray in ('diffuse', 'glossy', 'transmission', 'shadow', 'volume_scatter'):
        setattr(pane, f'visible_{ray}', False)
    scenes.world((0.0, 0.0, 0.0))
    scenes.camera(location=(0.0, 0.0, 1.5), kind='ORTHO', ortho_scale=0.5)
    rendering.matched(sc, 256, bounces=4)
    return sc


@pytest.mark.parametrize('total', [2, 4])
def test_glass_passes_count_against_total_bounces_as_in_cycles(tmp_path, total):
    sc = _box_with_pane()
    c = sc.cycles
    c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = total, total, total, 12
    bpy.ops.dacrt.copy_cycles_settings()
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        means[engine] = float(rendering.render_combined(sc, tmp_path / f"{engine}.exr")[..., :3].mean())
    assert means['DACRT'] == pytest.approx(means['CYCLES'], rel=0.025), means


@pytest.mark.parametrize('lamp_limit', [0, 1])
def test_a_lamps_max_bounces_counts_the_glass_pass_as_in_cycles(tmp_path, lamp_limit):
    """The box lit by a point lamp instead, Total 4: Cycles counts the pass against the lamp's
    Max Bounces too, so at 0 the floor behind the pane is black (0.0) and at 1 it has its direct
    light alone (0.997, as the bare floor at 0). DACRT had lit it as without the pane: 0.997 and
    1.894."""
    sc = _box_with_pane()
    bpy.data.objects.remove(bpy.data.objects['Panel'])
    lamp = scenes.light('POINT', 200.0, location=(0.5, 0.5, 1.8))
    lamp.data.shadow_soft_size = 0.0
    lamp.data.cycles.max_bounces = lamp_limit
    c = sc.cycles
    c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 4, 4, 4, 12
    bpy.ops.dacrt.copy_cycles_settings()
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        means[engine] = float(rendering.render_combined(sc, tmp_path / f"{engine}.exr")[..., :3].mean())
    assert means['DACRT'] == pytest.approx(means['CYCLES'], rel=0.025, abs=1e-4), means
