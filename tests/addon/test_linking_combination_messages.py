"""The render says when an object's combinations of linking collections pass Blender's 63
(lights/linking.py combinations): Blender then unlinks objects picked by memory order, so
Cycles' image changes between runs (test_linking_edges' 64 lamps, each lighting plane A and a
plane of its own: A lit by all 64 lamps, or by one with plane B); DACRT had said nothing."""
import bpy

from . import scenes


def _lamps(receivers):
    """A lamp per entry of receivers (lists of objects), each with a receiver collection of them."""
    for i, obs in enumerate(receivers):
        lamp = scenes.light('POINT', 10.0, (0, 0, 2), name=f"L{i:02d}")
        coll = bpy.data.collections.new(f"R{i}")
        for ob in obs:
            coll.objects.link(ob)
        lamp.light_linking.receiver_collection = coll


def _planes(n):
    scenes.camera(location=(0, 0, 10), kind='ORTHO', ortho_scale=4.0)
    a = scenes.plane("A", size=1.8, location=(-1, 0, 0))
    return a, [scenes.plane(f"D{i}", size=0.01, location=(10 + i, 10, 0)) for i in range(n)]


def test_65_combinations_are_said(scene, said):
    a, own = _planes(64)
    _lamps([[a, d] for d in own])
    scenes.render_rgba(scene)
    assert [t for t in said if "objects in 65 different combinations of light linking receiver collections, "
            "past Blender's 63" in t], said


def test_64_lamps_in_7_combinations_say_nothing(scene, said):
    a, bits = _planes(6)
    _lamps([[a] + [d for j, d in enumerate(bits) if i >> j & 1] for i in range(64)])
    scenes.render_rgba(scene)
    assert not [t for t in said if "combinations" in t or "light every object" in t], said
