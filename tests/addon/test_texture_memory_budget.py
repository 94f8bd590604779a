"""An image file whose texels do not fit in the memory available is refused before it is read,
named with its size and the memory it needs (magenta there, the rest rendered): Linux's
overcommit grants the read's arrays and the kernel kills Blender as they fill. A file's header
can claim texels that were never written (one of 30000 x 30000 had been given a 3.4 GB array,
granted by the overcommit, and read until its data ran out: 'could not be read')."""
import struct
import zlib

import numpy as np

from addon.export import budget

from . import scenes


def _emitting_image(scene, path):
    """An 8x6, 1-sample view of a plane emitting an Image Texture of the file at `path` (black
    world): each pixel is a texel's colour."""
    import bpy
    mat, nt, _, out = scenes.small_view(scene, size=(8, 6), eye=(0, 0, 5), background=None)
    em, tex = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.load(str(path))
    tex.image.name = 'Big'
    nt.links.new(tex.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))
    return scenes.render_rgba(scene)


def test_an_image_that_cannot_fit_is_refused_naming_its_size(scene, monkeypatch, said, tmp_path):
    """A 64 x 64 8-bit sRGB file with one texel fewer bytes available than its read needs: magenta
    and named; with its need available it is read (its grey)."""
    px = np.full((64, 64, 4), 128, np.uint8)
    px[..., 3] = 255
    path = scenes.write_image(tmp_path / "grey.png", px)
    need = budget.texture_bytes(64 * 64, True, 'srgb')
    assert need == 64 * 64 * budget.TEXEL_BYTES[True, 'srgb'] > budget.film_bytes(8 * 6, 0)
    monkeypatch.setattr(budget, 'available_bytes', lambda: need - 1)
    img = _emitting_image(scene, path)
    np.testing.assert_allclose(img[..., :3], np.broadcast_to([1.0, 0.0, 1.0], img[..., :3].shape))
    text = " | ".join(said)
    assert f"image 'Big': its file {path} holds 64 x 64 texels, which need about 68 KB to read, more than the " \
           f"68 KB of memory available; not read (magenta)" in text, text
    assert "could not be read" not in text
    said.clear()
    monkeypatch.setattr(budget, 'available_bytes', lambda: need)
    img = _emitting_image(scene, path)
    np.testing.assert_allclose(img[..., :3], 0.2158605, atol=1e-5)     # sRGB 128 / 255 decoded
    assert "memory available" not in " | ".join(said)


def _png_header_only(path, width, height):
    """A PNG whose header claims width x height 8-bit RGBA texels, one compressed row of data
    following, no more, after 2 MB of an ancillary chunk (OpenImageIO refuses a header claiming
    over ~1000x its file's size as corrupt: 3433 MB from 100 KB; from 1 MB it opens)."""
    def chunk(kind, data):
        return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data))
    row = zlib.compress(b'\x00' * (1 + 4 * width))
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 6, 0, 0, 0)) +
                chunk(b'zzZz', bytes(2 * 2**20)) + chunk(b'IDAT', row) + chunk(b'IEND', b''))
    return path


def test_a_file_claiming_dimensions_beyond_the_memory_is_refused_before_it_is_read(scene, monkeypatch, said,
                                                                                    tmp_path):
    """A header claiming 30000 x 30000 8-bit texels (3.4 GB as bytes: under OpenImageIO's own limit,
    the machine's memory, so it opens) with 8 GB available: it needs about 14 GB, so it is refused
    before any array is made, and not said to be damaged (it had been allocated, 3.6 GB granted
    by the overcommit, and read until its data ran out: 'could not be read')."""
    path = _png_header_only(tmp_path / "claims.png", 30000, 30000)
    monkeypatch.setattr(budget, 'available_bytes', lambda: 8 * 2**30)
    img = _emitting_image(scene, path)
    np.testing.assert_allclose(img[..., :3], np.broadcast_to([1.0, 0.0, 1.0], img[..., :3].shape))
    text = " | ".join(said)
    assert f"its file {path} holds 30000 x 30000 texels, which need about 14.2 GB to read, more than the 8.0 GB " \
           f"of memory available; not read (magenta)" in text, text
    assert "could not be read" not in text
