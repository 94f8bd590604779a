"""The normal-map "below the surface" WARNING (export/normalmaps.py lit_from_behind) in
interiors: a closed mesh holding the lamp or the camera had been warned whatever its shape, so
every room was. Cycles' light tree leaves a point dark only where a light lies behind the
surface's plane from the side a ray meets it; a closed convex room with the lamp and the camera
inside has every light on the inner side of every wall, and DACRT matches Cycles there
(normalmap_room.py: 0.6537 vs 0.6537 at 512 / 1024 spp, blocks within noise). Now the side test
per wall plane decides, with rays starting at the camera, on the room's own faces and in other
objects' bounds: an L-shaped room with the lamp in one arm and the camera in the other, a lamp
inside a room seen from outside, are still said (the plane test is conservative: a non-convex
room is said wherever some wall's plane separates a face of it from a light, hidden or not)."""
import bpy
import pytest
from mathutils import Vector

from . import scenes
from .test_message_truth import BELOW, _bumpy


def _box_room(rotation=(0, 0, 0), flipped=False):
    bpy.ops.mesh.primitive_cube_add(size=6.0, location=(0, 0, 3.0), rotation=rotation)
    room = bpy.context.active_object
    room.name = 'Room'
    room.data.materials.append(_bumpy('Walls'))
    if flipped:                 # normals into the room, as modelled interiors often are
        room.data.flip_normals()
    return room


def _l_room():
    """A closed L-shaped room (footprint 6 x 6 less its 3 x 3 corner at +x +y), 3 m high."""
    foot = [(0, 0), (6, 0), (6, 3), (3, 3), (3, 6), (0, 6)]
    verts = [(x, y, 0.0) for x, y in foot] + [(x, y, 3.0) for x, y in foot]
    n = len(foot)
    faces = [tuple(reversed(range(n))), tuple(range(n, 2 * n))]
    faces += [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return scenes.mesh('Room', verts, faces, materials=[_bumpy('Walls')])


def _camera(at, target):
    cam = scenes.camera(at, lens=18.0)
    cam.rotation_euler = (Vector(target) - Vector(at)).to_track_quat('-Z', 'Y').to_euler()
    return cam


def _said(data):
    return [m for _, m in data.messages if BELOW in m]


@pytest.fixture(autouse=True)
def _tree(scene):
    scene.dacrt.use_light_tree = True


@pytest.mark.parametrize('case', ['box', 'flipped', 'rotated', 'box with furniture', 'area lamp'])
def test_convex_room_with_lamp_and_camera_inside_not_said(case, exported):
    _box_room(rotation=(0.3, 0.2, 0.5) if case == 'rotated' else (0, 0, 0), flipped=case == 'flipped')
    if case == 'box with furniture':
        scenes.cube('Table', size=1.0, location=(0.5, 0.5, 0.5), materials=[_bumpy('Wood')])
    if case == 'area lamp':
        scenes.light('AREA', 300.0, location=(0.5, 0.0, 5.0), size=1.0)
    else:
        scenes.light('POINT', 500.0, location=(1.0, 0.5, 4.5), shadow_soft_size=0.2)
    _camera((-1.8, -1.8, 1.6), (1.5, 1.5, 2.0))
    assert _said(exported()) == []


def test_l_shaped_room_lamp_round_the_corner_said(exported):
    """A wall plane of the inner corner (x = 3) has the lamp on one side, the camera on the other."""
    _l_room()
    scenes.light('POINT', 300.0, location=(5.0, 1.5, 1.5), shadow_soft_size=0.1)
    _camera((1.5, 5.0, 1.5), (1.5, 1.5, 1.5))
    said = _said(exported())
    assert len(said) == 1 and "'Walls'" in said[0], said


def test_room_seen_from_outside_with_the_lamp_inside_said(exported):
    """A ray from the camera outside meets the walls' outer side, the lamp lies behind it."""
    _box_room()
    scenes.light('POINT', 500.0, location=(1.0, 0.5, 4.5), shadow_soft_size=0.2)
    _camera((0.0, -12.0, 3.0), (0.0, 0.0, 3.0))
    said = _said(exported())
    assert len(said) == 1 and "'Walls'" in said[0], said
