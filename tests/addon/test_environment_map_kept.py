"""Frames of an unchanged Environment Texture world reuse its native environment map
(lights/envkeep.py): the image's texels are read every frame (from the file, as Cycles reads
it), and where they hold the same bits as the frame before (and the rotation, strength and
lookup are the same) the map and the bright-texel check are not made again (a 4K float HDRI's
~120 + ~30 ms of CPU a frame), and a file's kept, read-only texels are scanned once (the
world's texel check, ~28 ms). A frame after any change of what the map is made from (a pixel
painted, the file rewritten and reloaded, the Background's strength, the Mapping rotation, the
interpolation) renders exactly as it does with nothing kept; an 8-bit image's map (made from
its bytes, sRGB-encoded) the same way."""
import math

import dacrt
import numpy as np
import pytest

from addon import scenedata as sd
from addon.lights import envkeep

from . import scenes
from .test_sky_map_kept import renders_as_with_nothing_kept


@pytest.fixture(autouse=True)
def nothing_kept():
    envkeep.forget()
    yield
    envkeep.forget()


def _texels(seed=3, h=32, w=64):
    rng = np.random.default_rng(seed)
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = (rng.random((h, w, 3)) ** 3 * 4).astype(np.float32)
    return px


def _hdri_world(scene, image):
    """A diffuse ball under an Environment Texture of image through a Mapping node; 1 spp, 2
    bounces."""
    scenes.camera(location=(0, -5, 0), rotation=(math.radians(90), 0, 0))
    scenes.uv_sphere(materials=[scenes.diffuse('grey', (0.5, 0.5, 0.5))])
    w = scenes.environment_world(image, strength=1.0, rotation=(0.0, 0.0, 0.3))
    scene.dacrt.samples, scene.dacrt.max_bounces = 1, 2
    nt = w.node_tree
    return (next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT'),
            next(n for n in nt.nodes if n.type == 'BACKGROUND'),
            next(n for n in nt.nodes if n.type == 'MAPPING'))



def _write_png(path, px):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(px.shape[1], px.shape[0], 4, 'uint8'))
    out.write_image(np.ascontiguousarray((np.clip(px[::-1], 0, 1) * 255).round().astype(np.uint8)))
    out.close()


@pytest.mark.parametrize('source', ['file', 'packed', 'buffer', '8-bit file'])
def test_frames_of_one_hdri_build_its_map_once(scene, tmp_path, monkeypatch, source, calls_to):
    if source == 'file':
        scenes.write_exr(tmp_path / 'sky.exr', _texels())
        image = scenes.bpy.data.images.load(str(tmp_path / 'sky.exr'))
    elif source == '8-bit file':      # (its bytes are the map's encoded texels: lights/environment.py)
        _write_png(tmp_path / 'sky.png', _texels())
        image = scenes.bpy.data.images.load(str(tmp_path / 'sky.png'))
    elif source == 'packed':
        image = scenes.float_image('sky', _texels())
    else:
        image = _buffer_image(_texels())
    _hdri_world(scene, image)
    builds = calls_to(dacrt.lamps, 'environment_map')
    films = scenes.frame_films(scene)
    assert len(builds) == 1, builds
    assert np.array_equal(films[0], films[1]) and np.array_equal(films[0], films[2])


def _buffer_image(px):
    """A float image of pixels (h, w, 4) held only in Blender's buffer (generated, not packed)."""
    img = scenes.bpy.data.images.new('painted', px.shape[1], px.shape[0], float_buffer=True, alpha=True)
    img.pixels.foreach_set(np.ascontiguousarray(px, np.float32).ravel())
    img.update()
    return img


def _paint(env, bg, mapping):
    img = env.image
    px = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(px)
    px[4 * (16 * 64 + 40):4 * (16 * 64 + 40) + 3] = 30.0      # one texel, bright
    img.pixels.foreach_set(px)
    img.update()


def _rewrite(env, bg, mapping):
    path = scenes.bpy.path.abspath(env.image.filepath)
    (_write_png if path.endswith('.png') else scenes.write_exr)(path, _texels(seed=4))
    env.image.reload()


CHANGES = {
    'painted': _paint,
    'rewritten': _rewrite,
    'rewritten 8-bit': _rewrite,
    'strength': lambda env, bg, mapping: setattr(bg.inputs['Strength'], 'default_value', 2.5),
    'rotation': lambda env, bg, mapping: setattr(mapping.inputs['Rotation'], 'default_value', (0.0, 0.0, 1.3)),
    'interpolation': lambda env, bg, mapping: setattr(env, 'interpolation', 'Closest'),
}


@pytest.mark.parametrize('change', CHANGES)
def test_a_changed_hdri_renders_as_with_nothing_kept(scene, tmp_path, change):
    if change == 'rewritten':
        scenes.write_exr(tmp_path / 'sky.exr', _texels())
        image = scenes.bpy.data.images.load(str(tmp_path / 'sky.exr'))
    elif change == 'rewritten 8-bit':
        _write_png(tmp_path / 'sky.png', _texels())
        image = scenes.bpy.data.images.load(str(tmp_path / 'sky.png'))
    elif change == 'painted':
        image = _buffer_image(_texels())     # (no file: Blender's buffer is what renders, edits too)
    else:
        image = scenes.float_image('sky', _texels())
    renders_as_with_nothing_kept(scene, CHANGES[change], _hdri_world(scene, image))


def _env(px, strength=1.0):
    return sd.Environment(px, np.full(3, strength, np.float32), np.eye(3), 'Linear')


def test_texels_written_in_place_are_not_taken_for_the_kept_ones(monkeypatch, calls_to):
    """The same array handed again after being written in place equals itself: it is not
    compared, the map is built again (and a copy of the same bits is the kept map)."""
    builds = calls_to(dacrt.lamps, 'environment_map')
    px = _texels()
    first = envkeep.native_map(_env(px), np.eye(3), 'Linear', np.ones(3, np.float32))
    px[3, 5, :3] = 50.0
    again = envkeep.native_map(_env(px), np.eye(3), 'Linear', np.ones(3, np.float32))
    assert len(builds) == 2 and again is not first
    same = envkeep.native_map(_env(px.copy()), np.eye(3), 'Linear', np.ones(3, np.float32))
    assert len(builds) == 2 and same is again
    assert envkeep.any_positive(_env(px.copy()))


def test_maps_above_the_limit_are_built_every_frame(monkeypatch, calls_to):
    monkeypatch.setattr(envkeep, '_SAME_BYTES', 1000)
    builds = calls_to(dacrt.lamps, 'environment_map')
    px = _texels()
    for _ in range(2):
        envkeep.native_map(_env(px.copy()), np.eye(3), 'Linear', np.ones(3, np.float32))
    assert len(builds) == 2 and not envkeep._same


def test_same_bits_is_every_byte_compared(monkeypatch):
    monkeypatch.setattr(envkeep, '_CHUNK', 7)      # (chunk edges inside the arrays)
    rng = np.random.default_rng(0)
    for shape, dtype in (((5, 9, 4), np.float32), ((3, 3, 3), np.float32), ((13,), np.uint8), ((2, 5), np.float64)):
        a = rng.normal(size=shape).astype(dtype) if dtype != np.uint8 else rng.integers(0, 255, shape, np.uint8)
        assert envkeep.same_bits(a, a.copy())
        for i in range(a.size):                     # any one element changed
            b = a.copy()
            flat = b.reshape(-1)
            flat[i] = flat[i] + 1 if dtype == np.uint8 else np.nextafter(flat[i], dtype(np.inf))
            assert not envkeep.same_bits(a, b), (shape, i)
    a = np.zeros((4, 4), np.float32)
    assert not envkeep.same_bits(a, -a)                                  # (-0 is other bits)
    nan = np.full(4, np.nan, np.float32)
    assert envkeep.same_bits(nan, nan.copy())                            # (NaN: the same bits)
    assert not envkeep.same_bits(a, a.astype(np.float64))
    assert not envkeep.same_bits(a, a.reshape(2, 8))
    assert not envkeep.same_bits(a[:, ::2], a[:, ::2].copy())            # (not contiguous: not compared)


def test_a_build_on_another_thread_cannot_replace_the_map_a_comparison_answered_for(monkeypatch):
    """A viewport's export and a final render's may ask at once: while one thread compares its
    texels with the kept ones, another thread's build of other texels waits, so the first gets
    the map of its own texels (without the lock it got the other's)."""
    import threading
    ones = np.ones(3, np.float32)
    a, b = _texels(seed=5), _texels(seed=6)
    kept_a = envkeep.native_map(_env(a), np.eye(3), 'Linear', ones)
    real = envkeep.same_bits
    other = {}

    def compare_while_another_builds(x, y):
        if not other:
            t = other['thread'] = threading.Thread(
                target=lambda: other.setdefault('map', envkeep.native_map(_env(b), np.eye(3), 'Linear', ones)))
            t.start()
            t.join(0.5)          # (blocked by the lock: the build waits for this answer)
        return real(x, y)
    monkeypatch.setattr(envkeep, 'same_bits', compare_while_another_builds)
    got = envkeep.native_map(_env(a.copy()), np.eye(3), 'Linear', ones)
    other['thread'].join()
    assert got is kept_a
    assert other['map'] is not kept_a


def test_frames_of_an_unchanged_hdri_file_scan_its_texels_once(scene, tmp_path, calls_to):
    """The world's check of the texels (non-finite, negative, bright) and the bright check scan
    a file's kept, read-only texels once in three frames (a 4K float HDRI: ~28 ms of CPU a scan;
    five scans before: two a frame, one on the third)."""
    from addon.export import readkeep
    readkeep.forget()
    scenes.write_exr(tmp_path / 'sky.exr', _texels())
    image = scenes.bpy.data.images.load(str(tmp_path / 'sky.exr'))
    _hdri_world(scene, image)
    scans = calls_to(dacrt.lamps, 'texel_stats')
    films = scenes.frame_films(scene)
    readkeep.forget()
    assert len(scans) == 1, scans
    assert np.array_equal(films[0], films[1]) and np.array_equal(films[0], films[2])


def test_texel_stats_are_kept_only_for_the_same_read_only_array(calls_to):
    """A writable array (written in place since, perhaps), a read-only view of a writable one and
    a copy with the same bits are scanned again; the same read-only array is not."""
    scans = calls_to(dacrt.lamps, 'texel_stats')
    px = _texels()
    assert envkeep.texel_stats(px) == (0, False, True)
    px[3, 5, 0], px[4, 6, 1] = np.nan, -2.0
    assert envkeep.texel_stats(px) == (1, True, True) and len(scans) == 2
    view = px[:]
    view.flags.writeable = False                    # (its base still writable)
    assert envkeep.texel_stats(view) == (1, True, True) and len(scans) == 3
    px[3, 5, 0] = 1.0
    assert envkeep.texel_stats(view) == (0, True, True) and len(scans) == 4
    frozen = px.copy()
    frozen.flags.writeable = False
    assert envkeep.texel_stats(frozen) == (0, True, True) and len(scans) == 5
    assert envkeep.texel_stats(frozen) == (0, True, True) and len(scans) == 5
    assert envkeep.any_positive(_env(frozen)) and len(scans) == 5
    assert envkeep.texel_stats(frozen.copy()) == (0, True, True) and len(scans) == 6
    dark = np.zeros_like(frozen)
    dark.flags.writeable = False
    assert envkeep.texel_stats(dark) == (0, False, False) and not envkeep.any_positive(_env(dark))
    assert len(scans) == 7
