"""Cycles' Simplify > Texture Limit halves an image bigger than the limit until it fits, each
texel the mean of its k x k block (util_image_resize_pixels); a float image is now downscaled so
too, where DACRT had rendered it at full size (a 512 texel-noise image at limit 128: Cycles'
per-pixel spread 0.046, DACRT's 0.184). Float texel noise on a sunlit plane filling an
orthographic view, Closest lookups, a pixel per downscaled texel: every pixel against Cycles'.
An image thinner than the factor keeps one row, the mean of the rows it has."""
import bpy
import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 128                       # a pixel per downscaled texel


@pytest.mark.parametrize('shape, limit', [((256, 256), '128'), ((2, 1024), '128')], ids=['square', 'thin'])
def test_float_image_renders_at_cycles_texture_limit_size(shape, limit, tmp_path):
    rng = np.random.default_rng(7)
    px = np.ones(shape + (4,), np.float32)
    px[..., :3] = rng.random(shape + (3,), np.float32)

    def wire(nt, tex, diffuse):
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])
    sunplane.build(px, wire, RES, 4)
    sc = bpy.context.scene
    sc.render.use_simplify = True
    sc.cycles.texture_limit_render = limit
    cycles, dacrt = (sunplane.render_rgb(e, tmp_path) for e in ('CYCLES', 'DACRT'))
    k = shape[1] // 128                   # (width 1024 -> 128 columns, 2 rows -> 1)
    assert cycles.std() < 0.9 * px[..., :3].std() * cycles.mean() / px[..., :3].mean()   # averaged
    if shape[0] < k:
        assert (np.ptp(cycles, axis=0) < 1e-5).all()          # one row of texels
    # each pixel its texel's value (a sample on a texel's edge may pick its neighbour: a few)
    off = np.abs(dacrt - cycles).max(axis=-1) > 2e-4 * cycles.max(axis=-1) + 1e-6
    assert off.mean() < 0.002, f"{off.sum()} of {off.size} pixels off Cycles'"
