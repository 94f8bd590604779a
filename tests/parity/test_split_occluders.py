"""An object hidden from diffuse rays but casting shadows (a split occluder): behind it a light's
samples are shadowed and the bounce rays toward the light pass, and MIS weighs the two by the
light-selection pdf, so the image agrees where both engines pick the light alike. A lamp hidden
from diffuse rays lights nothing there, but Cycles keeps it in its light choice, where it takes
its share of the picks and so lowers the other light's (fuzz seed 306); DACRT had left it out,
0.97x Cycles' mean (z -24, 4 seeds x 64 spp), and keeps it now (lights/choiceonly.py): a point
lamp hidden from camera and diffuse rays, one hidden from every ray kind (the export had
skipped it), two hidden lamps, a hidden area light, with a grey world lighting the scene too.
Alone, or with the object hidden from shadow rays too, it matched before. Per pixel and 4x4
block (Welch tests, 4 seeds a side) and per channel (1%)."""
import bpy
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _hide(lamp, every_ray=False):
    lamp.visible_diffuse = lamp.visible_camera = False
    if every_ray:
        lamp.visible_glossy = lamp.visible_transmission = lamp.visible_volume_scatter = False


def _scene(case):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    box = scenes.box_on_floor()
    box.visible_diffuse = False
    box.visible_shadow = case != 'unsplit'
    scenes.light('POINT', 200, location=(0.5, 0.3, 2.2), name='Key', shadow_soft_size=0.6)
    if case == 'hidden_area':
        _hide(scenes.light('AREA', 5000, location=(-3, 2, 3), rotation=(0.6, -0.6, 0), name='Hidden', size=0.5))
    elif case != 'alone':
        _hide(scenes.light('POINT', 5000, location=(-3, 2, 3), name='Hidden', shadow_soft_size=0.2),
              every_ray=case == 'hidden_from_every_ray')
    if case == 'two_hidden':
        _hide(scenes.light('POINT', 3000, location=(3, 3, 2), name='Hidden2', shadow_soft_size=0.3))
    if case == 'hidden_world_lit':
        scenes.world((0.2, 0.25, 0.3), 1.0)
    else:
        scenes.black_world()
    rendering.matched(sc, 64, bounces=0)
    return sc


@pytest.mark.parametrize('case', ['alone', 'unsplit', 'hidden', 'hidden_from_every_ray', 'two_hidden',
                                  'hidden_area', 'hidden_world_lit'])
def test_split_occluder_matches_cycles(case, said):
    sc = _scene(case)
    rendering.assert_agrees(sc)
    assert not any("hidden from diffuse rays but not from shadows" in t for t in said), said
