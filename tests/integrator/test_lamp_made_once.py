"""The lamp the export's float32 check makes of a light is the one the set-up takes
(lights/madelamp.py), only while the light holds exactly the values it was made from, and only
once: a light changed after the check (the export sets visibility, Max Bounces and light group
after it; recentring moves its matrix) gets a lamp of its new values."""
import numpy as np
import pytest

from addon.lights import make_lamp
from addon.lights.madelamp import checked_lamp, taken_lamp
from addon.scenedata import Light


def _light(kind='AREA'):
    m = np.eye(4)
    m[:3, 3] = (0.5, -0.25, 2.0)
    return Light(kind=kind, strength=np.array([10.0, 8.0, 6.0]), matrix=m, radius=0.1, spot_size=0.8,
                 angle=0.05, size_x=0.5, size_y=0.5, name='L')


def _counting():
    made = []

    def make(light):
        made.append(light)
        return make_lamp(light)
    return make, made


@pytest.mark.parametrize('kind', ['POINT', 'SPOT', 'SUN', 'AREA'])
def test_an_unchanged_light_takes_the_checked_lamp_once(kind):
    light = _light(kind)
    make, made = _counting()
    lamp = checked_lamp(light, make)
    assert lamp is not None and len(made) == 1
    assert taken_lamp(light, make) is lamp and len(made) == 1
    # a second taker (another view's set-up) makes its own, with the same record
    again = taken_lamp(light, make)
    assert again is not lamp and len(made) == 2
    assert again.record().tobytes() == lamp.record().tobytes()


def _set(light, what):
    if what == 'visible_camera':
        light.visible_camera = False
    elif what == 'max_bounces':
        light.max_bounces = 3
    elif what == 'lightgroup':
        light.lightgroup = 'key'
    elif what == 'matrix replaced':
        m = light.matrix.copy()
        m[0, 3] += 1.0
        light.matrix = m
    elif what == 'matrix written in place':
        light.matrix[2, 3] -= 0.5
    elif what == 'strength written in place':
        light.strength *= 2.0
    elif what == 'zero to minus zero':
        light.angle = 0.0             # (a float field compared by its bits, not by ==)
        return 'angle', -0.0
    return None


@pytest.mark.parametrize('what', ['visible_camera', 'max_bounces', 'lightgroup', 'matrix replaced',
                                  'matrix written in place', 'strength written in place', 'zero to minus zero'])
def test_a_light_changed_after_its_check_is_made_again(what):
    light = _light('AREA')
    then = _set(light, what) if what == 'zero to minus zero' else None
    make, made = _counting()
    lamp = checked_lamp(light, make)
    if then is None:
        _set(light, what)
    else:
        setattr(light, *then)
    got = taken_lamp(light, make)
    assert got is not lamp and len(made) == 2
    fresh = make_lamp(light)
    assert got.record().tobytes() == fresh.record().tobytes()
    assert (got.visible_camera, got.max_bounces, got.lightgroup) == \
        (fresh.visible_camera, fresh.max_bounces, fresh.lightgroup)


def test_a_light_beyond_float32_keeps_no_lamp():
    light = _light('POINT')
    light.strength = np.array([1e39, 1.0, 1.0])
    make, made = _counting()
    assert checked_lamp(light, make) is None
    assert light.made is None
    with np.errstate(over='ignore'):
        assert taken_lamp(light, make) is not None and len(made) == 2
