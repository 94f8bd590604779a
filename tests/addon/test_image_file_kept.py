"""A float image file read again, unchanged and with the same settings, is not read again
(export/readkeep.py): frames of a 4K EXR HDRI had read it every frame (~0.63 s of a ~0.72 s
frame). Any change of what the read depends on (the file rewritten, replaced or touched, the
image pointed at another file, a sequence's frame, its name, alpha mode, colour space, Non-Color
flag, the lookup's unassociation) reads it again and gives exactly what a read with nothing kept
gives; the Texture Limit, applied after, too. Kept texels are read-only, and the kept bytes are
bounded."""
import math
import os

import dacrt
import numpy as np
import pytest

from addon.export import images, readkeep
from addon.lights import envkeep

from . import scenes
from .test_environment_map_kept import _hdri_world


@pytest.fixture(autouse=True)
def nothing_kept():
    readkeep.forget()
    envkeep.forget()
    yield
    readkeep.forget()
    envkeep.forget()


def _texels(seed=3, h=32, w=64):
    rng = np.random.default_rng(seed)
    px = np.empty((h, w, 4), np.float32)
    px[..., :3] = (rng.random((h, w, 3)) ** 3 * 4).astype(np.float32)
    px[..., 3] = rng.random((h, w)).astype(np.float32) * 0.8 + 0.1     # (alpha settings change the texels)
    return px


def test_frames_of_an_unchanged_hdri_file_read_it_once(scene, tmp_path, monkeypatch, calls_to):
    scenes.write_exr(tmp_path / 'sky.exr', _texels())
    _hdri_world(scene, scenes.bpy.data.images.load(str(tmp_path / 'sky.exr')))
    reads = calls_to(images, '_read_flipped')
    builds = calls_to(dacrt.lamps, 'environment_map')
    films = scenes.frame_films(scene)
    assert len(reads) == 1, reads
    assert len(builds) == 1, builds          # (envkeep reuses the map of the kept, read-only texels)
    readkeep.forget()
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert all(np.array_equal(f, fresh) for f in films)


def _hdri_frames(scene, tmp_path, px, frames=(1, 2, 3)):
    """Films of frames of a sphere under an HDRI world read from an EXR of px."""
    scenes.write_exr(tmp_path / 'sky.exr', px)
    _hdri_world(scene, scenes.bpy.data.images.load(str(tmp_path / 'sky.exr')))
    return scenes.frame_films(scene, frames)


def test_what_the_check_finds_in_kept_texels_is_said_every_frame(scene, tmp_path, said):
    px = _texels()
    px[3, 5, 1] = np.nan
    px[7, 9, 0] = -2.0
    films = _hdri_frames(scene, tmp_path, px)
    for what in ("1 pixel(s) not finite", "negative values rendered as 0"):
        assert sum(what in t for t in said) == 3, (what, said)
    readkeep.forget()
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert all(np.array_equal(f, fresh) for f in films)


def _bytes(seed):
    rng = np.random.default_rng(seed)
    return (rng.random((32, 64, 4)) * 255).astype(np.uint8)


@pytest.mark.parametrize("alpha", ['STRAIGHT', 'NONE'])
def test_frames_of_an_unchanged_8bit_file_decode_it_once(scene, tmp_path, calls_to, alpha):
    """An 8-bit file's decoded bytes are kept for the next frame with the same key (a 4K x 2K
    PNG world: ~280 ms of a ~370 ms frame's CPU decoding it every frame); each frame converts a
    copy, so what it renders is what a frame with nothing kept renders. A rewritten file is
    decoded again."""
    path = scenes.write_image(tmp_path / 'sky.png', _bytes(3))
    image = scenes.bpy.data.images.load(path)
    image.alpha_mode = alpha
    scenes.camera(location=(0, -5, 0), rotation=(math.radians(90), 0, 0))
    scenes.uv_sphere(materials=[scenes.diffuse('grey', (0.5, 0.5, 0.5))])
    scenes.environment_world(image, strength=1.0, rotation=(0.0, 0.0, 0.3))
    scene.dacrt.samples, scene.dacrt.max_bounces = 1, 2
    reads = calls_to(images, '_read_flipped')
    films = scenes.frame_films(scene)
    assert len(reads) == 1, reads
    readkeep.forget()
    envkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert all(np.array_equal(f, fresh) for f in films)
    scenes.write_image(tmp_path / 'sky.png', _bytes(4))
    image.reload()
    reads.clear()
    again = scenes.render_rgba(scene)
    assert len(reads) == 1
    readkeep.forget()
    envkeep.forget()
    assert np.array_equal(again, scenes.render_rgba(scene)) and not np.array_equal(again, fresh)


def _stored(t):
    s = getattr(t, 'stored', None)
    return None if s is None else (np.asarray(s.texels), s.srgb, s.unassociate, float(s.scale))


def _same(a, b):
    sa, sb = _stored(a), _stored(b)
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True) and (sa is None) == (sb is None) and (
        sa is None or (np.array_equal(sa[0], sb[0], equal_nan=True) and sa[1:] == sb[1:]))


def _rewrite(img, path, tmp_path):
    scenes.write_exr(path, _texels(seed=4))


def _replace(img, path, tmp_path):      # (a new inode: written beside and renamed over it)
    scenes.write_exr(tmp_path / 'new.exr', _texels(seed=5))
    os.replace(tmp_path / 'new.exr', path)


def _touch(img, path, tmp_path):        # (the same bytes, a later mtime: read again all the same)
    st = os.stat(path)
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000_000))


def _other_file(img, path, tmp_path):
    scenes.write_exr(tmp_path / 'other.exr', _texels(seed=6))
    img.filepath = str(tmp_path / 'other.exr')


CHANGES = {
    'rewritten': _rewrite,
    'replaced': _replace,
    'touched': _touch,
    'other file': _other_file,
    'name': lambda img, path, tmp_path: setattr(img, 'name', 'renamed'),
    'alpha mode': lambda img, path, tmp_path: setattr(img, 'alpha_mode', 'NONE'),
    'colour space': lambda img, path, tmp_path: setattr(img.colorspace_settings, 'name', 'sRGB'),
    'non-color': lambda img, path, tmp_path: setattr(img.colorspace_settings, 'is_data', True),
    'unassociate': None,
}


@pytest.mark.parametrize('change', CHANGES)
def test_a_change_of_what_the_read_depends_on_reads_again_as_with_nothing_kept(tmp_path, monkeypatch, change, calls_to):
    path = tmp_path / 'tex.exr'
    scenes.write_exr(path, _texels())
    img = scenes.bpy.data.images.load(str(path))
    if change == 'non-color':        # (from sRGB: a linear EXR's texels are the same as data)
        img.colorspace_settings.name = 'sRGB'
    reads = calls_to(images, '_read_flipped')
    before = images.image_pixels(img, [])
    assert _same(images.image_pixels(img, []), before) and len(reads) == 1      # (kept)
    unassociate = change == 'unassociate'
    if not unassociate:
        CHANGES[change](img, str(path), tmp_path)
    after = images.image_pixels(img, [], unassociate)
    assert len(reads) == 2
    readkeep.forget()
    fresh = images.image_pixels(img, [], unassociate)
    assert _same(after, fresh)
    if change not in ('touched', 'name'):
        assert not _same(before, fresh)          # (the change shows in the texels)


def test_the_texture_limit_applies_to_kept_texels_as_to_read_ones(tmp_path):
    scenes.write_exr(tmp_path / 'tex.exr', _texels())
    img = scenes.bpy.data.images.load(str(tmp_path / 'tex.exr'))
    whole = images.image_pixels(img, [])
    limited = images.ImageReading(texture_limit=16)
    kept = images.image_pixels(img, [], reading=limited)
    readkeep.forget()
    fresh = images.image_pixels(img, [], reading=limited)
    assert kept.shape == (8, 16, 4) and np.array_equal(kept, fresh) and not np.array_equal(whole[:8, :16], fresh)


def test_each_frame_of_a_sequence_is_its_own_file(tmp_path, monkeypatch, calls_to):
    for frame, seed in ((1, 7), (2, 8)):
        scenes.write_exr(tmp_path / f'sky_{frame:03d}.exr', _texels(seed))
    img = scenes.bpy.data.images.load(str(tmp_path / 'sky_001.exr'))
    img.source = 'SEQUENCE'
    user = type('User', (), dict(frame_duration=2, frame_start=1, use_cyclic=False, frame_offset=0))()
    reads = calls_to(images, '_read_flipped')
    one, two, one_again = (images.image_pixels(img, [], user=user, frame=f) for f in (1, 2, 1))
    assert len(reads) == 2 and not _same(one, two) and one_again is one
    readkeep.forget()
    assert _same(two, images.image_pixels(img, [], user=user, frame=2))


def test_kept_texels_are_read_only(tmp_path):
    scenes.write_exr(tmp_path / 'tex.exr', _texels())
    img = scenes.bpy.data.images.load(str(tmp_path / 'tex.exr'))
    img.colorspace_settings.name = 'sRGB'        # (a stored sRGB copy beside the linear texels)
    texels = images.image_pixels(img, [])
    assert texels.stored is not None
    for a in (texels, texels.stored.texels, np.asarray(texels)):
        with pytest.raises(ValueError):
            a[0, 0, 0] = 1.0


def test_the_kept_bytes_are_bounded(tmp_path, monkeypatch, calls_to):
    one = _texels().nbytes
    monkeypatch.setattr(readkeep, '_KEEP_BYTES', 2 * one)
    imgs = []
    for name in 'abc':
        scenes.write_exr(tmp_path / f'{name}.exr', _texels())
        imgs.append(scenes.bpy.data.images.load(str(tmp_path / f'{name}.exr')))
    reads = calls_to(images, '_read_flipped')
    for img in imgs:
        images.image_pixels(img, [])
    assert len(readkeep._kept) == 2 and sum(e[2] for e in readkeep._kept.values()) <= 2 * one
    images.image_pixels(imgs[2], [])              # (the latest two kept, the first dropped)
    images.image_pixels(imgs[1], [])
    assert len(reads) == 3
    images.image_pixels(imgs[0], [])
    assert len(reads) == 4
    monkeypatch.setattr(readkeep, '_KEEP_BYTES', one - 1)     # (an image above the bound: never kept)
    readkeep.forget()
    images.image_pixels(imgs[0], [])
    images.image_pixels(imgs[0], [])
    assert len(reads) == 6 and not readkeep._kept


@pytest.mark.parametrize('space, alpha_linked, png', [('Linear Rec.709', False, False), ('sRGB', True, False),
                                                      ('sRGB', True, True), ('Non-Color', False, True)])
def test_a_material_texture_of_a_kept_file_renders_as_with_nothing_kept(scene, tmp_path, space, alpha_linked, png,
                                                                        calls_to):
    """The kept, read-only texels (and their stored lookup copy: sRGB, unassociated), or an 8-bit
    file's kept bytes, go through the material's image texture as a fresh read's do."""
    if png:
        path = scenes.write_image(tmp_path / 'tex.png', _bytes(6))
    else:
        scenes.write_exr(tmp_path / 'tex.exr', _texels())
        path = str(tmp_path / 'tex.exr')
    img = scenes.bpy.data.images.load(path)
    img.colorspace_settings.name = space
    mat, nt, out = scenes._material('textured')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(tex.outputs['Color'], em.inputs['Color'])
    if alpha_linked:
        nt.links.new(tex.outputs['Alpha'], em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.camera(location=(0, 0, 3))
    scenes.plane(materials=[mat])
    scenes.black_world()
    scene.dacrt.samples = 1
    reads = calls_to(images, '_read_flipped')
    first, second = scenes.render_rgba(scene), scenes.render_rgba(scene)
    assert len(reads) == 1
    readkeep.forget()
    fresh = scenes.render_rgba(scene)
    assert np.array_equal(first, fresh) and np.array_equal(second, fresh) and fresh[..., :3].max() > 0.1
