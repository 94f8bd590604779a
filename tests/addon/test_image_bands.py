"""Image files read band by band (export/images.py _read_flipped): each band of rows is flipped
into place as it is read, so no whole-image copy is made and the cancel check runs between
bands. The texels must be exactly what reading the whole file at once and flipping it gives,
for scanline and tiled files whose height is not a multiple of the band, data windows that do
not start at 0, every channel count and byte and deeper formats; checked against OpenImageIO's
ImageBuf read of the whole image, an independent path."""
import OpenImageIO as oiio
import numpy as np
import pytest

from addon.export import images
from addon.export.errors import ExportCancelled


def _write(path, pixels, fmt, tile=0, origin=(0, 0)):
    h, w, ch = pixels.shape
    spec = oiio.ImageSpec(w, h, ch, fmt)
    spec.attribute('oiio:UnassociatedAlpha', 1)     # alpha straight, as given
    spec.x, spec.y = origin
    if origin != (0, 0):     # the display window stays at 0: the data window is offset
        spec.full_x = spec.full_y = 0
        spec.full_width, spec.full_height = w + origin[0], h + origin[1]
    if tile:
        spec.tile_width = spec.tile_height = tile
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), oiio.geterror()
    assert out.write_image(pixels), out.geterror()
    out.close()


def _whole_flipped(path, byte):
    """The reference: the whole file through ImageBuf, flipped, as bytes or as float RGBA."""
    straight = oiio.ImageSpec()
    straight.attribute('oiio:UnassociatedAlpha', 1)
    buf = oiio.ImageBuf(str(path), 0, 0, straight)
    spec = buf.spec()
    raw = np.asarray(buf.get_pixels(oiio.UINT8 if byte else oiio.FLOAT)).reshape(spec.height, spec.width, -1)[::-1]
    if byte:
        return raw
    ch = raw.shape[2]
    rgba = np.ones(raw.shape[:2] + (4,), np.float32)
    if ch >= 3:
        rgba[..., :min(ch, 4)] = raw[..., :4]
    else:
        rgba[..., :3] = raw[..., :1]
        if ch == 2:
            rgba[..., 3] = raw[..., 1]
    return rgba


def _read(path, byte, alpha_one=False, reading=images.WHOLE):
    inp, spec = images._open_straight(str(path))
    assert spec is not None
    try:
        return images._read_flipped(inp, spec, byte, alpha_one, reading=reading)
    finally:
        inp.close()


@pytest.mark.parametrize('channels', [1, 2, 3, 4, 5])
@pytest.mark.parametrize('tile', [0, 64])
@pytest.mark.parametrize('fmt', ['float', 'half'])
def test_float_files_read_in_bands_equal_the_whole_read(tmp_path, channels, tile, fmt):
    rng = np.random.default_rng(channels + tile)
    h, w = images._BAND_ROWS * 2 + 37, 45      # three bands, the last one short
    pixels = rng.uniform(-2, 40, (h, w, channels)).astype(np.float32)
    path = tmp_path / "t.exr"
    _write(path, pixels, oiio.FLOAT if fmt == 'float' else oiio.HALF, tile)
    got = _read(path, byte=False)
    want = _whole_flipped(path, byte=False)
    assert got.shape == (h, w, 4) and got.dtype == np.float32
    np.testing.assert_array_equal(got, want)
    if fmt == 'float' and channels >= 3:       # and the file's own values, row 0 at the bottom
        np.testing.assert_array_equal(got[..., :min(channels, 4)], pixels[::-1, :, :4])


@pytest.mark.parametrize('tile', [0, 32])
def test_data_window_not_at_the_origin(tmp_path, tile):
    rng = np.random.default_rng(3)
    pixels = rng.uniform(0, 1, (300, 20, 4)).astype(np.float32)
    path = tmp_path / "w.exr"
    _write(path, pixels, oiio.FLOAT, tile, origin=(5, 9))
    np.testing.assert_array_equal(_read(path, byte=False), pixels[::-1])


@pytest.mark.parametrize('channels', [1, 2, 3, 4])
def test_byte_and_16_bit_files(tmp_path, channels):
    rng = np.random.default_rng(channels)
    h, w = images._BAND_ROWS + 3, 17
    b8 = rng.integers(0, 256, (h, w, channels), dtype=np.uint8)
    _write(tmp_path / "b.png", b8, oiio.UINT8)
    got = _read(tmp_path / "b.png", byte=True)
    assert got.dtype == np.uint8 and got.shape == (h, w, channels)
    np.testing.assert_array_equal(got, b8[::-1])
    b16 = rng.integers(0, 65536, (h, w, channels), dtype=np.uint16)
    _write(tmp_path / "c.png", b16, oiio.UINT16)
    np.testing.assert_array_equal(_read(tmp_path / "c.png", byte=False), _whole_flipped(tmp_path / "c.png", False))


@pytest.mark.parametrize('channels', [2, 4])
def test_alpha_ignored_is_one(tmp_path, channels):
    pixels = np.full((40, 8, channels), 0.25, np.float32)
    _write(tmp_path / "a.exr", pixels, oiio.FLOAT)
    got = _read(tmp_path / "a.exr", byte=False, alpha_one=True)
    assert (got[..., 3] == 1).all() and (got[..., :3] == 0.25).all()
    _write(tmp_path / "a.png", np.full((40, 8, channels), 64, np.uint8), oiio.UINT8)
    got = _read(tmp_path / "a.png", byte=True, alpha_one=True)
    assert (got[..., channels - 1] == 255).all() and (got[..., 0] == 64).all()


def test_cancel_between_bands(tmp_path):
    """Esc during a big file's read stops at the next band, not after the whole file."""
    _write(tmp_path / "big.exr", np.zeros((images._BAND_ROWS * 4, 8, 3), np.float32), oiio.FLOAT)
    calls = []

    def check():
        calls.append(1)
        return len(calls) >= 2          # cancelled while the first band is read

    with pytest.raises(ExportCancelled):
        _read(tmp_path / "big.exr", byte=False, reading=images.ImageReading(check_break=check))
    assert len(calls) == 2


def test_a_truncated_file_reads_as_none(tmp_path):
    path = tmp_path / "cut.exr"
    _write(path, np.ones((images._BAND_ROWS * 3, 64, 3), np.float32), oiio.FLOAT)
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    inp, spec = images._open_straight(str(path))
    assert spec is not None         # the header is whole: the read of the missing bands fails
    try:
        assert images._read_flipped(inp, spec, False, False) is None
    finally:
        inp.close()
