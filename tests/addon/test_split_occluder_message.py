"""An object hidden from diffuse rays but casting shadows (or hidden from shadows only) splits
what a light's samples and the bounce rays toward the light see behind it, and MIS weighs the
two by how likely the light is chosen. Cycles chooses among lamps hidden from diffuse rays too,
which DACRT leaves out of its choice, so beside such a lamp the light behind the object differs:
fuzz seed 306 (a 413 W diffuse-hidden point lamp beside a diffuse-hidden half cylinder), Cycles
3.5% brighter, one 4x4 block 4-6x DACRT's, and nothing said; the reduced scene here 0.97x
Cycles' mean (tests/parity/test_split_occluders.py renders the unsaid cases against Cycles).
It is said, naming the object and the lamp, and not where the image cannot change: no hidden
lamp (or one of zero strength), or the object hidden from shadow rays too.

DACRT's messages at 1 sample, 32x24."""
import pytest

from tests.parity import rendering

from . import scenes

SAID = "hidden from diffuse rays but not from shadows"


def _scene(sc, hidden=True, diffuse=False, shadow=True, energy=5000):
    box = scenes.box_on_floor()
    box.visible_diffuse, box.visible_shadow = diffuse, shadow
    scenes.light('POINT', 200, location=(0.5, 0.3, 2.2), name='Key', shadow_soft_size=0.6)
    if hidden:
        lamp = scenes.light('POINT', energy, location=(-3, 2, 3), name='Hidden', shadow_soft_size=0.2)
        lamp.visible_diffuse = lamp.visible_camera = False
    scenes.black_world()
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    rendering.matched(sc, 1, bounces=0)


@pytest.mark.parametrize('split', ['diffuse_off', 'shadow_off'])
def test_said_naming_the_object_and_the_lamp(scene, said, split):
    _scene(scene, diffuse=split != 'diffuse_off', shadow=split != 'shadow_off')
    got = scenes.rendered_messages(said, SAID)
    assert len(got) == 1 and got[0].startswith("object(s) 'Box' hidden from diffuse rays"), got
    assert "('Hidden')" in got[0] and "'Key'" not in got[0], got


@pytest.mark.parametrize('case', ['no_hidden_lamp', 'unsplit', 'dark_hidden_lamp'])
def test_not_said_where_the_image_cannot_change(scene, said, case):
    """(A hidden lamp of zero strength, which Cycles drops too, is no choice of its.)"""
    _scene(scene, hidden=case != 'no_hidden_lamp', shadow=case != 'unsplit',
           energy=0.0 if case == 'dark_hidden_lamp' else 5000)
    assert not scenes.rendered_messages(said, SAID)
