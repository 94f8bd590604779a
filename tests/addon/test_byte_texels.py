"""8-bit images kept as their bytes end to end (texture.ByteTexels): Cycles keeps 4 bytes a
texel, and the export had held each 8-bit image as (h, w, 4) float32 scene-linear texels as
well (an 8K PNG: 1 GB, plus a float64 copy of its colour in the node evaluation (1.6 GB), a
finiteness mask and a float64 mean: 4.8 GB of RSS growth and 21-46 s for an 8K PNG into an
Emission, 0.5 GB and 1.8 s now). The renderer reads the bytes as Cycles stores them; the
scene-linear floats (colour nodes, averages) are a 256-entry table of the bytes, made only if
something reads them, and equal, bit for bit, to what the float path computes (images.py
_linear_rgba without `lazy`). Float images, UDIM tiles, converted colour spaces and a linked
Alpha's division keep the float path."""
import bpy
import dacrt
import numpy as np
import pytest

from addon import export
from addon.export import images
from addon.texture import ByteTexels, LazyTexels, mean_rgb, stored_texels

from . import scenes


def _pixels(h, w, ch, seed=0):
    """(h, w, ch) uint8 with every byte value in each channel, and alpha 0 and 255 among them."""
    rng = np.random.default_rng(seed)
    px = rng.integers(0, 256, (h, w, ch), dtype=np.uint8)
    k = min(256, h * w)
    px.reshape(-1, ch)[:k] = np.arange(k, dtype=np.uint8)[:, None]
    return px


def _material(img, link='diffuse', alpha_linked=False, strength=1.0):
    mat, nt, out = scenes._material("M " + img.name)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    if link == 'emission':
        node = nt.nodes.new('ShaderNodeEmission')
        node.inputs['Strength'].default_value = strength
    else:
        node = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(tex.outputs['Color'], node.inputs['Color'])
    if alpha_linked:
        nt.links.new(tex.outputs['Alpha'], node.inputs['Roughness' if link == 'diffuse' else 'Strength'])
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    builder = export.materials.MaterialBuilder()
    return builder.materials[builder.index(mat)]


def _float_path(img, unassociate=False):
    """The texels as the float path makes them (lazy off), from the image's file bytes."""
    path = bpy.path.abspath(img.filepath_raw)
    inp, spec = images._open_straight(path)
    raw = images._read_flipped(inp, spec, True, alpha_one=img.alpha_mode == 'NONE')
    inp.close()
    return np.asarray(images._linear_rgba(raw, img, [], unassociate, byte=True, encoded=True,
                                          channels=spec.nchannels))


@pytest.mark.parametrize('link', ['diffuse', 'emission'])
def test_8bit_png_into_a_closure_holds_no_floats(tmp_path, link):
    img = bpy.data.images.load(scenes.write_image(tmp_path / "c.png", _pixels(40, 24, 3), 'uint8'))
    m = _material(img, link, strength=2.0)
    tex = m.texture if link == 'diffuse' else m.emission_texture
    source = tex if link == 'diffuse' else None
    # the renderer's texels: the bytes as Cycles stores them
    stored = stored_texels(tex)
    assert stored is not None and stored.texels.dtype == np.uint8, type(tex)
    # no float texels were made: the image's own (diffuse) or the strength baked in (emission)
    assert isinstance(tex, LazyTexels) and not tex.made, type(tex)
    if source is not None:
        assert isinstance(source, ByteTexels)
        np.testing.assert_array_equal(np.asarray(source), _float_path(img))
    assert not m.approximated


@pytest.mark.parametrize('ch', [1, 2, 3, 4])
@pytest.mark.parametrize('space', ['sRGB', 'Non-Color', 'Linear Rec.709'])
def test_texels_made_from_bytes_equal_the_float_path(tmp_path, ch, space):
    img = bpy.data.images.load(scenes.write_image(tmp_path / f"b{ch}.png", _pixels(33, 17, ch, ch), 'uint8'))
    img.colorspace_settings.name = space
    notes = []
    px = images.image_pixels(img, notes)
    assert isinstance(px, ByteTexels) and not px.made
    want = _float_path(img)
    np.testing.assert_allclose(mean_rgb(px), want[..., :3].astype(np.float64).reshape(-1, 3).mean(0),
                               rtol=1e-14, atol=0)
    assert not px.made                  # the mean came from the bytes
    np.testing.assert_array_equal(np.asarray(px), want)
    assert px.dtype == np.float32 and px.shape == want.shape


@pytest.mark.parametrize('ch', [3, 4])
def test_packed_image_from_blenders_floats(tmp_path, ch):
    """A packed 8-bit image comes from Blender's float buffer (its bytes' floats): bytes too."""
    img = bpy.data.images.load(scenes.write_image(tmp_path / f"p{ch}.png", _pixels(21, 30, ch, 7), 'uint8'))
    img.pack()
    buf = np.empty(img.size[0] * img.size[1] * img.channels, np.float32)
    img.pixels.foreach_get(buf)
    want = np.asarray(images._linear_rgba(buf.reshape(img.size[1], img.size[0], img.channels), img, [], False,
                                          byte=True, encoded=False, from_file=False))
    px = images.image_pixels(img, [])
    assert isinstance(px, ByteTexels) and not px.made
    np.testing.assert_array_equal(np.asarray(px), want)


def test_linked_alpha_and_float_images_keep_the_float_path(tmp_path):
    """An associated image whose Alpha output is linked is divided per texel: floats, as before;
    so is a float image."""
    img = bpy.data.images.load(scenes.write_image(tmp_path / "a.png", _pixels(20, 14, 4, 3), 'uint8'))
    px = images.image_pixels(img, [], unassociate=True)
    assert not isinstance(px, LazyTexels)
    np.testing.assert_array_equal(np.asarray(px), _float_path(img, unassociate=True))
    f = scenes.float_image("F", np.random.default_rng(1).uniform(0, 2, (6, 5, 4)).astype(np.float32))
    assert not isinstance(images.image_pixels(f, []), LazyTexels)


def test_native_bytes_without_floats():
    buf = _pixels(20, 13, 4, 5)
    table = np.arange(256, dtype=np.float32) * np.float32(1 / 255)
    rgba, straight, assoc, exact = dacrt.shading.byte_texels(buf, table, True)
    none, straight2, assoc2, exact2 = dacrt.shading.byte_texels(buf, table, True, floats=False)
    assert none is None and exact2
    np.testing.assert_array_equal(straight, straight2)
    np.testing.assert_array_equal(assoc, assoc2)
    floats = (buf.astype(np.float32) / 255).astype(np.float32)
    _, s3, a3, e3 = dacrt.shading.byte_texels(floats, table, True, floats=False)
    np.testing.assert_array_equal(s3, straight)


@pytest.mark.parametrize('alpha_one', [False, True])
@pytest.mark.parametrize('ch', [1, 2, 3, 4])
def test_file_read_expanded_is_the_expanded_bytes(tmp_path, ch, alpha_one):
    """A byte file read straight into RGBA bytes (no second whole-image array): what
    byte_texels expands its bytes to (grey replicated, alpha 255 where it has none)."""
    path = scenes.write_image(tmp_path / f"e{ch}.png", _pixels(300, 9, ch, 11), 'uint8')
    reads = []
    for expand in (False, True):
        inp, spec = images._open_straight(path)
        reads.append(images._read_flipped(inp, spec, True, alpha_one, expand=expand))
        inp.close()
    raw, expanded = reads
    assert expanded.shape == raw.shape[:2] + (4,) and expanded.dtype == np.uint8
    table = np.arange(256, dtype=np.float32) * np.float32(1 / 255)
    np.testing.assert_array_equal(expanded, dacrt.shading.byte_texels(raw, table, False, floats=False)[1])


def _bright_reference(k8, table):
    """ByteTexels.any_positive_rgb as it was (every texel's RGB bytes looked up in the table)."""
    return bool((np.asarray(table, np.float32)[k8[..., :3]] > 0).any())


def test_the_bright_check_of_bytes_is_the_lookup_of_every_rgb_byte():
    """ByteTexels.any_positive_rgb (the world light's bright check, read from the bytes) against
    the table lookup of every RGB byte: random images, one lit byte at the first or last texel
    in each channel, only alpha set, and tables whose first lit byte is 0, 1, or later, or with
    gaps; bands of 64 rows end inside the image or exactly at it."""
    from addon.texture import ByteTexels
    rng = np.random.default_rng(11)
    ramp = np.arange(256, dtype=np.float32) / 255
    tables = [ramp, ramp + 0.1, np.where(ramp > 0.5, ramp, 0), np.where(np.arange(256) % 7 == 3, ramp, 0),
              np.zeros(256, np.float32)]
    images = []
    for h, w in ((1, 1), (3, 5), (64, 3), (130, 7)):
        images.append((rng.random((h, w, 4)) * 256).astype(np.uint8))
        dark = np.zeros((h, w, 4), np.uint8)
        images.append(dark)
        alpha_only = dark.copy()
        alpha_only[..., 3] = 255
        images.append(alpha_only)
        for y, x in ((0, 0), (h - 1, w - 1)):
            for c in range(3):
                for v in (1, 4, 200):
                    one = alpha_only.copy()
                    one[y, x, c] = v
                    images.append(one)
    for table in tables:
        for k8 in images:
            got = ByteTexels(k8, table, np.ones(256, np.float32), None).any_positive_rgb()
            assert got == _bright_reference(k8, table), (k8.shape, table[:3])
