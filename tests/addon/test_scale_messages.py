"""Messages that scale with the scene: an instanced zero-strength lamp is named once, however many
copies the instancer makes (5000 copies had been 5000 names over 34 report lines), and thousands
of skipped objects are each named once."""
import bpy

from . import scenes


def test_an_instanced_zero_strength_lamp_is_named_once(scene, said):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=10)
    lamp = scenes.light('POINT', 0.0, name="Lamp")
    grid = scenes.mesh("Grid", [(x, y, 0) for x in range(10) for y in range(10)], [])
    grid.instance_type = 'VERTS'
    lamp.parent = grid
    scenes.render_rgba(scene)
    text = next(t for t in said if "with zero strength" in t)
    assert text.count("Lamp") == 1 and "skipped 100 light(s)" in text, text


def test_thousands_of_skipped_objects_are_each_named_once(scene, said):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=10)
    for i in range(3000):
        ob = bpy.data.objects.new(f"Vol{i:04d}", bpy.data.volumes.new(f"V{i}"))
        scene.collection.objects.link(ob)
    scenes.render_rgba(scene)
    text = " ".join(t for t in said if "volume" in t)
    assert all(text.count(f"'Vol{i:04d}'") == 1 for i in (0, 1500, 2999)), text[:300]
