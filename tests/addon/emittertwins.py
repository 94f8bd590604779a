"""The scene the coincident and overlapping emitter tests share: a 1 m emissive plane facing down
over a floor, seen from above, no world light, no bounces, and a twin, a second object sharing
the plane's mesh where a duplicated import, a Mirror applied twice or a copy turned in place puts
it."""
import math

import bpy

from tests.parity import rendering

from . import scenes


def lamp_scene(sc, height, samples):
    """The floor, the camera and the emissive plane 'Lamp' at `height` (returned); Cycles' and
    DACRT's settings matched (tests/parity/rendering.py) at `samples`, 0 bounces."""
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    scenes.plane('Floor', size=8, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    lamp = scenes.plane('Lamp', size=1, location=(0, 0, height), materials=[scenes.emission('e', (1, 1, 1), 5.0)])
    lamp.rotation_euler = (math.pi, 0, 0)
    scenes.black_world()
    rendering.matched(sc, samples, bounces=0)
    return lamp


def twin(lamp, offset=(0.0, 0.0, 0.0), turn=0.0, material=None):
    """'Twin', an object of the lamp's mesh moved by `offset` and turned by `turn` about the
    lamp's normal; its material, where given, linked to the object (a Diffuse copy)."""
    other = scenes.link(bpy.data.objects.new('Twin', lamp.data))
    other.location = tuple(a + d for a, d in zip(lamp.location, offset))
    rx, ry, rz = lamp.rotation_euler
    other.rotation_euler = (rx, ry, rz + turn)
    if material is not None:
        other.material_slots[0].link = 'OBJECT'
        other.material_slots[0].material = material
    return other
