"""A huge single-quad ground plane under small objects is said where the render still gets it
wrong, and only there (the scale fuzz hunt's top bug). The step off an axis-aligned plane is
ULPs of its own height (pathvertex.h normal_share: tests/integrator/test_huge_plane_contact.py),
so such a plane renders right except where float32 itself falls short of the objects on it: its
hit points placed to ~1 ULP of its extent (0.06 at half-size 1e6) and points within the step (8
ULPs: 0.06 at 1e5, 0.5 at 1e6) of a face's edge moved along the surface (a 1 m box standing on
the quad's diagonal); on a tilted plane also the step along the normal. Each is named where it
exceeds 1% of the objects on or near the surface (sceneprep.huge_surfaces); the same plane with
the box away from the diagonal says nothing at 1e5. Planes up to 1e4, far-away large objects (a
mountain 1e5 out), objects too small to make out from the camera and ordinary scenes say
nothing."""

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


def scene(half_size, mountain_at=None, offset=0.0, eye=(3.0, -3.0, 2.0), at=(0.0, 0.0), tilt=0.0):
    """A 1 m box standing at `at` on one quad of the given half-size (two triangles, the
    diagonal through the origin), camera above; optionally a large box ('mountain') far away;
    tilt: the whole scene turned about y (radians)."""
    o = np.array([1.0, 0.5, 0.25]) * offset
    plane = np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], np.float64) * (half_size, half_size, 0)
    box = _box((at[0] - 0.5, at[1] - 0.5, 0), (at[0] + 0.5, at[1] + 0.5, 1))
    if tilt:
        c, s = np.cos(tilt), np.sin(tilt)
        turn = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        plane, box = plane @ turn.T, (box[0] @ turn.T, box[1])
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
    return [text for level, text in integ.messages if level == 'WARNING' and 'has faces reaching' in text]


@pytest.mark.parametrize("half_size", [1e5, 1e6])
def test_a_box_on_the_diagonal_of_a_huge_ground_plane_is_said(half_size):
    said = _said(render(scene(half_size)))
    assert len(said) == 1, said
    text = said[0]
    step = 8 * float(np.spacing(np.float32(half_size)))
    assert "object 'ground'" in text and f"{half_size:.3g}" in text, text
    assert f"within {step:.2g} of their edges move up to {2 * step:.2g}" in text and "Subdivide" in text, text
    assert "off the surface" not in text, text           # the plane is axis-aligned: a tiny step
    # an ULP of 1e6 is 6% of the box, of 1e5 0.8%: the placement is named only at 1e6
    assert ("placed only to" in text) == (half_size == 1e6), text


def test_a_box_away_from_the_edges_is_not_said_where_the_plane_renders_right():
    """The box 3.5 m from the diagonal (beyond 4 steps of it at 1e6). At 1e5 the step along the
    normal is ULPs of z = 0 and an ULP of 1e5 under 1% of the box: nothing is wrong, nothing is
    said (it had been); at 1e6 the placement, an ULP of 1e6."""
    integ = render(scene(1e5, at=(0.0, 5.0)))
    assert not _said(integ), integ.messages
    said = _said(render(scene(1e6, at=(0.0, 5.0))))
    assert len(said) == 1 and "placed only to ~0.062" in said[0] and "edges" not in said[0], said


def test_a_tilted_huge_plane_says_its_step_off_the_surface():
    """Turned 0.3 rad, the plane's points err along its normal by ULPs of 1e5 in x: the step."""
    said = _said(render(scene(1e5, at=(0.0, 3.0), tilt=0.3)))
    assert len(said) == 1 and "off the surface" in said[0] and "edges" not in said[0], said


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
