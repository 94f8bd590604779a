"""Cycles' Simplify > Texture Limit halves an image bigger than the limit until it fits, each
texel the mean of its k x k block (util_image_resize_pixels) of the texels as Cycles stores
them; a float image (its floats) and an 8-bit one (its bytes, the mean rounded back to a byte)
are now downscaled so too, where DACRT had rendered them at full size (a 512 texel-noise image
at limit 128: Cycles' per-pixel spread 0.046, DACRT's 0.184). Texel noise on a sunlit plane
filling an orthographic view, Closest lookups, a pixel per downscaled texel: every pixel against
Cycles' (but where a byte mean lies on a half-byte boundary, which Cycles' build can round the
other way: a 4x4 block's, ~0.7% of texels one byte off). An image thinner than the factor keeps
one row, the mean of the rows it has."""
import bpy
import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 128                       # a pixel per downscaled texel


def _png(path, k8):
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(k8.shape[1], k8.shape[0], 4, oiio.UINT8))
    out.write_image(np.ascontiguousarray(k8[::-1]))
    out.close()
    return bpy.data.images.load(str(path))


@pytest.mark.parametrize('shape, kind', [((256, 256), 'float'), ((2, 1024), 'float'), ((256, 256), 'sRGB bytes'),
                                         ((512, 256), 'Non-Color bytes')],
                         ids=['float', 'float-thin', 'srgb-bytes', 'data-bytes'])
def test_image_renders_at_cycles_texture_limit_size(shape, kind, tmp_path):
    rng = np.random.default_rng(7)
    px = np.ones(shape + (4,), np.float32)
    px[..., :3] = rng.random(shape + (3,), np.float32)
    k8 = rng.integers(0, 256, shape + (4,)).astype(np.uint8)      # alpha too: associated bytes

    def wire(nt, tex, diffuse):
        if kind != 'float':
            tex.image = _png(tmp_path / "noise.png", k8)
            tex.image.colorspace_settings.name = kind.split()[0]
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])
    sunplane.build(px, wire, RES, 4)
    sc = bpy.context.scene
    sc.render.use_simplify = True
    sc.cycles.texture_limit_render = '128'
    cycles, dacrt = (sunplane.render_rgb(e, tmp_path) for e in ('CYCLES', 'DACRT'))
    if kind == 'float':                  # Cycles' texels are block means: less spread than the image's
        assert cycles.std() / cycles.mean() < 0.75 * px[..., :3].std() / px[..., :3].mean()
    if shape[0] < shape[1] // 128:
        assert (np.ptp(cycles, axis=0) < 1e-5).all()          # one row of texels
    # each pixel its texel's value (a sample on a texel's edge may pick its neighbour: a few;
    # a byte mean on a half-byte boundary may round the other way than Cycles' build: one byte)
    off = np.abs(dacrt - cycles).max(axis=-1) > 2e-4 * cycles.max(axis=-1) + 1e-6
    assert off.mean() < (0.002 if kind in ('float', 'sRGB bytes') else 0.01), \
        f"{off.sum()} of {off.size} pixels off Cycles'"
