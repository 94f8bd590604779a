"""'Linear' image lookups agree with Cycles and with the closed form: Cycles keeps an sRGB image
in its encoding (8-bit and 16-bit files, byte images; ImageMetaData::detect_colorspace's
compress_as_srgb), blends the stored texels and decodes after the blend (svm_image_texture),
and so does DACRT (addon/texture.py EncodedTexels).

A two-texel-wide image (texels a, b per channel; REPEAT) magnified across an orthographic view
blends to a + (b - a) t between the texel centres, so a pixel column covering u in [u0, u1]
averages decode(blend(u)) over that range: a closed form (integrated here on a fine grid). Both
engines' 4-column blocks must match it within 0.2% of the brightest block (measured at 64 spp,
Cycles without denoising: DACRT within 0.01%, Cycles 0.05%); blending decoded texels instead,
as DACRT did, is 32% off (16% with the alpha below; 0/255 stripes: 0.5 against 0.214 at the
midpoint). Cases: an 8-bit PNG file, a 16-bit one, an 8-bit one with alpha (colour associated
in bytes before the blend), and an 8-bit Environment Texture seen whole by an equirectangular
camera: the image mean is the closed form's over u (within 0.01% for both; 16-54% off per
channel for blended decoded texels), and the engines' columns agree within 0.02%."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

WIDTH, HEIGHT, BLOCK = 64, 4, 4
SAMPLES = 64
K = 2.0 / np.pi                  # the sun's E / pi (sunplane: strength 2, straight down)
TEXELS = np.array([[[0, 64, 255, 255], [255, 200, 30, 255]]], np.uint8)   # (1, 2, 4) bytes, a and b


def decode(c):
    c = np.asarray(c, np.float64)
    return np.where(c < 0.04045, np.maximum(c / 12.92, 0.0), ((np.maximum(c, 0) + 0.055) / 1.055) ** 2.4)


def blend(a, b, u):
    """REPEAT bilinear of texel a (centre u = 0.25) and b (0.75), per channel: (n, 3)."""
    x = np.mod(u * 2.0 - 0.5, 2.0)[:, None]
    t = np.where(x < 1.0, x, 2.0 - x)
    return a + (b - a) * t


def columns(f, n=WIDTH, fine=512):
    """Mean of f(u) (u, -> (u, 3)) over each of n equal columns of u in [0, 1]."""
    u = (np.arange(n * fine) + 0.5) / (n * fine)
    return f(u).reshape(n, fine, 3).mean(axis=1)


def predictions(texels):
    """(encoded blend then decoded, decoded texels blended) per column, from the stored bytes
    (associated with alpha as Cycles stores them)."""
    t = texels.astype(np.int64)
    t[..., :3] = t[..., :3] * t[..., 3:4] // 255
    a, b = t[0, 0, :3] / 255.0, t[0, 1, :3] / 255.0
    exact = columns(lambda u: decode(blend(a, b, u)))
    old = columns(lambda u: blend(decode(a), decode(b), u))
    return exact, old


def _write(path, px, fmt):
    import OpenImageIO as oiio
    h, w, c = px.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.attribute('oiio:UnassociatedAlpha', 1)      # straight alpha, as given
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(px[::-1]))
    assert buf.write(str(path)), buf.geterror()
    return str(path)


def _blocks(rgb):
    """(H, W, 3) -> per 4-column block means (W / 4, 3)."""
    return rgb.mean(axis=0).reshape(WIDTH // BLOCK, BLOCK, 3).mean(axis=1)


def _exact_cycles(sc):
    """Cycles without denoising (on by default; it moves a 64 x 4 render's blocks by up to 6%)
    and without adaptive stops."""
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False


CASES = {
    '8-bit': (TEXELS, 'uint8'),
    '16-bit': (TEXELS, 'uint16'),
    '8-bit alpha': (np.array([[[200, 100, 50, 255], [255, 255, 40, 64]]], np.uint8), 'uint8'),
}


@pytest.mark.parametrize('case', sorted(CASES))
def test_linear_lookup_blends_the_encoding(tmp_path, case):
    texels, fmt = CASES[case]
    px = texels if texels[..., 3].min() < 255 else texels[..., :3]      # RGBA only with alpha
    if fmt == 'uint16':
        px = px.astype(np.uint16) * 257
    path = _write(tmp_path / f"texels_{fmt}.png", px, fmt)

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.interpolation = 'Linear'
        nt.links.new(tex.outputs['Color'], diffuse.inputs['Color'])

    sunplane.build(np.ones((1, 1, 4), np.float32), wire, WIDTH, SAMPLES)
    _exact_cycles(bpy.context.scene)
    bpy.context.scene.render.resolution_y = HEIGHT
    exact, old = (_blocks(p[None]) * K for p in predictions(texels))
    dacrt = _blocks(sunplane.render_rgb('DACRT', tmp_path))
    cycles = _blocks(sunplane.render_rgb('CYCLES', tmp_path))
    top = exact.max()
    for name, got in (('DACRT', dacrt), ('Cycles', cycles)):
        err = np.abs(got - exact).max() / top
        assert err < 0.002, (name, case, err, got.round(4).tolist(), exact.round(4).tolist())
    assert np.abs(old - exact).max() / top > 0.1      # what blending decoded texels gave


def test_environment_lookup_blends_the_encoding(tmp_path):
    """An 8-bit Environment Texture (two texels around, one row) seen whole by an
    equirectangular camera: each pixel is the lookup at its direction, so the image mean is the
    mean of decode(blend(u)) over u (the closed form), and the engines' columns agree."""
    path = _write(tmp_path / "env.png", TEXELS[..., :3], 'uint8')
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    cam = scenes.camera((0, 0, 0), (0, 0, 0), kind='PANO')
    cam.data.panorama_type = 'EQUIRECTANGULAR'
    cam.rotation_euler = (math.pi / 2, 0, 0)
    scenes.environment_world(bpy.data.images.load(path))
    sc.render.resolution_x, sc.render.resolution_y = WIDTH, 2 * HEIGHT
    sc.cycles.device = 'CPU'
    _exact_cycles(sc)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    exact, old = (p.mean(axis=0) for p in predictions(TEXELS))
    dacrt = sunplane.render_rgb('DACRT', tmp_path)
    cycles = sunplane.render_rgb('CYCLES', tmp_path)
    for name, got in (('DACRT', dacrt), ('Cycles', cycles)):
        err = np.abs(got.mean(axis=(0, 1)) - exact).max() / exact.max()
        assert err < 0.002, (name, err, got.mean(axis=(0, 1)).round(4).tolist(), exact.round(4).tolist())
    assert np.abs(old - exact).max() / exact.max() > 0.1
    cols = np.abs(_blocks(dacrt) - _blocks(cycles)).max() / _blocks(cycles).max()
    assert cols < 0.003, cols


TINT = np.array([0.9, 0.8, 0.7])
CHAINS = {
    # Mix Multiply by a constant (the everyday tint) and Invert: affine in the image's colour,
    # kept as weight x lookup + constant after the encoded blend, as Cycles runs them
    'tint': (lambda c: c * TINT, lambda nt, s: scenes.mix_node(nt, 'MULTIPLY', s, (*TINT,), 1.0).outputs['Result']),
    'invert': (lambda c: 1.0 - c, None),
}


def _invert(nt, socket):
    node = nt.nodes.new('ShaderNodeInvert')
    nt.links.new(socket, node.inputs['Color'])
    return node.outputs['Color']


@pytest.mark.parametrize('chain', sorted(CHAINS))
def test_affine_colour_nodes_after_an_image_keep_its_encoded_blend(tmp_path, chain):
    """Colour nodes after an 8-bit image run after Cycles' lookup (blend the encoded texels,
    decode, then the nodes). Baking them into decoded texels before the blend, as DACRT did,
    brightened a tinted 0/255 stripe pattern 61% (a tester's). Affine chains now keep the blend."""
    f, build = CHAINS[chain]
    build = build or _invert
    path = _write(tmp_path / "texels.png", TEXELS[..., :3], 'uint8')

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.interpolation = 'Linear'
        nt.links.new(build(nt, tex.outputs['Color']), diffuse.inputs['Color'])

    sunplane.build(np.ones((1, 1, 4), np.float32), wire, WIDTH, SAMPLES)
    _exact_cycles(bpy.context.scene)
    bpy.context.scene.render.resolution_y = HEIGHT
    t = TEXELS.astype(np.float64)[0, :, :3] / 255.0
    exact = _blocks(columns(lambda u: f(decode(blend(t[0], t[1], u))))[None]) * K
    old = _blocks(columns(lambda u: blend(f(decode(t[0])), f(decode(t[1])), u))[None]) * K
    top = exact.max()
    for name in ('DACRT', 'CYCLES'):
        got = _blocks(sunplane.render_rgb(name, tmp_path))
        err = np.abs(got - exact).max() / top
        assert err < 0.002, (name, chain, err, got.round(4).tolist(), exact.round(4).tolist())
    assert np.abs(old - exact).max() / top > 0.05
