"""Coincident non-emissive faces through Blender (addon/coincidentfaces.py;
tests/integrator/test_coincident_faces_said.py for the rules): a Mirror modifier on a mesh
already symmetric, or a second object sharing a mesh in place, lays exact copies of faces,
which render as one surface here and darker in Cycles (a mirrored cube under a grey world, 1
bounce: 1.094x Cycles' image mean). The render says so once, naming the object(s) and
counting the copied triangles (a float64 brute force over the evaluated meshes); a copy moved
by 1e-5 is not said; an emitter's copy keeps its own message alone."""
import math
from collections import Counter

import bpy
import numpy as np

from . import scenes

SAID = "coincide exactly with other triangles"
EMITTERS = "emissive triangles of"


def _scene():
    scenes.camera(location=(0, -7, 4), rotation=(math.radians(60), 0, 0))
    scenes.plane('Floor', size=10, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    cube = scenes.cube('Cube', size=1.0, location=(0, 0, 0.5), materials=[scenes.diffuse('grey', (0.5, 0.5, 0.5))])
    scenes.world((0.5, 0.5, 0.5))
    return cube


def _said(said):
    said.clear()
    scenes.render_rgba()
    return [t for t in said if SAID in t]


def _brute_force_copies():
    """How many triangles of the evaluated scene repeat another exactly (world space, float32
    corners as a sorted tuple)."""
    dg = bpy.context.evaluated_depsgraph_get()
    keys = []
    for ob in bpy.context.scene.objects:
        if ob.type != 'MESH':
            continue
        ev = ob.evaluated_get(dg)
        me = ev.to_mesh()
        me.calc_loop_triangles()
        mw = np.array(ev.matrix_world, np.float64)
        v = np.array([tuple(p.co) for p in me.vertices], np.float64)
        v = (v @ mw[:3, :3].T + mw[:3, 3]).astype(np.float32) + np.float32(0.0)
        keys += [tuple(sorted(map(tuple, v[list(t.vertices)].tolist()))) for t in me.loop_triangles]
        ev.to_mesh_clear()
    return sum(c for c in Counter(keys).values() if c > 1)


def test_mirror_on_a_symmetric_mesh_is_said_once(scene, said):
    cube = _scene()
    assert not _said(said)
    m = cube.modifiers.new('mirror', 'MIRROR')         # the cube is symmetric in x already
    m.use_axis = [True, False, False]
    n = _brute_force_copies()
    assert n > 0
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"{n} triangles of 'Cube' {SAID}"), (n, got)
    assert "one surface" in got[0] and "darker" in got[0], got


def test_a_twin_object_is_said_and_a_near_copy_is_not(scene, said):
    cube = _scene()
    twin = scenes.link(bpy.data.objects.new('Twin', cube.data))
    twin.location = cube.location
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"24 triangles of 'Cube', 'Twin' {SAID}"), got
    twin.location = (0, 0, 0.5 + 1e-5)
    assert not _said(said)


def test_an_emitters_copy_keeps_its_own_message_alone(scene, said):
    _scene()
    lamp = scenes.plane('Lamp', size=1, location=(0, 0, 2), materials=[scenes.emission('e', (1, 1, 1), 5.0)])
    lamp.rotation_euler = (math.pi, 0, 0)
    twin = scenes.link(bpy.data.objects.new('LampTwin', lamp.data))
    twin.location, twin.rotation_euler = lamp.location, lamp.rotation_euler
    assert not _said(said)
    assert len([t for t in said if EMITTERS in t and "coincide" in t]) == 1, said
