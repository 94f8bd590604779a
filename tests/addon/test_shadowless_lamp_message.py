"""A lamp with Cast Shadow off that BSDF rays meet (Multiple Importance on, a size, radius or
angle) is lit past occluders by its light samples while BSDF rays toward it stop there, and MIS
weighs the two by the light-selection pdf. Beside another light source DACRT picks it with other
probabilities than Cycles, so near an occluder its light differs (a shadowless area light beside
a point light over a cube: 1.01x Cycles' mean, pixels by the cube 1.1x; fuzz seed 305, a wide
shadowless sun under a Hosek sky, 4x4 blocks 1.08x). That was silent; it is said, naming the
lamp, where it can change the image, and not where it cannot: the lamp alone (both pick it
with probability 1), Cast Shadow on, Multiple Importance off, or a point light of radius 0, which
no BSDF ray meets (tests/parity/test_shadowless_lamps.py renders the unsaid cases against Cycles).

DACRT's messages at 1 sample, 32x24."""
import math

import bpy
import pytest

from tests.parity import rendering

from . import scenes

SAID = "have Cast Shadow off"


def _scene(sc, shadow=False, mis=True, other='point', radius=None):
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(55), 0, 0))
    scenes.plane(size=12, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    scenes.cube('Box', size=1.2, location=(0, 0, 0.6), materials=[scenes.diffuse('box', (0.5, 0.6, 0.7))])
    if radius is None:
        lamp = scenes.light('AREA', 300, location=(0.5, 0.3, 2.0), name='Fill', size=3.0, use_shadow=shadow)
    else:
        lamp = scenes.light('POINT', 300, location=(0.5, 0.3, 2.2), name='Fill', shadow_soft_size=radius,
                            use_shadow=shadow)
    lamp.data.cycles.use_multiple_importance_sampling = mis
    scenes.black_world()
    if other == 'point':
        scenes.light('POINT', 200, location=(-2, 1, 3), name='Key')
    elif other == 'sun':
        scenes.light('SUN', 2.0, rotation=(0.4, 0.2, 0), name='Key', angle=0.2)
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    rendering.matched(sc, 1, bounces=0)


def _said(sc, said):
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if SAID in t]


@pytest.mark.parametrize('other', ['point', 'sun'])
def test_said_naming_the_lamp_beside_another_light(scene, said, other):
    _scene(scene, other=other)
    got = _said(scene, said)
    assert len(got) == 1 and got[0].startswith("light(s) 'Fill' have Cast Shadow off"), got
    assert "'Key'" not in got[0]


def test_said_of_a_point_light_with_a_radius(scene, said):
    _scene(scene, radius=0.5)
    assert len(_said(scene, said)) == 1


@pytest.mark.parametrize('case', ['alone', 'shadow_on', 'mis_off', 'radius_0'])
def test_not_said_where_the_image_cannot_change(scene, said, case):
    _scene(scene, shadow=case == 'shadow_on', mis=case != 'mis_off', other=None if case == 'alone' else 'point',
           radius=0.0 if case == 'radius_0' else None)
    assert not _said(scene, said)


def test_said_beside_a_light_that_lights_nothing_here(scene, said):
    """A lamp hidden from diffuse rays lights nothing DACRT renders here, but both engines keep it
    among the lights they pick from (lights/choiceonly.py), which moves the MIS weights of the
    shadowless lamp by choices that differ (fuzz 1459: a wide shadowless sun beside such an area
    light, one object's pixels 1.3-1.9x Cycles, unsaid while DACRT left it out). Said, naming the
    shadowless lamp, whether the camera sees the hidden one or not; a lamp of zero strength,
    which Cycles drops too, changes nothing and is not counted."""
    _scene(scene, other=None)
    hidden = scenes.light('AREA', 200, location=(-2, 1, 3), name='Hidden', size=0.5)
    hidden.visible_diffuse = hidden.visible_camera = False
    for camera in (False, True):
        hidden.visible_camera = camera
        got = _said(scene, said)
        assert len(got) == 1 and got[0].startswith("light(s) 'Fill' have Cast Shadow off"), got
    hidden.data.energy = 0.0
    assert not _said(scene, said)


def test_instances_of_one_lamp_named_once(scene, said):
    """Two collection instances of the shadowless lamp (the fuzzer's seed 523 had said
    "'L0', 'L0'")."""
    _scene(scene)
    lamp = bpy.data.objects['Fill']
    coll = bpy.data.collections.new('Lamps')
    scene.collection.objects.unlink(lamp)
    coll.objects.link(lamp)
    for k in range(2):
        e = bpy.data.objects.new(f'Inst{k}', None)
        e.instance_type, e.instance_collection = 'COLLECTION', coll
        e.location = (k - 0.5, 0.0, 0.0)
        scene.collection.objects.link(e)
    got = _said(scene, said)
    assert len(got) == 1 and got[0].startswith("light(s) 'Fill' have Cast Shadow off"), got
