"""A translation changes no image, also when the geometry's bounding box does not show where the
scene is (the numerics hunt's bug 1): a closed room 1e5 .. 1e6 from the origin with one small
triangle left on the other side of the origin. The bounding box then centres near 0, the room
kept coordinates of 3e5, and every bounce or shadow ray started 8 ULPs of them (0.25 m) off its
wall: 0.62x the same room at the origin, 0.61x Cycles, silently. The render now centres on the
geometry around the camera (sceneprep.recentred), and says so when no origin keeps it precise.

Paired against the room at the origin (same seeds): mean and 4x4 blocks within noise; the
Position pass still reads world coordinates; a scene around the origin keeps its coordinates
(the same SceneData, bit for bit); a warning naming the coordinates where no origin helps, none
where one does."""

import numpy as np
import pytest

from addon import scenedata as sd
from addon.sceneprep import recentred

from ..integrator.scenes import ALL_VIS, cornell_box, geometry, light, material, render
from .conftest import REPORT

Z = 4.5  # two-sided z bound per comparison (17 per render: false alarms ~1e-4 in all)
W, H = 32, 24
DIRECTION = np.array([1.0, 0.5, 0.25])   # where the room is moved, as a georeferenced scene


def _look_at(eye, target):
    f = np.asarray(target, float) - eye
    f /= np.linalg.norm(f)
    x = np.cross(f, (0.0, 0.0, 1.0))
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(x, f), -f, eye
    return m


def _box(lo, hi, inward):
    """The six faces of an axis-aligned box as 12 triangles, facing in or out."""
    c = np.array([(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])],
                 np.float64)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    t = [tri for a, b, cc, d in quads for tri in ((a, b, cc), (a, cc, d))]
    t = np.array(t)
    return c, (t[:, ::-1] if inward else t)


def room(offset=0.0, outlier=False, samples=32, seed=0, passes=(), camera_at=None, twin=False):
    """A closed 4 x 4 x 3 m room (walls facing in) with a 1 m box on the floor and a 0.8 m area
    light under the ceiling; a sun and a bright world outside must not leak in. Moved by
    offset x DIRECTION; outlier: a 10 cm triangle at minus that; twin: a second room there."""
    o = offset * DIRECTION
    walls, cube = _box((-2, -2, 0), (2, 2, 3), True), _box((-0.5, 0.3, 0), (0.5, 1.3, 1), False)
    parts = [(walls[0] + o, walls[1], 1, ALL_VIS), (cube[0] + o, cube[1], 2, ALL_VIS)]
    if outlier:
        parts.append((np.array([(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)]) - o, np.array([(0, 1, 2)]), 1, ALL_VIS))
    if twin:
        parts.append((walls[0] - o, walls[1], 1, ALL_VIS))
    area = np.eye(4)
    area[:3, 3] = o + (0.8, -0.5, 2.9)
    sun = np.eye(4)
    sun[:3, 3] = o + (0, 0, 10)
    sun[:3, :3] = np.array([[1, 0, 0], [0, np.cos(0.7), -np.sin(0.7)], [0, np.sin(0.7), np.cos(0.7)]])
    lights = [light('AREA', 200.0, area, size_x=0.8, size_y=0.8), light('SUN', 50.0, sun)]
    eye = o + (1.5, -1.7, 1.6) if camera_at is None else np.asarray(camera_at, float)
    cam = sd.Camera('PERSP', _look_at(eye, o + (-0.5, 0.8, 0.5)), (-W / H, W / H, -1.0, 1.0),
                    np.tan(np.radians(37.0)), 0.01, 1e7, W, H)
    mats = [material('default'), material('white', (0.7,) * 3), material('red', (0.7, 0.2, 0.2))]
    return sd.SceneData(cam, geometry(parts), mats, lights, np.array([2.5, 3.0, 5.0], np.float32),
                        sd.Settings(samples=samples, max_bounces=4, seed=seed, filter_type='BOX',
                                    passes=tuple(passes)))


def _image(integ):
    return integ.film.combined()[..., :3].astype(np.float64).mean(axis=2)


def _blocks(img):
    return img.reshape(4, H // 4, 4, W // 4).mean(axis=(1, 3)).ravel()


_BASE = {}


def _at_origin():
    if 'img' not in _BASE:
        _BASE['img'] = _image(render(room()))
    return _BASE['img']


@pytest.mark.parametrize("offset", [1e5, 3e5, 1e6])
def test_far_room_with_an_outlier_renders_as_at_the_origin(offset):
    base = _at_origin()
    integ = render(room(offset, outlier=True))
    img = _image(integ)
    diff = img - base                                  # same seeds: paired pixels
    se = diff.std(ddof=1) / np.sqrt(diff.size)
    REPORT.append(f"far room +{offset:g} with an outlier: mean {img.mean():.4f} vs {base.mean():.4f} "
                  f"at the origin (ratio {img.mean() / base.mean():.4f}, paired se {se:.2g})")
    assert abs(diff.mean()) <= Z * se + 1e-6, \
        f"+{offset:g}: mean {img.mean():.4f} vs {base.mean():.4f} at the origin (paired se {se:.3g})"
    # blocks: paired too, each against its own pixels' spread (a darker floor shows here first)
    d = diff.reshape(4, H // 4, 4, W // 4).transpose(0, 2, 1, 3).reshape(16, -1)
    bse = d.std(axis=1, ddof=1) / np.sqrt(d.shape[1])
    bad = np.abs(d.mean(axis=1)) > Z * bse + 1e-6
    assert not bad.any(), f"+{offset:g}: blocks {np.flatnonzero(bad)} differ: " \
        f"{np.round(_blocks(img) / _blocks(base), 3)[bad]} of the origin's"
    assert not any('float32 precision' in text for _, text in integ.messages), integ.messages


def test_position_pass_reads_world_coordinates_after_camera_centring():
    """The render's origin is the camera's surroundings, not the box centre: Position adds it back."""
    base = render(room(passes=('Position',), samples=1)).film.pass_image('Position')
    far = render(room(3e5, outlier=True, passes=('Position',), samples=1)).film.pass_image('Position')
    seen = np.isfinite(base).all(axis=2) & np.isfinite(far).all(axis=2)
    assert seen.mean() > 0.99
    moved = far[seen].astype(np.float64) - 3e5 * DIRECTION
    # float32 world coordinates at 3e5 hold 2^-5 m: the pass can say no more than that
    assert np.abs(moved - base[seen]).max() <= 2 ** -5 * 2, np.abs(moved - base[seen]).max()


def test_a_scene_around_the_origin_keeps_its_coordinates():
    for scene in (cornell_box(), room(), room(0.0, outlier=True)):
        out, origin, warning = recentred(scene)
        assert out is scene and not origin.any() and warning is None


def test_one_far_cluster_is_centred_as_before():
    """No outlier: the bounding box's rule, unchanged (the same origin, the box's centre)."""
    scene = room(3e5)
    _, origin, warning = recentred(scene)
    v = scene.geometry.vertices
    assert np.array_equal(origin, 0.5 * (v.min(axis=0) + v.max(axis=0))) and warning is None


@pytest.mark.parametrize("offset", [1e5, 1e6])
def test_camera_surroundings_centred_far_from_the_bounding_box(offset):
    out, origin, warning = recentred(room(offset, outlier=True))
    v = np.asarray(out.geometry.vertices)
    assert warning is None
    assert np.abs(v[:16]).max() < 8, origin     # the room and box: a few metres, not 1e5


def test_warns_where_no_origin_keeps_the_camera_surroundings_precise():
    """Two rooms 6e5 apart, the camera half-way: whatever the render centres on, one of them
    keeps coordinates of 3e5 (0.25 m steps). Said once, naming the coordinates."""
    integ = render(room(3e5, twin=True, samples=1, camera_at=(0.0, 0.0, 1.0)))
    said = [text for level, text in integ.messages if 'float32 precision' in text]
    assert len(said) == 1 and ('WARNING', said[0]) in integ.messages, integ.messages
    assert "3e+05" in said[0] and "near the world origin" in said[0], said[0]
    # the same rooms around the origin: precise, nothing said
    quiet = render(room(0.0, samples=1, camera_at=(0.0, 0.0, 1.0)))
    assert not any('float32 precision' in text for _, text in quiet.messages), quiet.messages
