"""Zero-area triangles are dropped (no ray meets them, in Cycles either) and the report names
the objects holding them with their counts, on each export path: separate objects written
together (assembly._single_batch), a mesh placed several times (_instance_batch) and an object
with non-finite vertices too (_each_alone). The message had given only the total, leaving the
user to search every object for them."""
import math
import re

import bpy

from . import scenes

# two good triangles and `n` zero-area ones (collinear corners, a repeated corner)
_GOOD = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]


def _mesh(name, n, location, nan=False):
    verts = list(_GOOD)
    faces = [(0, 1, 2), (0, 2, 3)]
    for i in range(n):
        b = len(verts)
        verts += [(2 + i, 0, 0), (2.5 + i, 0, 0), (3 + i, 0, 0)] if i % 2 else [(2 + i, 0, 1), (2 + i, 0, 1), (3 + i, 0, 1)]
        faces.append((b, b + 1, b + 2))
    if nan:
        verts.append((float('nan'), 0, 0))
        faces.append((0, 1, len(verts) - 1))
    return scenes.mesh(name, verts, faces, location=location)


def _said(data):
    text = [m for _, m in data.messages if 'degenerate (zero-area)' in m]
    assert len(text) == 1, data.messages
    counts = dict((name, int(n)) for name, n in re.findall(r"'([^']+)' (\d+)", text[0]))
    total = int(text[0].split()[0])
    return total, counts


def test_zero_area_triangles_are_said_per_object(scene, exported):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    _mesh("Fan", 3, (-3, 0, 0))
    _mesh("Sliver", 1, (0, 0, 2))
    scenes.cube("Clean", location=(3, 0, 0))
    shared = _mesh("Shared", 2, (0, 0, -2))
    dup = bpy.data.objects.new("SharedCopy", shared.data)     # the same mesh placed twice
    scene.collection.objects.link(dup)
    dup.location = (0, 3, -2)
    data = exported()
    total, counts = _said(data)
    assert counts == {'Fan': 3, 'Sliver': 1, 'Shared': 2, 'SharedCopy': 2}
    assert total == 8 == data.skipped['triangles_degenerate']


def test_zero_area_triangles_beside_nonfinite_vertices_are_said_per_object(scene, exported):
    """A NaN vertex among single placements has them written one by one (_each_alone)."""
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    _mesh("Fan", 3, (-3, 0, 0))
    _mesh("Broken", 4, (-3, 0, 2), nan=True)
    data = exported()
    total, counts = _said(data)
    assert counts == {'Fan': 3, 'Broken': 4}
    assert total == 7 == data.skipped['triangles_degenerate']
    assert any("'Broken': 1 vertices with NaN" in m for _, m in data.messages), data.messages


def test_many_objects_are_named_by_count(scene, exported):
    """Beyond five objects the message names those with the most and counts the rest."""
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    for i in range(7):
        _mesh(f"M{i}", i + 1, (i, 0, 0))
    data = exported()
    total, counts = _said(data)
    assert total == 28
    assert counts == {'M6': 7, 'M5': 6, 'M4': 5, 'M3': 4, 'M2': 3}
    assert "and 2 more objects" in [m for _, m in data.messages if 'zero-area' in m][0]
