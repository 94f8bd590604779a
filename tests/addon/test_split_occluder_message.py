"""An object hidden from diffuse rays but casting shadows (or hidden from shadows only) splits
what a light's samples and the bounce rays toward the light see behind it, and MIS weighs the
two by how likely the light is chosen. A lamp hidden from diffuse rays lights nothing there but
takes its share of that choice in Cycles: fuzz seed 306 (a 413 W diffuse-hidden point lamp
beside a diffuse-hidden half cylinder), Cycles 3.5% brighter, one 4x4 block 4-6x DACRT's, while
DACRT left the lamp out of its choice (said from session 76 on). DACRT keeps it too now
(lights/choiceonly.py; tests/parity/test_split_occluders.py renders those cases against
Cycles), and its light tree weighs it among lamps as Cycles' does, so beside such a lamp in the
tree and lamps only nothing is said any more. Outside the tree (a hidden sun, or Light Tree off),
or in it beside a sun BSDF rays meet or a light-sampled world (the tree's share against those is
DACRT's reweighting: a 1.5 rad sun, 0.986x Cycles' mean beside one hidden lamp, 0.997x beside
two), DACRT's share for it is its own: said, naming the object and the lamp; not where the image
cannot change (no hidden lamp, or one of zero strength, or the object hidden from shadow rays too).

DACRT's messages at 1 sample, 32x24."""
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes

SAID = "hidden from diffuse rays but not from shadows"


def _scene(sc, hidden='sun', diffuse=False, shadow=True, energy=5000, tree=True, key='point', two=False,
           world=False):
    box = scenes.box_on_floor()
    box.visible_diffuse, box.visible_shadow = diffuse, shadow
    if key == 'sun':        # a wide sun: BSDF rays meet it
        scenes.light('SUN', 3, rotation=(0.5, 0.3, 0), name='Key', angle=0.3)
    else:
        scenes.light('POINT', 200, location=(0.5, 0.3, 2.2), name='Key', shadow_soft_size=0.6)
    if hidden:
        lamps = [scenes.light('SUN', energy / 1000, rotation=(0.4, -0.5, 0), name='Hidden', angle=0.1)
                 if hidden == 'sun' else
                 scenes.light('POINT', energy, location=(-3, 2, 3), name='Hidden', shadow_soft_size=0.2)]
        if two:
            lamps.append(scenes.light('POINT', 3000, location=(3, 3, 2), name='Hidden2', shadow_soft_size=0.3))
        for lamp in lamps:
            lamp.visible_diffuse = lamp.visible_camera = False
    if world:               # a map the light choice samples (a uniform world is BSDF rays' alone)
        sky = np.ones((4, 8, 4), np.float32)
        sky[2:, :, :3] = 0.3
        scenes.environment_world(scenes.float_image('Sky', sky))
    else:
        scenes.black_world()
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    rendering.matched(sc, 1, bounces=0)
    sc.cycles.use_light_tree = sc.dacrt.use_light_tree = tree


@pytest.mark.parametrize('split', ['diffuse_off', 'shadow_off'])
def test_said_beside_a_hidden_sun_naming_the_object_and_the_lamp(scene, said, split):
    _scene(scene, diffuse=split != 'diffuse_off', shadow=split != 'shadow_off')
    got = scenes.rendered_messages(said, SAID)
    assert len(got) == 1 and got[0].startswith("object(s) 'Box' hidden from diffuse rays"), got
    assert "'Hidden')" in got[0] and "'Key'" not in got[0], got


def test_said_beside_a_hidden_lamp_with_the_light_tree_off(scene, said):
    _scene(scene, hidden='point', tree=False)
    got = scenes.rendered_messages(said, SAID)
    assert len(got) == 1 and "Light Tree off: 'Hidden')" in got[0], got


@pytest.mark.parametrize('two', [False, True], ids=['one_hidden_lamp', 'two_hidden_lamps'])
@pytest.mark.parametrize('beside', ['sun', 'world'])
def test_said_for_hidden_lamps_of_the_tree_beside_a_sun_or_the_world(scene, said, beside, two):
    """The tree's share against a sun BSDF rays meet, or the world, is DACRT's split
    (LightSet.reweight), which gives lamps that light nothing only its uniform part whatever
    their power: said, one hidden point lamp (no tree: a group of its own, the same share) or
    two (a tree) alike. (Had been said only for the one.)"""
    _scene(scene, hidden='point', key=beside if beside == 'sun' else 'point', world=beside == 'world', two=two)
    got = scenes.rendered_messages(said, SAID)
    assert len(got) == 1 and "beside a sun or the world" in got[0], got
    assert ("'Hidden', 'Hidden2')" if two else "'Hidden')") in got[0] and "'Key'" not in got[0], got


@pytest.mark.parametrize('case', ['hidden_lamp_in_the_tree', 'two_hidden_lamps_in_the_tree', 'no_hidden_lamp',
                                  'unsplit', 'dark_hidden_lamp', 'unsplit_beside_a_sun'])
def test_not_said_where_the_image_is_right(scene, said, case):
    """(A hidden lamp of zero strength, which Cycles drops too, is no choice of its. Hidden
    point lamps in the light tree beside lamps only: seed 306's case, said until DACRT kept them
    in its choice.)"""
    _scene(scene, hidden=False if case == 'no_hidden_lamp' else 'point' if 'in_the_tree' in case or 'sun' in case
           else 'sun', shadow=not case.startswith('unsplit'), energy=0.0 if case == 'dark_hidden_lamp' else 5000,
           two=case.startswith('two'), key='sun' if case == 'unsplit_beside_a_sun' else 'point')
    assert not scenes.rendered_messages(said, SAID)
