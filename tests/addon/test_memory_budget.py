"""The frame's memory budget (export/budget.py): point clouds and hair go coarser than their
usual tessellation when the frame would not fit in the memory available, the biggest are left
out (named) when even the coarsest does not fit, and a frame whose meshes alone cannot fit is
refused with the numbers, where the kernel had killed the process without a word (a 4M-point
cloud grew to 23.5 GB). The memory available is replaced by a small figure here."""
import math
import sys

import numpy as np
import pytest

from addon import hair, pointcloud
from addon.export import budget

from . import scenes


def _strands(key, kind, per_level, copies=1):
    return budget.Strands(key, kind, lambda level: per_level[level], copies)


def test_fit_coarsens_the_kind_that_needs_most_then_leaves_out_the_biggest():
    ladders = {'spheres': (3, 2, 1), 'tubes': ('fine', 'coarse')}
    start = {'spheres': 3, 'tubes': 'fine'}
    cloud = _strands('cloud', 'spheres', {3: 1000, 2: 400, 1: 100})
    fur = _strands('fur', 'tubes', {'fine': 300, 'coarse': 150}, copies=2)
    per = budget.STRAND_BYTES
    mesh = 10
    room = lambda tris: (tris * per + mesh * budget.MESH_BYTES) / budget.HEADROOM
    # everything fits: nothing changes
    assert budget.fit(mesh, [cloud, fur], start, ladders, room(1000 + 600)) == (start, [])
    # 1000 + 600 does not fit in 1100: the cloud (1000) is coarsened first, to 400, which fits
    assert budget.fit(mesh, [cloud, fur], start, ladders, room(1100)) == ({'spheres': 2, 'tubes': 'fine'}, [])
    # 700: cloud -> 400, then the fur (600) needs most -> 300: 700
    assert budget.fit(mesh, [cloud, fur], start, ladders, room(700)) == ({'spheres': 2, 'tubes': 'coarse'}, [])
    # 350: everything at its coarsest is 100 + 300; the fur (300) is left out
    levels, dropped = budget.fit(mesh, [cloud, fur], start, ladders, room(350))
    assert levels == {'spheres': 1, 'tubes': 'coarse'} and dropped == [fur]
    # nothing fits: both left out, the biggest first
    assert budget.fit(mesh, [cloud, fur], start, ladders, room(50))[1] == [fur, cloud]
    # where the system does not say how much memory there is, no budget
    assert budget.fit(mesh, [cloud, fur], start, ladders, None) == (start, [])


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason="reads Linux's /proc/meminfo")
def test_the_memory_available_is_read_from_the_system():
    with open('/proc/meminfo') as f:
        total = next(int(line.split()[1]) * 1024 for line in f if line.startswith('MemTotal:'))
    room = budget.available_bytes()
    from addon import allocator
    assert 16 * 2**20 < room <= total + allocator.heap_free(), (room, total)


def test_coarser_tessellations_have_the_spheres_and_tubes_area():
    """The octahedron and the 3-sided tube the budget may fall to keep Cauchy's scaling: the
    sphere's area 4 pi r^2, the tube's perimeter 2 pi r, a Poly tube's two end caps the
    sphere's area."""
    v, t, scale = pointcloud.unit_sphere(pointcloud.LADDER[-1])
    e1, e2 = v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]
    normal = np.cross(e1, e2)
    assert len(t) == 8 and (np.einsum('ij,ij->i', normal, v[t].mean(1)) > 0).all()
    assert math.isclose(0.5 * np.linalg.norm(normal, axis=1).sum() * scale ** 2, 4 * math.pi, rel_tol=1e-9)
    offsets = np.array([0, 2])
    ends = np.array([[0, 0, 0], [0, 0, 1.0]])
    v, t, n, kept = hair.tubes(ends, np.full(2, 0.1), offsets, hair.LADDER[-1])
    ring = v[:3]
    perimeter = np.linalg.norm(ring - np.roll(ring, 1, axis=0), axis=1).sum()
    assert len(t) == hair.triangle_count(offsets, hair.LADDER[-1]) == 6
    assert math.isclose(perimeter, 2 * math.pi * 0.1, rel_tol=1e-6)
    v, t, n, kept = hair.tubes(ends, np.full(2, 0.1), offsets, hair.LADDER[-1], linear=True)
    corners = v[t].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert len(t) == hair.triangle_count(offsets, hair.LADDER[-1], linear=True) == 6 + 2 * 3 * 3
    assert math.isclose(area, 2 * math.pi * 0.1 + 4 * math.pi * 0.1 ** 2, rel_tol=1e-6)


def _lit_scene(scene):
    scenes.camera((0, -6, 1.5), (math.radians(80), 0, 0))
    scenes.plane("Floor", size=8)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    rng = np.random.default_rng(3)
    cloud = scenes.point_cloud("Cloud", rng.uniform(-1, 1, (300, 3)) + (0, 0, 1.2), radius=0.05)
    fur = scenes.hair_curves("Fur", [np.array([[0.2 * i - 1, 0.5, 0.1 * j] for j in range(8)]) for i in range(10)],
                             radius=0.02)
    return cloud, fur


def _room(monkeypatch, nbytes):
    monkeypatch.setattr(budget, 'available_bytes', lambda: nbytes)


def _tris(data, name):
    return int((data.geometry.object_index == data.object_names.index(name)).sum())


def test_point_clouds_go_coarser_to_fit_the_memory(scene, exported, monkeypatch):
    _lit_scene(scene)
    usual = exported()
    assert _tris(usual, "Cloud") == 300 * 1280 and _tris(usual, "Fur") == 10 * 7 * 4 * 16 * 2
    # 20 MB: the spheres of 1280 (115 MB) and 320 triangles (29 MB) do not fit, of 80 (7 MB) do;
    # the hair (2.7 MB) keeps its level
    _room(monkeypatch, 20 * 2**20)
    data = exported()
    assert _tris(data, "Cloud") == 300 * 80 and _tris(data, "Fur") == _tris(usual, "Fur")
    text = " ".join(t for _, t in data.messages)
    assert "'Cloud': point clouds rendered as spheres of 80 triangles, coarser than usual to fit the frame " \
           "in the 20 MB of memory available" in text, text
    assert "tubes of 16 sides, 4 step(s) a segment, open ends" in text and "open ends, coarser" not in text, text


def test_what_cannot_fit_is_left_out_named_and_the_rest_rendered(scene, monkeypatch, said):
    cloud, fur = _lit_scene(scene)
    # 0.5 MB: at their coarsest the spheres (2400 triangles, 0.7 MB) and the 3-sided tubes
    # (420, 0.1 MB) do not fit together; the cloud, the bigger, is left out
    _room(monkeypatch, 2**19)
    left_out = scenes.render_rgba(scene)
    text = " ".join(said)
    assert "skipped 'Cloud': a point cloud of 300 points, even at the coarsest tessellation (2,400 triangles" in text
    assert "(2,400 triangles, about 703 KB), does not fit with the rest of the frame in the 512 KB of memory" \
           " available" in text, text
    assert "'Fur': hair curves rendered as tubes of 3 sides, 1 step(s) a segment, open ends, coarser than usual" in text
    # the image is the frame's without the cloud: as a render with the cloud hidden (and 160
    # KB, where the hair takes the same 3-sided tubes: 4 sides, 168 KB, do not fit)
    cloud.hide_render = True
    _room(monkeypatch, 160 * 2**10)
    said.clear()
    hidden = scenes.render_rgba(scene)
    assert not any("Cloud" in t for t in said) and "tubes of 3 sides" in " ".join(said)
    assert np.array_equal(left_out, hidden)


def test_a_frame_of_meshes_that_cannot_fit_is_refused_with_the_numbers(scene, monkeypatch):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor")
    scenes.light('SUN', 3.0)
    _room(monkeypatch, 400)
    with pytest.raises(RuntimeError, match="the frame's meshes make 2 triangles .* about 500 bytes to render, "
                                           "more than the 400 bytes of memory available"):
        scenes.render_rgba(scene)


def test_a_film_that_cannot_fit_is_refused_naming_its_size(scene, monkeypatch, said):
    """A resolution whose film does not fit is refused before it is allocated, naming its size
    (a 100000 x 100000 render had failed as 'out of memory ... DACRT holds every triangle',
    and one whose arrays Linux grants gets the process killed); a cropped border is the film."""
    scenes.camera((0, 0, 5))
    scenes.plane("Floor")
    scenes.light('SUN', 3.0)
    need = budget.film_bytes(32 * 24, 0)
    assert need == 32 * 24 * budget.PIXEL_BYTES
    _room(monkeypatch, need - 1)
    with pytest.raises(RuntimeError, match=r"the image of 32 x 24 pixels \(Resolution 32 x 24 at 100%\) needs "
                                           r"about 150 KB to render .* more than the 150 KB of memory available"):
        scenes.render_rgba(scene)
    # a pass's channels count: the Normal pass (3) does not fit where Combined alone does
    _room(monkeypatch, need)
    assert scenes.render_rgba(scene).shape == (24, 32, 4)
    scene.view_layers[0].use_pass_normal = True
    with pytest.raises(RuntimeError, match="the image of 32 x 24 pixels"):
        scenes.render_rgba(scene)
    scene.view_layers[0].use_pass_normal = False
    # the cropped border (8 x 6 pixels) is the film; at 50% the resolution is named as set
    r = scene.render
    r.use_border, r.use_crop_to_border = True, True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.5, 0.25, 0.5
    _room(monkeypatch, budget.film_bytes(8 * 6, 0))
    assert scenes.render_rgba(scene).shape == (6, 8, 4)
    r.use_border = False
    r.resolution_percentage = 50
    _room(monkeypatch, budget.film_bytes(16 * 12, 0) - 1)
    with pytest.raises(RuntimeError, match=r"the image of 16 x 12 pixels \(Resolution 32 x 24 at 50%\)"):
        scenes.render_rgba(scene)
