"""The environment map's build (native/cpp/envbuild.cpp): its tables have the same bits on one
thread as on all of them; an image's RGBA texels with the strength as `scale` build the map of
the RGB x strength product the export had made in numpy, and an 8-bit image's bytes the map of
their floats; an sRGB map's importance is its decoded texels' mean (the byte table's decodes
are the lookup's); texel_stats counts what the export reports."""

import dacrt
import numpy as np
import pytest
from dacrt import lamps

F32 = np.float32


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q.astype(F32)


def _outputs(env, rng):
    """Everything the renderer reads of a map: eval at random directions, both samplers' draws."""
    n = 4000
    D = rng.normal(size=(3, n)).astype(F32)
    D /= np.linalg.norm(D, axis=0)
    u1, u2 = rng.random(n, dtype=F32), rng.random(n, dtype=F32)
    return [np.array([env.total])] + list(env.eval(D)) + list(env.sample(u1, u2)) + list(env.sample_lanes(u1, u2))


def _maps(rng):
    """(name, rgb, srgb, scale): maps of many shapes, wide dark runs, 8-bit and arbitrary sRGB values."""
    out = []
    for h, w in ((1, 1), (1, 9), (7, 1), (33, 65), (512, 1024)):
        px = (rng.random((h, w, 4), F32) ** 4 * 10).astype(F32)
        px[..., :3][rng.random((h, w)) < 0.3] = 0
        st = np.array([1.5, 0.7, 2.25], F32)
        out.append((f"linear-{h}x{w}", px, False, st))
        out.append((f"bytes-{h}x{w}", rng.integers(0, 256, (h, w, 3)).astype(F32) * F32(1 / 255), True, st))
        out.append((f"srgb-floats-{h}x{w}", rng.random((h, w, 3), F32), True, st))
        out.append((f"black-{h}x{w}", np.zeros((h, w, 3), F32), False, None))
    return out


@pytest.mark.parametrize("interp", ["Linear", "Closest"])
def test_tables_have_the_same_bits_on_any_thread_count(interp):
    rng = np.random.default_rng(3)
    M = _rotation(rng)
    for name, rgb, srgb, scale in _maps(rng):
        with dacrt.thread_limit(1):
            one = lamps.environment_map(rgb, M, interp, srgb=srgb, scale=scale)
        every = lamps.environment_map(rgb, M, interp, srgb=srgb, scale=scale)
        seed = int(rng.integers(1 << 30))
        for a, b in zip(_outputs(one, np.random.default_rng(seed)), _outputs(every, np.random.default_rng(seed))):
            assert a.tobytes() == b.tobytes(), (name, interp)


@pytest.mark.parametrize("interp", ["Linear", "Closest"])
def test_rgba_texels_with_a_scale_are_the_map_of_their_rgb_times_it(interp):
    """What the export hands over (an image's RGBA, the Background's strength) builds, bit for
    bit, the map of the float32 product RGB x strength (alpha unread)."""
    rng = np.random.default_rng(4)
    M = _rotation(rng)
    rgba = (rng.random((48, 96, 4), F32) ** 3 * 20).astype(F32)
    rgba[..., 3] = rng.choice([0.0, np.nan, -1.0, 1e30], size=(48, 96))    # alpha: never read
    st = np.array([3.0, 0.25, 1.7], F32)
    folded = lamps.environment_map(rgba, M, interp, scale=st)
    product = lamps.environment_map(np.ascontiguousarray(rgba[..., :3]) * st, M, interp)
    seed = int(rng.integers(1 << 30))
    for a, b in zip(_outputs(folded, np.random.default_rng(seed)), _outputs(product, np.random.default_rng(seed))):
        assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize("interp", ["Linear", "Closest"])
@pytest.mark.parametrize("srgb", [True, False])
def test_bytes_build_the_map_of_their_floats(interp, srgb):
    """An 8-bit image's bytes (h, w, 4) build, bit for bit, the map of the floats the export
    made of them (float32 k x 1/255, RGB): no float copy of the image is needed."""
    rng = np.random.default_rng(6)
    M = _rotation(rng)
    k8 = rng.integers(0, 256, (40, 72, 4)).astype(np.uint8)
    st = np.array([2.0, 0.3, 1.1], F32)
    floats = np.ascontiguousarray(k8[..., :3]).astype(F32) * F32(1 / 255)
    from_bytes = lamps.environment_map(k8, M, interp, srgb=srgb, scale=st)
    from_floats = lamps.environment_map(floats, M, interp, srgb=srgb, scale=st)
    seed = int(rng.integers(1 << 30))
    for a, b in zip(_outputs(from_bytes, np.random.default_rng(seed)),
                    _outputs(from_floats, np.random.default_rng(seed))):
        assert a.tobytes() == b.tobytes()


def test_an_srgb_maps_importance_is_its_decoded_texels_mean():
    """'Closest': the pdf of a texel over another in its row is the ratio of their looked-up
    (decoded) RGB means, for 8-bit values (decoded by the byte table) and others alike."""
    rng = np.random.default_rng(5)
    h, w = 16, 32
    for enc in (rng.integers(1, 256, (h, w, 3)).astype(F32) * F32(1 / 255), rng.random((h, w, 3), F32) + F32(0.01)):
        st = np.array([2.0, 1.0, 0.5], F32)
        env = lamps.environment_map(enc, None, "Closest", srgb=True, scale=st)
        i = np.repeat(np.arange(1, h - 1), w)
        j = np.tile(np.arange(w), h - 2)
        u, v = (j + 0.5) / w, (i + 0.5) / h
        theta, phi = np.pi * (1.0 - v), np.pi * (1.0 - 2.0 * u)
        D = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]).astype(F32)
        L, pdf = env.eval(D)
        lum = L.astype(np.float64).mean(axis=0).reshape(h - 2, w)
        ratio = pdf.astype(np.float64).reshape(h - 2, w) / lum
        # (the pdf carries sin(theta) of the direction: a row's texels share it)
        np.testing.assert_allclose(ratio / ratio[:, :1], 1.0, rtol=2e-6)


def test_a_texel_beyond_float_after_the_scale_or_negative_is_refused_saying_which():
    """(the message had said "negative or not finite" of a texel whose value is kept when not finite)"""
    px = np.ones((4, 8, 4), F32)
    px[2, 5, 1] = 1e30
    with pytest.raises(ValueError, match=r"pixel value 1.00000002e\+30 at 21 \(channel 1\) times scale 1e\+10 is beyond float.s range"):
        lamps.environment_map(px, scale=np.array([1.0, 1e10, 1.0], F32))
    with pytest.raises(ValueError, match=r"scale nan is negative or not finite"):
        lamps.environment_map(px, scale=np.array([1.0, np.nan, 1.0], F32))
    px[2, 5, 1] = -0.5
    with pytest.raises(ValueError, match=r"pixel value -0.5 at 21 \(channel 1\) is negative$"):
        lamps.environment_map(px)


def test_texel_stats_count_the_rgb_faults_and_light():
    px = np.zeros((5, 7, 4), F32)
    assert lamps.texel_stats(px) == (0, False, False)
    px[..., 3] = np.nan          # alpha: not counted
    px[0, 0, 3] = -1.0
    px[1, 1, 3] = 5.0
    assert lamps.texel_stats(px) == (0, False, False)
    px[2, 3, 0] = px[2, 3, 2] = np.nan          # one texel, two values
    px[4, 6, 1] = -np.inf                      # not finite: black, not 'negative'
    assert lamps.texel_stats(px) == (2, False, False)
    px[3, 3, 2] = -0.5
    px[0, 1, 1] = 1e-30
    assert lamps.texel_stats(px) == (2, True, True)
    big = np.zeros((300, 600, 3), F32)          # (threaded)
    big[299, 599, 2] = np.inf
    assert lamps.texel_stats(big) == (1, False, True)


def _stats_reference(px):
    """texel_stats in numpy: texels with a non-finite RGB value, a finite negative one, one > 0."""
    rgb = px.reshape(-1, px.shape[-1])[:, :3]
    with np.errstate(invalid='ignore'):
        return (int((~np.isfinite(rgb)).any(axis=1).sum()), bool((np.isfinite(rgb) & (rgb < 0)).any()),
                bool((rgb > 0).any()))


@pytest.mark.parametrize('channels', [3, 4, 5])
def test_texel_stats_read_every_value_class_as_the_float_tests(channels):
    """texel_stats reads the floats' bits (a branch-free pass): each class of value (NaNs of
    either sign and payload, infinities, zeros of either sign, subnormals, the largest finite
    values) counts as isfinite, < 0 and > 0 read it, alone in an image at every place (the
    threaded split's ends too) and mixed."""
    special = np.array([np.nan, -np.nan, np.inf, -np.inf, 0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38, -1.1754942e-38,
                        3.4028235e38, -3.4028235e38, 1.0, -1.0], F32)
    bits = special.view(np.uint32)
    special = np.concatenate([special, (bits | np.uint32(0x7fc00123)).view(F32), np.array([0x7f800001, 0xff800001],
                                                                                           np.uint32).view(F32)])
    for h, w in ((3, 5), (300, 600)):          # (the second threaded)
        for v in special:
            for at in (0, 1, h * w // 2, (1 << 16) - 1, 1 << 16, h * w - 1):
                if at >= h * w:
                    continue
                px = np.zeros((h, w, channels), F32)
                px.reshape(-1, channels)[at, (at % 3)] = v
                px.reshape(-1, channels)[at // 2, channels - 1] = -np.nan if channels > 3 else 0.0   # (not RGB)
                alone = _stats_reference(np.array([[v, 0, 0]], F32))      # (the rest is 0)
                assert lamps.texel_stats(px) == alone, (h, w, float(v), v.view(np.uint32), at)
    rng = np.random.default_rng(7)
    for n in (1, 17, 70000, 200003):
        px = rng.choice(special, size=(n, channels)).astype(F32)
        assert lamps.texel_stats(px) == _stats_reference(px), n
        px = np.abs(rng.normal(size=(n, channels))).astype(F32)
        assert lamps.texel_stats(px) == _stats_reference(px) == (0, False, True)
