"""A huge single-quad ground plane under small objects is said, not rendered wrong in silence
(the scale fuzz hunt's top bug). A triangle's self-intersection step is 8 float32 ULPs of its
largest coordinate (surfacetables.OFFSET_ULPS), so a plane of half-size 1e6 steps every bounce
and shadow ray 0.5 m off itself, also under a 1 m box at the origin: the box's contact shadow
is lost (64x48, Cycles 512 spp against DACRT 2 x 256 spp, the shadow's 8x8 block: half-size
1e4 x1.003, 1e5 x1.033, 1e6 x1.128 Cycles'; a fuzz scene with Suzanne, boxes and a sun on such
a plane 1.22x Cycles over the whole image), and nothing was said. The render now warns, naming
the object and the step, where the step exceeds 1% of the objects on or near the surface
(sceneprep.huge_surfaces); planes up to 1e4 (within noise), far-away large objects (a mountain
1e5 out), objects too small to make out from the camera and ordinary scenes say nothing."""

from dataclasses import replace

import numpy as np
import pytest

from addon import scenedata as sd
from addon.sceneprep import huge_surfaces, recentred

from ..integrator.scenes import ALL_VIS, cornell_box, geometry, material, render


def _box(lo, hi):
    c = np.array([(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])],
                 np.float64)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return c, np.array([t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))])


def scene(half_size, mountain_at=None, offset=0.0, eye=(3.0, -3.0, 2.0)):
    """A 1 m box standing on one quad of the given half-size (two triangles), camera above;
    optionally a large box ('mountain') far away."""
    o = np.array([1.0, 0.5, 0.25]) * offset
    plane = np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], np.float64) * (half_size, half_size, 0)
    box = _box((-0.5, -0.5, 0), (0.5, 0.5, 1))
    parts = [(plane + o, np.array([(0, 1, 2), (0, 2, 3)]), 1, ALL_VIS), (box[0] + o, box[1], 1, ALL_VIS)]
    names = ['ground', 'box']
    if mountain_at is not None:
        m = _box((mountain_at, mountain_at, 0), (1.5 * mountain_at, 1.5 * mountain_at, 0.3 * mountain_at))
        parts.append((m[0] + o, m[1], 1, ALL_VIS))
        names.append('mountain')
    cam = np.eye(4)
    cam[:3, 3] = o + eye
    data = sd.SceneData(sd.Camera('PERSP', cam, (-1.0, 1.0, -1.0, 1.0), 0.8, 0.01, 1e7, 8, 8),
                        geometry(parts), [material('default'), material('grey', (0.5,) * 3)], [],
                        np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
    data.object_names[:] = names
    return data


def _said(integ):
    return [text for level, text in integ.messages if level == 'WARNING' and 'off the surface' in text]


@pytest.mark.parametrize("half_size", [1e5, 1e6])
def test_a_huge_ground_plane_under_a_box_is_said(half_size):
    said = _said(render(scene(half_size)))
    assert len(said) == 1, said
    text = said[0]
    step = 8 * float(np.spacing(np.float32(half_size)))
    assert "object 'ground'" in text and f"{half_size:.3g}" in text, text
    assert f"{step:.2g} off the surface" in text and "Subdivide" in text, text


def test_the_same_plane_far_from_the_origin_is_said_too():
    """Moved 1e5 away, the render centres on it: the plane still reaches 1e6 from that origin."""
    said = _said(render(scene(1e6, offset=1e5)))
    assert len(said) == 1 and "render's origin" in said[0], said


@pytest.mark.parametrize("half_size", [10.0, 1e3, 1e4])
def test_planes_whose_step_is_within_noise_are_not_said(half_size):
    integ = render(scene(half_size))
    assert not _said(integ), integ.messages


def test_a_large_object_far_away_is_not_said():
    """A mountain 1e5 out has a 6 cm step, but nothing small lies near it."""
    integ = render(scene(10.0, mountain_at=1e5))
    assert not _said(integ), integ.messages


def test_objects_too_small_to_see_from_the_camera_are_not_weighed():
    """The same plane and box seen from 1e5 away: the box spans 1e-5 of its distance."""
    integ = render(scene(1e6, eye=(0.0, -1e5, 2e4)))
    assert not _said(integ), integ.messages


def test_ordinary_scenes_say_nothing():
    for data in (cornell_box(width=8, height=6, samples=1), scene(3.0)):
        moved, origin, _ = recentred(data)
        assert huge_surfaces(moved, origin) == []


def _tilted(distance, half_size=1e6):
    """The box under a huge quad tilted 45 degrees about x whose plane passes `distance` from the
    origin: the quad's halves' boxes hold the box at any distance."""
    s = 1.0 / np.sqrt(2.0)
    c = np.array([0.0, distance * np.sqrt(2.0), 0.0])
    h = half_size
    plane = c + np.array([(-h, -h * s, -h * s), (h, -h * s, -h * s), (h, h * s, h * s), (-h, h * s, h * s)])
    box = _box((-0.5, -0.5, 0), (0.5, 0.5, 1))
    parts = [(plane, np.array([(0, 1, 2), (0, 2, 3)]), 1, ALL_VIS), (box[0], box[1], 1, ALL_VIS)]
    cam = np.eye(4)
    cam[:3, 3] = (3.0, -3.0, 2.0)
    data = sd.SceneData(sd.Camera('PERSP', cam, (-1.0, 1.0, -1.0, 1.0), 0.8, 0.01, 1e7, 8, 8),
                        geometry(parts), [material('default'), material('grey', (0.5,) * 3)], [],
                        np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
    data.object_names[:] = ['slope', 'box']
    return data


@pytest.mark.parametrize("distance,said", [(0.0, True), (1e3, False), (1e5, False)])
def test_a_tilted_huge_quad_is_said_only_of_objects_near_its_plane(distance, said):
    """A tilted quad's box spans 1e6 on every axis: objects 1e3 off its plane (1 000 steps) lie
    inside it but lose no contact shadow, and are not said; the box the plane cuts is."""
    found = _said(render(_tilted(distance)))
    assert len(found) == int(said), found
    if said:
        assert "object 'slope'" in found[0], found


def _scattered(instanced, half_size=1e6):
    """Three 1 m boxes 30 apart on the plane: three objects, or (instanced) three instances of
    one object, which share its object index and differ by placement (Geometry.instance)."""
    plane = np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], np.float64) * (half_size, half_size, 0)
    parts = [(plane, np.array([(0, 1, 2), (0, 2, 3)]), 1, ALL_VIS)]
    for x in (-30.0, 0.0, 30.0):
        b = _box((x - 0.5, -0.5, 0), (x + 0.5, 0.5, 1))
        parts.append((b[0], b[1], 1, ALL_VIS))
    g = geometry(parts)
    names = ['ground', 'box1', 'box2', 'box3']
    if instanced:
        place = np.asarray(g.object_index)
        g = replace(g, object_index=np.minimum(place, 1).astype(np.int32), instance=place.astype(np.int32))
        names = ['ground', 'rock']
    cam = np.eye(4)
    cam[:3, 3] = (3.0, -3.0, 2.0)
    data = sd.SceneData(sd.Camera('PERSP', cam, (-1.0, 1.0, -1.0, 1.0), 0.8, 0.01, 1e7, 8, 8),
                        g, [material('default'), material('grey', (0.5,) * 3)], [],
                        np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
    data.object_names[:] = names
    return data


@pytest.mark.parametrize("instanced", [False, True], ids=['objects', 'instances'])
def test_instances_scattered_on_a_huge_plane_are_weighed_each(instanced):
    """Instances of one rock scattered over the plane are each 1 m across, as three separate
    objects are: said alike (their joint box, 61 m wide, had hidden the 0.5 m step)."""
    found = _said(render(_scattered(instanced)))
    assert len(found) == 1 and "object 'ground'" in found[0] and "50% of the 1-unit objects" in found[0], found


def test_instances_of_a_huge_surface_are_said_once():
    """Two instances of one huge tile side by side: one message naming the tile's object."""
    tile = np.array([(0, -1, 0), (1, -1, 0), (1, 1, 0), (0, 1, 0)], np.float64) * (1e6, 1e6, 0)
    box = _box((-0.5, -0.5, 0), (0.5, 0.5, 1))
    parts = [(tile, np.array([(0, 1, 2), (0, 2, 3)]), 1, ALL_VIS),
             (tile * (-1, 1, 1), np.array([(0, 2, 1), (0, 3, 2)]), 1, ALL_VIS), (box[0], box[1], 1, ALL_VIS)]
    g = geometry(parts)
    place = np.asarray(g.object_index)
    g = replace(g, object_index=np.where(place < 2, 0, 1).astype(np.int32), instance=place.astype(np.int32))
    cam = np.eye(4)
    cam[:3, 3] = (3.0, -3.0, 2.0)
    data = sd.SceneData(sd.Camera('PERSP', cam, (-1.0, 1.0, -1.0, 1.0), 0.8, 0.01, 1e7, 8, 8),
                        g, [material('default'), material('grey', (0.5,) * 3)], [],
                        np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
    data.object_names[:] = ['tile', 'box']
    found = _said(render(data))
    assert len(found) == 1 and "object 'tile'" in found[0] and "more such" not in found[0], found
