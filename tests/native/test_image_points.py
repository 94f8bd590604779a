"""Per-point image lookups (native/cpp/imagepoints.cpp, dacrt.images): texels blended at (u, v)
and Box projection at points and object-space normals. Properties: the kernel agrees with a
float64 numpy reference written from Cycles' formulas (texel centres at (i + 0.5) / size,
bilinear and uniform cubic B-spline taps, Repeat / Extend / Clip / Mirror, the Box weights of
svm_node_tex_image_box) for every interpolation, extension, Blend 0 / 0.5 / 1, float and byte
texels, points on the cube's edges and corners and at the poles; and it gives the very bits of
the add-on's numpy lookups it replaces (texture._blend_texels, texture.box_projected), NaN,
infinite and huge coordinates and NaN or zero normals included, but for the sRGB decode of a
Box plane (libm's powf where numpy's float32 power is SVML's: within 4 ulps once weighed). Byte texels are
read in place (no float copy)."""
import math

import numpy as np
import pytest

import dacrt
from addon import texture

F32 = np.float32
INTERPS = ['Closest', 'Linear', 'Cubic']
EXTS = ['REPEAT', 'EXTEND', 'CLIP', 'MIRROR']


def _texels(dtype, h=5, w=7, c=4, seed=3):
    rs = np.random.RandomState(seed)
    if dtype == np.uint8:
        return rs.randint(0, 256, (h, w, c)).astype(np.uint8)
    return rs.rand(h, w, c).astype(F32)


def _coords(n, seed=5):
    """(u, v) float32: spread over several image repeats, exact texel edges and centres, and
    non-finite or huge values."""
    rs = np.random.RandomState(seed)
    u = rs.uniform(-2.5, 3.5, n).astype(F32)
    v = rs.uniform(-2.5, 3.5, n).astype(F32)
    u[:40] = (np.arange(40) - 15) / F32(14)        # texel edges and centres of a 7-wide image
    v[40:80] = (np.arange(40) - 15) / F32(10)
    special = np.array([np.nan, np.inf, -np.inf, 1e30, -1e30, 2.0 ** 40, -0.0, 0.0, 1.0, 1e-42], F32)
    u[80:90], v[90:100] = special, special
    return u, v


def _wrap64(i, size, ext):
    if ext == 'REPEAT':
        return np.mod(i, size), np.ones(i.shape, bool)
    if ext == 'EXTEND':
        return np.clip(i, 0, size - 1), np.ones(i.shape, bool)
    if ext == 'MIRROR':
        m = np.mod(i, 2 * size)
        return np.where(m < size, m, 2 * size - 1 - m), np.ones(i.shape, bool)
    return np.clip(i, 0, size - 1), (i >= 0) & (i < size)


def _bspline64(t):
    return ((1 - t) ** 3 / 6, (3 * t ** 3 - 6 * t ** 2 + 4) / 6, (-3 * t ** 3 + 3 * t ** 2 + 3 * t + 1) / 6, t ** 3 / 6)


def _blend64(tex, u, v, interp, ext, c0, c1):
    """float64 reference (c1 - c0, n) at finite (u, v): the texel positions u w (less 0.5 when
    blended) as the float32 lookup finds them, the weights and the sums in float64."""
    h, w = tex.shape[:2]
    t = tex[..., c0:c1].astype(np.float64)
    x, y = u * F32(w), v * F32(h)
    if interp == 'Closest':
        ix, mx = _wrap64(np.floor(x).astype(np.int64), w, ext)
        iy, my = _wrap64(np.floor(y).astype(np.int64), h, ext)
        return (t[iy, ix] * (mx & my)[:, None]).T
    x, y = x - F32(0.5), y - F32(0.5)
    fx, fy = x.astype(np.float64) - np.floor(x), y.astype(np.float64) - np.floor(y)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    if interp == 'Linear':
        tx, ty = ((0, 1 - fx), (1, fx)), ((0, 1 - fy), (1, fy))
    else:
        tx, ty = list(zip(range(-1, 3), _bspline64(fx))), list(zip(range(-1, 3), _bspline64(fy)))
    out = np.zeros((len(u), c1 - c0))
    for dy, wy in ty:
        iy, my = _wrap64(y0 + dy, h, ext)
        for dx, wx in tx:
            ix, mx = _wrap64(x0 + dx, w, ext)
            out += t[iy, ix] * (wx * wy * (mx & my))[:, None]
    return out.T


def _box_weights64(n, blend):
    """Cycles' svm_node_tex_image_box weights in float64, case by case."""
    a = np.abs(n.astype(np.float64))
    w = np.zeros_like(a)
    limit = 0.5 * (1 + blend)
    for i, (x, y, z) in enumerate(a / a.sum(axis=1, keepdims=True)):
        if x > limit * (x + y) and x > limit * (x + z):
            w[i] = 1, 0, 0
        elif y > limit * (x + y) and y > limit * (y + z):
            w[i] = 0, 1, 0
        elif z > limit * (x + z) and z > limit * (y + z):
            w[i] = 0, 0, 1
        elif blend <= 0:
            w[i] = 1, 0, 0
        elif z < (1 - limit) * (y + x):
            q = min(max((x / (x + y) - 0.5 * (1 - blend)) / blend, 0), 1)
            w[i] = q, 1 - q, 0
        elif x < (1 - limit) * (y + z):
            q = min(max((y / (y + z) - 0.5 * (1 - blend)) / blend, 0), 1)
            w[i] = 0, q, 1 - q
        elif y < (1 - limit) * (x + z):
            q = min(max((x / (x + z) - 0.5 * (1 - blend)) / blend, 0), 1)
            w[i] = q, 0, 1 - q
        else:
            w[i] = [((2 - limit) * q + (limit - 1)) / (2 * limit - 1) for q in (x, y, z)]
    return w


def _normals(n, seed=7):
    """Face normals, cube edges and corners, the poles, and random unit normals."""
    s = 1 / math.sqrt(2)
    r3 = 1 / math.sqrt(3)
    fixed = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (s, s, 0), (-s, s, 0), (s, 0, -s),
             (0, -s, s), (r3, r3, r3), (-r3, r3, -r3), (0.6, 0.8, 0.0), (0.2, 0.3, 0.93)]
    rs = np.random.RandomState(seed)
    rnd = rs.normal(size=(n - len(fixed), 3))
    rnd /= np.linalg.norm(rnd, axis=1, keepdims=True)
    return np.concatenate([np.array(fixed), rnd]).astype(F32)


def _same(a, b):
    """Equal bits, except that any NaN equals any NaN."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    bad = np.flatnonzero((a.view(np.uint32) != b.view(np.uint32)) & ~nan)
    assert len(bad) == 0, f"{len(bad)} values differ, first at {bad[:5]}: {a.ravel()[bad[:5]]} vs {b.ravel()[bad[:5]]}"


@pytest.mark.parametrize('dtype', [F32, np.uint8])
@pytest.mark.parametrize('ext', EXTS)
@pytest.mark.parametrize('interp', INTERPS)
def test_blend_agrees_with_the_float64_reference(interp, ext, dtype):
    tex = _texels(dtype)
    u, v = _coords(3000)
    fin = np.isfinite(u) & np.isfinite(v) & (np.abs(u) < 1e6) & (np.abs(v) < 1e6)
    for c0, c1 in ((0, 3), (3, 4), (0, 4)):
        got = dacrt.images.texel_blend(tex, u[fin], v[fin], (c0, c1), interp, ext)
        want = _blend64(tex, u[fin], v[fin], interp, ext, c0, c1)
        assert got.shape == want.shape and got.dtype == F32
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=2e-6 * (255 if dtype == np.uint8 else 1))
    if interp != 'Closest':     # a non-finite coordinate blends to NaN (its weights are)
        bad = dacrt.images.texel_blend(tex, u[~fin], v[~fin], (0, 4), interp, ext)
        assert np.isnan(bad[:, ~np.isfinite(u[~fin]) | ~np.isfinite(v[~fin])]).all()


@pytest.mark.parametrize('dtype', [F32, np.uint8])
@pytest.mark.parametrize('ext', EXTS)
@pytest.mark.parametrize('interp', INTERPS)
def test_blend_gives_the_numpy_lookups_bits(interp, ext, dtype):
    """NaN, infinite and huge UVs too (numpy casts them to index INT64_MIN and wraps that)."""
    tex = _texels(dtype, 6, 9, 4, seed=11)
    u, v = _coords(5000, seed=12)
    for channels in (3, 4):
        with np.errstate(invalid='ignore', over='ignore'):
            want = texture._blend_texels(tex, u, v, interp, ext, channels)
        _same(dacrt.images.texel_blend(tex, u, v, (0, channels), interp, ext), want)
        _same(texture._blend(tex, u, v, interp, ext, channels), want)     # the add-on's lookup takes it


def test_blend_reads_strided_and_byte_texels_in_place():
    """A view (every other column, rows flipped) reads as its copy; bytes as their values."""
    big = _texels(np.uint8, 8, 14, 4, seed=4)
    view = big[::-1, ::2]
    u, v = _coords(2000, seed=9)
    for t in (view, view.astype(F32)):
        _same(dacrt.images.texel_blend(t, u, v, (0, 4), 'Linear', 'MIRROR'),
              dacrt.images.texel_blend(np.ascontiguousarray(view, F32), u, v, (0, 4), 'Linear', 'MIRROR'))


def _box_case(n, seed):
    rs = np.random.RandomState(seed)
    normal = _normals(n, seed)
    co = rs.uniform(-0.5, 1.5, (n, 3)).astype(F32)
    return co, normal


@pytest.mark.parametrize('blend', [0.0, 0.5, 1.0, 0.3])
@pytest.mark.parametrize('interp', INTERPS)
def test_box_agrees_with_the_float64_reference(interp, blend):
    """Each plane's lookup (u flipped by the normal's sign) weighed as Cycles weighs it."""
    tex = _texels(F32, 6, 5, 4, seed=21)
    co, normal = _box_case(1500, 22)
    w, out = dacrt.images.box_lookup(tex, co, normal, blend, (0, 3), interp, 'REPEAT')
    w64 = _box_weights64(normal, blend)
    np.testing.assert_allclose(w, w64, atol=2e-6)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-5)
    x, y, z = co.T
    planes = ((np.where(normal[:, 0] < 0, F32(1) - y, y), z), (np.where(normal[:, 1] > 0, F32(1) - x, x), z),
              (np.where(normal[:, 2] > 0, F32(1) - y, y), x))
    want = sum(w64[:, k, None] * _blend64(tex, u, v, interp, 'REPEAT', 0, 3).T for k, (u, v) in enumerate(planes))
    np.testing.assert_allclose(out, want, rtol=1e-5, atol=3e-6)
    if blend == 0.0:       # no blending: one plane a point (on an edge or a corner: X, Cycles' "desperate mode")
        assert set(np.unique(w)) <= {0.0, 1.0}
        np.testing.assert_array_equal(w[6:12], np.eye(3)[[0] * 6])


def _numpy_box(tex, co, normal, blend, interp, ext, alpha=False):
    def read(u, v):
        if alpha:
            return texture.alpha_lookup(tex, u, v, interp, ext)[:, None]
        return texture.texture_lookup(tex, u, v, interp, ext).T
    with np.errstate(invalid='ignore', over='ignore'):
        return texture.box_projected(co, normal, F32(blend), read, 1 if alpha else 3)


def _numpy_only(monkeypatch):
    """The add-on's numpy lookups alone (what ran before the native kernel)."""
    monkeypatch.setattr(texture, '_native_texels', lambda tex, channels: None)


def _within_ulps(a, b, ulps):
    """Equal NaNs, and the rest within `ulps` float32 ulps."""
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    ok = ~np.isnan(a)
    np.testing.assert_array_max_ulp(a[ok], b[ok], maxulp=ulps)


@pytest.mark.parametrize('blend', [0.0, 0.5, 1.0])
@pytest.mark.parametrize('ext', EXTS)
@pytest.mark.parametrize('interp', INTERPS)
def test_box_gives_the_numpy_lookups_bits(monkeypatch, interp, ext, blend):
    """Colour and alpha, float and encoded byte texels (sRGB decoded per plane before the
    weighing: natively with libm's powf, within 4 ulps of numpy's SVML power after the
    weighing; unassociated alpha in numpy, exact), NaN coordinates and NaN or zero normals
    among the points."""
    co, normal = _box_case(3000, 31)
    co[:20] = np.nan
    normal[20:25] = np.nan
    normal[25:30] = 0.0
    k8 = _texels(np.uint8, 7, 6, 4, seed=32)
    cases = [(_texels(F32, 7, 6, 4, seed=33), False), (_texels(F32, 7, 6, 4, seed=33), True),
             (texture.EncodedTexels(k8, srgb=False, scale=1 / 255), False),
             (texture.EncodedTexels(k8, srgb=True, scale=1 / 255), False),
             (texture.EncodedTexels(k8, srgb=True, unassociate=True, scale=1 / 255), False),
             (texture.EncodedTexels(k8, srgb=True, scale=1 / 255), True)]
    for tex, alpha in cases:
        spec = texture.box_texels(tex, alpha, interp, ext)
        assert spec is not None
        got = texture.box_lookup(spec, co, normal, F32(blend), interp, ext)
        with monkeypatch.context() as m:
            _numpy_only(m)
            want = _numpy_box(tex, co, normal, blend, interp, ext, alpha)
        if getattr(tex, 'srgb', False) and not tex.unassociate and not alpha:
            _within_ulps(got, want, 4)
        else:
            _same(got, want)


def test_srgb_bytes_decode_as_cycles():
    """Every byte value on one plane (Blend 0, Closest at texel centres): Cycles'
    color_srgb_to_linear of k / 255, within an ulp of the add-on's numpy decode and 1e-6 of
    float64."""
    k = np.arange(256, dtype=np.uint8)
    k8 = np.stack([k, k[::-1], k, np.full(256, 255, np.uint8)], axis=-1).reshape(16, 16, 4)
    enc = texture.EncodedTexels(k8, srgb=True, scale=1 / 255)
    i = np.arange(256)
    co = np.stack([(i // 16 + 0.5) / 16, (i % 16 + 0.5) / 16, np.zeros(256)], axis=1).astype(F32)   # plane Z: (y, x)
    normal = np.tile(np.array([[0, 0, -1]], F32), (256, 1))
    got = texture.box_lookup(texture.box_texels(enc, False, 'Closest', 'REPEAT'), co, normal, F32(0), 'Closest', 'REPEAT')
    want = texture.srgb_to_linear(k8.reshape(-1, 4)[:, :3] * F32(1 / 255))
    _within_ulps(got, want, 1)
    c = k8.reshape(-1, 4)[:, :3] / 255.0
    np.testing.assert_allclose(got, np.where(c < 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4), rtol=1e-6, atol=1e-9)


def test_srgb_bytes_are_decoded_in_the_kernel():
    """An 8-bit sRGB image (the common colour texture) is decoded and weighed natively, with
    no per-plane pass in numpy; unassociated alpha and nodes after the image still are."""
    k8 = _texels(np.uint8, 8, 8, 4)
    spec = texture.box_texels(texture.EncodedTexels(k8, srgb=True, scale=1 / 255), False, 'Linear', 'REPEAT')
    assert spec[3] is True and spec[4] is None
    for enc in (texture.EncodedTexels(k8, srgb=True, unassociate=True, scale=1 / 255),
                texture.EncodedTexels(k8, srgb=True, scale=1 / 255, then=lambda rgb: rgb * 2)):
        assert texture.box_texels(enc, False, 'Linear', 'REPEAT')[4] is not None


def test_byte_texels_stay_bytes():
    """An 8-bit image's stored bytes reach the kernel as they are: no float copy."""
    k8 = _texels(np.uint8, 64, 64, 4)
    enc = texture.EncodedTexels(k8, srgb=True, scale=1 / 255)
    for alpha in (False, True):
        arr = texture.box_texels(enc, alpha, 'Linear', 'REPEAT')[0]
        assert arr.dtype == np.uint8 and np.shares_memory(arr, k8)
    assert np.shares_memory(texture._native_texels(enc.texels, 3), k8)


def test_bad_arguments_are_refused():
    tex = _texels(F32)
    u = np.zeros(4, F32)
    with pytest.raises(ValueError):
        dacrt.images.texel_blend(tex, u, u, (2, 5), 'Linear', 'REPEAT')        # channels past c
    with pytest.raises(ValueError):
        dacrt.images.texel_blend(tex[:0], u, u, (0, 3), 'Linear', 'REPEAT')    # no texels
    with pytest.raises(ValueError):
        dacrt.images.texel_blend(tex.astype(np.float64)[..., 0], u, u, (0, 1), 'Linear', 'REPEAT')
    with pytest.raises(ValueError):
        dacrt.images.box_lookup(tex, np.zeros((3, 3), F32), np.zeros((4, 3), F32), 0.5, (0, 3), 'Linear', 'REPEAT')
