"""Images Cycles keeps in their sRGB encoding (addon/texture.py EncodedTexels): the lookup blends
the stored texels and decodes after, as Cycles' svm_image_texture (compress_as_srgb), against
closed forms. A two-texel pattern (a, b) repeated along u blends to a + (b - a) t between the
texel centres, so the looked-up value is decode(a + (b - a) t) exactly; decoding each texel
first gives the straight line between decode(a) and decode(b), too bright in between (0/255:
0.5 against 0.214 at the midpoint). Also: the blended alpha divides a linked Alpha output's
colour before the decoding, 'Closest' reads the very same texels as before (bit for bit), UDIM
tiles, colour maps after the lookup, the environment map's native kernels, and a render."""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.lights.environment import EnvironmentLight
from addon.texture import (MISSING_TILE, EncodedTexels, ImageTexels, UdimTiles, baked, linear_to_srgb,
                           lookup_texels, srgb_to_linear, stored_texels, texture_lookup)

from .scenes import light, material, plane_scene, render

F32 = np.float32
A = np.array([0, 64, 255], np.uint8)      # texel 0's bytes (R, G, B)
B = np.array([255, 200, 30], np.uint8)    # texel 1's


def decode(c):
    """sRGB -> linear in float64 (the closed form's)."""
    c = np.asarray(c, np.float64)
    return np.where(c < 0.04045, np.maximum(c / 12.92, 0.0), (np.maximum(c + 0.055, 0.0) / 1.055) ** 2.4)


def two_texels(alpha=(255, 255)):
    """(1, 2, 4) uint8: texels A and B with the given alphas."""
    px = np.zeros((1, 2, 4), np.uint8)
    px[0, 0, :3], px[0, 1, :3] = A, B
    px[0, :, 3] = alpha
    return px


def sweep(n=257):
    """u from texel 0's centre (0.25) to texel 1's (0.75) and on to texel 0's again (1.25, REPEAT):
    t, the place between the two, 0 -> 1 -> 0."""
    u = np.linspace(0.25, 1.25, n).astype(F32)
    x = (u.astype(np.float64) - 0.25) * 2.0
    return u, np.full(n, 0.5, F32), np.where(x <= 1.0, x, 2.0 - x)


def test_decode_is_cycles_and_encode_inverts_it():
    c = np.linspace(-0.1, 1.5, 4001).astype(F32)
    assert np.allclose(srgb_to_linear(c), decode(c), rtol=2e-6, atol=1e-9)
    assert srgb_to_linear(c).dtype == F32 and (srgb_to_linear(c)[c < 0] == 0).all()
    x = np.linspace(0, 1, 256).astype(F32)
    assert np.abs(linear_to_srgb(srgb_to_linear(x)) - x).max() < 3e-7


@pytest.mark.parametrize('extension', ['REPEAT', 'EXTEND'])
def test_bilinear_blends_the_encoding_then_decodes(extension):
    """decode(a + (b - a) t) on the way between the two texel centres (closed form), where the
    blend of decoded texels is the straight line between decode(a) and decode(b)."""
    tex = EncodedTexels(two_texels(), srgb=True, scale=1 / 255)
    u, v, t = sweep()
    if extension == 'EXTEND':                  # no wrap: only the way from texel 0 to texel 1
        keep = u <= 0.75
        u, v, t = u[keep], v[keep], t[keep]
    got = texture_lookup(tex, u, v, 'Linear', extension)
    a, b = A / 255.0, B / 255.0
    exact = decode(a[:, None] + (b - a)[:, None] * t[None, :])
    assert got.shape == (3, len(u)) and got.dtype == F32
    assert np.abs(got - exact).max() < 2e-6
    linear = decode(a)[:, None] + (decode(b) - decode(a))[:, None] * t[None, :]
    mid = np.argmin(np.abs(t - 0.5))
    assert linear[0, mid] == pytest.approx(0.5, abs=1e-2) and exact[0, mid] == pytest.approx(0.214, abs=1e-3)


def test_closest_reads_the_stored_texels():
    """'Closest' reads one texel, decoded before or after alike: the stored texels are what the
    lookup reads (as for 'Linear'), the scene-linear ones up to float rounding."""
    rng = np.random.default_rng(4)
    b = rng.integers(0, 256, (5, 7, 4)).astype(np.uint8)
    linear = srgb_to_linear(b / F32(255))
    stored = EncodedTexels(b, srgb=True, scale=1 / 255)
    image = ImageTexels(linear, stored)
    assert lookup_texels(image, 'Closest') is stored and lookup_texels(image, 'Linear') is stored
    u, v = rng.random((2, 1000), F32) * 3 - 1
    for ext in ('REPEAT', 'EXTEND', 'CLIP'):
        ref = texture_lookup(np.ascontiguousarray(linear), u, v, 'Closest', ext)
        # the stored texels decoded after the pick: the same up to float rounding
        assert np.allclose(texture_lookup(lookup_texels(image, 'Closest'), u, v, 'Closest', ext), ref,
                           rtol=1e-6, atol=1e-7)


def test_what_is_computed_from_the_texels_is_plain_linear_texels():
    """Only the loader's array carries the stored encoding: copies, views and arithmetic (a
    colour baked into the texels) are read as plain linear texels."""
    image = ImageTexels(np.ones((2, 2, 4), F32), EncodedTexels(np.full((2, 2, 4), 255, np.uint8), True, scale=1 / 255))
    assert stored_texels(image) is image.stored
    copy = image.copy()
    copy[..., :3] = image[..., :3] * 0.5 + 0.1
    assert stored_texels(copy) is None and stored_texels(image[..., :3]) is None
    assert type(image * 2) is np.ndarray and type(image[..., :3].mean()) is not ImageTexels
    udim = UdimTiles([1001], [(2, 2)], image.reshape(1, 4, 4))
    assert stored_texels(udim) is None                  # a reshaped view is plain
    udim = UdimTiles([1001], [(2, 2)], ImageTexels(np.ones((1, 4, 4), F32), image.stored))
    assert stored_texels(udim.with_texels(udim.flat)) is image.stored


def test_linked_alpha_divides_the_blended_colour_before_decoding():
    """Cycles associates an 8-bit image's colour with alpha in bytes on load (c a / 255), blends
    the associated texels and alpha, divides by the blended alpha and decodes; without the
    division (Alpha output unlinked) the associated colour is decoded."""
    px = two_texels(alpha=(255, 64))
    assoc = px.astype(np.int64)
    assoc[..., :3] = assoc[..., :3] * assoc[..., 3:4] // 255
    u, v, t = sweep()
    a, b = assoc[0, 0] / 255.0, assoc[0, 1] / 255.0
    blend = a[:, None] + (b - a)[:, None] * t[None, :]
    for unassociate in (False, True):
        tex = EncodedTexels(assoc.astype(np.uint8), srgb=True, unassociate=unassociate, scale=1 / 255)
        got = texture_lookup(tex, u, v, 'Linear', 'REPEAT')
        want = decode(blend[:3] / blend[3] if unassociate else blend[:3])
        assert np.abs(got - want).max() < 3e-6, unassociate
    # a linear image with alpha: the blend of associated floats divided by the blended alpha
    lin = np.array([[[0.2, 0.4, 0.8, 1.0], [0.3, 0.1, 0.05, 0.25]]], F32)
    got = texture_lookup(EncodedTexels(lin, srgb=False, unassociate=True), u, v, 'Linear', 'REPEAT')
    bl = lin[0, 0, :, None] + (lin[0, 1] - lin[0, 0])[:, None] * t[None, :]
    assert np.abs(got - bl[:3] / bl[3]).max() < 1e-6
    with pytest.raises(ValueError, match="encoded texels"):
        EncodedTexels(lin[..., :3], srgb=False, unassociate=True)


def test_udim_tiles_decode_per_tile_and_keep_magenta():
    tiles = {1001: two_texels() / F32(255), 1002: np.full((1, 1, 4), 0.5, F32)}
    tex = EncodedTexels(UdimTiles.stack(tiles), srgb=True)
    u, v, t = sweep(65)
    got = texture_lookup(tex, u, v, 'Linear', 'REPEAT')
    a, b = A / 255.0, B / 255.0
    in_tile = u < 1.0                                      # u >= 1 is tile 1002's
    exact = decode(a[:, None] + (b - a)[:, None] * t[None, :])
    assert np.abs(got[:, in_tile] - exact[:, in_tile]).max() < 2e-6
    assert np.allclose(got[:, ~in_tile], decode(0.5), atol=1e-6)
    missing = texture_lookup(tex, np.array([0.5], F32), np.array([1.5], F32), 'Linear', 'REPEAT')
    assert np.array_equal(missing[:, 0], MISSING_TILE)


def test_colour_map_baked_in_applies_after_the_lookup():
    """A colour map baked into an image's texels (texture.baked) is applied after the stored
    texels' lookup, in Cycles' order: exact for the blend too; 'Closest' reads what the baked texels hold."""
    px = two_texels()
    linear = srgb_to_linear(px / F32(255))
    image = ImageTexels(linear, EncodedTexels(px, srgb=True, scale=1 / 255))
    f = lambda rgb: np.sqrt(rgb) * [0.5, 1.0, 2.0] + 0.1          # nonlinear, per point
    values = linear.copy()
    values[..., :3] = f(linear[..., :3])
    texture = baked(image, values, f)
    u, v, t = sweep()
    got = texture_lookup(lookup_texels(texture, 'Linear'), u, v, 'Linear', 'REPEAT')
    a, b = A / 255.0, B / 255.0
    want = f(decode(a[:, None] + (b - a)[:, None] * t[None, :]).T).T
    assert np.abs(got - want).max() < 1e-5
    closest = texture_lookup(lookup_texels(texture, 'Closest'), u, v, 'Closest', 'REPEAT')
    assert np.allclose(closest, texture_lookup(np.ascontiguousarray(values), u, v, 'Closest', 'REPEAT'),
                       rtol=1e-5, atol=1e-6)
    plain = baked(np.ascontiguousarray(linear), values, f)         # no stored encoding: the values
    assert stored_texels(plain) is None


def test_render_reads_the_encoded_texture():
    """The integrator looks an image's stored texels up (through the material's texture):
    a plane under a sun whose UVs sit between the two texels renders decode(blend) x albedo."""
    scene = plane_scene([light('SUN', np.pi, np.eye(4))], samples=4)
    px = two_texels()
    image = ImageTexels(srgb_to_linear(px / F32(255)), EncodedTexels(px, srgb=True, scale=1 / 255))
    a, b = A / 255.0, B / 255.0
    for t in (0.0, 0.3, 0.5):
        scene.geometry.uvs = np.full((2, 3, 2), (0.25 + 0.5 * t, 0.5), F32)
        for interp, want in (('Linear', decode(a + (b - a) * t)),
                             ('Closest', decode(a if t < 0.5 else b))):
            scene.materials[1] = material('tex', (0.8, 0.4, 0.2), texture=image, texture_interpolation=interp)
            rgb = render(scene).film.combined()[..., :3].reshape(-1, 3)
            assert np.allclose(rgb, np.array([0.8, 0.4, 0.2]) * want, rtol=2e-5, atol=1e-7), (t, interp)


def _env(encoded, interpolation='Linear', strength=(1.0, 1.0, 1.0)):
    pixels = srgb_to_linear(encoded)
    return EnvironmentLight(sd.Environment(pixels, np.asarray(strength, F32), np.eye(3), interpolation,
                                           encoded=encoded))


def test_srgb_environment_native_matches_definition_and_closed_form():
    """An 8-bit environment map (as Cycles keeps it, in its encoding): the native lookup decodes
    the blend and multiplies by the strength, as the Python definition and the closed form;
    its importance map comes from the decoded texels, and samples stay unbiased."""
    rng = np.random.default_rng(9)
    enc = (rng.integers(0, 256, (16, 32, 3)) / 255.0).astype(F32)
    enc[5, 7] = 1.0
    ref = _env(enc, strength=(2.0, 1.0, 0.5))
    D = rng.normal(size=(3, 20_000))
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    Le, pdf = ref.native.eval(D)
    _, Le_ref, pdf_ref = ref.eval_miss(D)
    assert np.isclose(pdf, pdf_ref, rtol=1e-4).mean() > 0.999
    assert np.median(np.abs(Le - Le_ref) / np.maximum(Le_ref, 1e-6)) < 1e-5
    assert np.allclose(Le, Le_ref, rtol=2e-3, atol=1e-4)
    # the closed form at texel rows' centres, between two texel centres of a row
    j = np.arange(32)
    x = rng.random(32)
    u = ((j + 0.5 + x) / 32).astype(F32)
    v = np.full(32, 5.5 / 16, F32)
    direction = np.stack([np.sin(np.pi * (1 - v)) * np.cos(np.pi * (1 - 2 * u)),
                          np.sin(np.pi * (1 - v)) * np.sin(np.pi * (1 - 2 * u)), np.cos(np.pi * (1 - v))])
    Le, _ = ref.native.eval(direction.astype(F32))
    row = enc[5].astype(np.float64)
    blend = row[j] * (1 - x)[:, None] + row[(j + 1) % 32] * x[:, None]
    assert np.allclose(Le, (decode(blend) * [2.0, 1.0, 0.5]).T, rtol=1e-4, atol=1e-6)
    # sampling: E[value] is the integral of the looked-up radiance (quadrature, 8 x 8 a texel)
    wi, value, spdf = ref.native.sample(*rng.random((2, 200_000), F32))
    th = np.pi * (np.arange(128) + 0.5) / 128
    ph = 2 * np.pi * (np.arange(256) + 0.5) / 256
    T, PH = np.meshgrid(th, ph, indexing='ij')
    grid = np.stack([np.sin(T) * np.cos(PH), np.sin(T) * np.sin(PH), np.cos(T)]).reshape(3, -1).astype(F32)
    Lq, _ = ref.native.eval(grid)
    integral = (Lq * np.sin(T).ravel()).sum(axis=1) * (np.pi / 128) * (2 * np.pi / 256)
    assert np.allclose(value.astype(np.float64).mean(axis=1), integral, rtol=0.01)
    # 'Closest' decodes the picked texel: the decoded texels' lookup
    closest = _env(enc, 'Closest')
    Lc, _ = closest.native.eval(D)
    plain = EnvironmentLight(sd.Environment(srgb_to_linear(enc), np.ones(3, F32), np.eye(3), 'Closest'))
    assert np.allclose(Lc, plain.native.eval(D)[0], rtol=1e-6, atol=1e-7)
