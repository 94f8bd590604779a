"""How an export reads images (its cancel check, Cycles' Texture Limit) comes with each read as an
export/images.ImageReading, not from module globals the running export set and reset: two
exports' reads do not see each other's, and a read outside an export is whole and uncancelled
whatever an export left behind (what outlives an export: test_export_lifetime.py)."""
import numpy as np
import pytest

from addon.export import images
from addon.export.errors import ExportCancelled

from . import scenes


def test_each_read_has_its_own_texture_limit_and_cancel_check():
    px = np.random.default_rng(3).random((64, 32, 4)).astype(np.float32)
    img = scenes.float_image("Limited", px)
    limited = images.ImageReading(texture_limit=16)          # (64 -> 16: 4 x 4 blocks)
    small = np.asarray(images.image_pixels(img, [], reading=limited))
    whole = np.asarray(images.image_pixels(img, []))
    again = np.asarray(images.image_pixels(img, [], reading=limited))
    assert whole.shape == (64, 32, 4) and small.shape == again.shape == (16, 8, 4)
    np.testing.assert_array_equal(whole, px)
    np.testing.assert_array_equal(small, again)
    # a block's mean, as Cycles' box filter (images.downscaled) makes it
    np.testing.assert_allclose(small[0, 0], px[:4, :4].mean(axis=(0, 1)), rtol=1e-5)
    cancelled = images.ImageReading(check_break=lambda: True)
    with pytest.raises(ExportCancelled):
        images.image_pixels(img, [], reading=cancelled)
    np.testing.assert_array_equal(np.asarray(images.image_pixels(img, [])), px)   # nothing left behind

