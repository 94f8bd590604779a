"""The counter-based random numbers and the warps built on them."""
import numpy as np
import pytest

from addon.sampling import (RandomStream, concentric_disk, dot, orthonormal_basis, to_world, uniform_cone,
                            uniform_sphere)

N = 1 << 16


def uniforms(seed=0, dim=0, n=N):
    rs = RandomStream(seed)
    keys = rs.path_keys(np.arange(n) // 16, np.arange(n) % 16)
    return rs.uniform2(keys, dim)


def test_pure_function_of_seed_pixel_sample_dimension():
    rs = RandomStream(5)
    keys = rs.path_keys(np.array([3, 3, 9]), np.array([0, 0, 2]))
    assert keys.shape == (2, 3) and keys.dtype == np.uint32
    assert np.array_equal(keys[:, 0], keys[:, 1]) and not np.array_equal(keys[:, 0], keys[:, 2])
    a = rs.uniform2(keys, 4)
    b = RandomStream(5).uniform2(RandomStream(5).path_keys(np.array([3, 3, 9]), np.array([0, 0, 2])), 4)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(uniforms(seed=1)[0], uniforms(seed=2)[0])


def test_keys_never_collide():
    rs = RandomStream(0)
    pix, smp = np.meshgrid(np.arange(512), np.arange(512))
    keys = rs.path_keys(pix.ravel(), smp.ravel())
    assert len(np.unique(keys.T.copy().view(np.uint64))) == keys.shape[1]


@pytest.mark.parametrize('dim', [0, 1, 7])
def test_uniform_and_independent(dim):
    u1, u2 = uniforms(dim=dim)
    for u in (u1, u2):
        assert u.dtype == np.float32 and u.min() >= 0.0 and u.max() < 1.0
        hist = np.bincount((u * 64).astype(int), minlength=64)
        chi2 = ((hist - N / 64) ** 2 / (N / 64)).sum()
        assert chi2 < 130                                   # 63 dof: p ~ 1e-6
    v1, v2 = uniforms(dim=dim + 1)
    for a, b in ((u1, u2), (u1, v1), (u2, v2)):
        assert abs(np.corrcoef(a, b)[0, 1]) < 0.02
    pick, rr = RandomStream(0).uniform_pick(RandomStream(0).path_keys(np.arange(N), np.zeros(N, int)), dim)
    assert pick.dtype == np.float64 and abs(np.corrcoef(pick, rr)[0, 1]) < 0.02


def test_native_uniforms_equal_the_numpy_definition():
    """The renderer draws its uniforms with the native kernel; it must be the same hash."""
    rs = RandomStream(11)
    keys = rs.path_keys(np.arange(N) // 16, np.arange(N) % 16)
    for dim in (0, 1, 5, 40):
        a, b = rs.uniform2(keys, dim)
        c, d = rs.uniform2_numpy(keys, dim)
        assert np.array_equal(a, c) and np.array_equal(b, d)
        a, b = rs.uniform_pick(keys, dim)
        c, d = rs.uniform_pick_numpy(keys, dim)
        assert a.dtype == c.dtype == np.float64 and np.array_equal(a, c) and np.array_equal(b, d)


def test_sphere_disk_cone():
    s = uniform_sphere(*uniforms())
    assert np.allclose(dot(s, s), 1.0, atol=1e-5) and np.allclose(s.mean(axis=1), 0.0, atol=0.01)
    x, y = concentric_disk(*uniforms())
    assert (x * x + y * y).max() <= 1.0 + 1e-6 and (x * x + y * y).mean() == pytest.approx(0.5, abs=0.005)
    omc = 1e-5                                                   # a sun-sized cone stays exact
    d, cos_t = uniform_cone(*uniforms(), omc)
    assert np.allclose(dot(d, d), 1.0, atol=1e-5)
    sin_t = np.hypot(d[0].astype(np.float64), d[1])              # the angle is kept, not just cos
    assert sin_t.max() <= np.sqrt(omc * (2 - omc)) * (1 + 1e-5)
    assert (sin_t ** 2).mean() == pytest.approx(omc, rel=0.01)


def test_frames_are_orthonormal():
    n = uniform_sphere(*uniforms())
    t, b = orthonormal_basis(n)
    for a, c in ((t, b), (t, n), (b, n)):
        assert np.abs(dot(a, c)).max() < 1e-5
    assert np.allclose(dot(t, t), 1.0, atol=1e-5) and np.allclose(dot(b, b), 1.0, atol=1e-5)
    local = np.array([0.0, 0.0, 1.0], np.float32)[:, None] * np.ones(N, np.float32)
    assert np.allclose(to_world(local, n), n, atol=1e-6)


@pytest.mark.parametrize('kind, width', [('BLACKMAN_HARRIS', 1.5), ('GAUSSIAN', 3.0), ('BOX', 1.0)])
def test_native_pixel_samples_equal_keys_uniforms_and_filter_lookup(kind, width):
    """The render loop draws path keys and filtered raster positions natively in one pass."""
    import dacrt
    from addon.filter import PixelFilter
    rs, filt = RandomStream(123), PixelFilter(kind, width)
    w = 1920
    pixel = np.arange(0, w * 1080, 37, dtype=np.int64)
    sample = (np.arange(len(pixel)) * 7919) % 4096
    keys, rx, ry = dacrt.shading.pixel_samples(pixel, sample, w, *rs.seed_words, *rs.dim_words(0), filt.table)
    ref = rs.path_keys(pixel, sample)
    assert np.array_equal(keys, ref)
    u1, u2 = rs.uniform2_numpy(ref, 0)
    first = sample == 0                   # Cycles: sample 0 reads the filter table at u = 0.5
    assert first.any() and not first.all()
    u1, u2 = np.where(first, np.float32(0.5), u1), np.where(first, np.float32(0.5), u2)
    ex, ey = filt.offsets(u1), filt.offsets(u2)
    # (half a table step off the centre, as Cycles' table of even size puts it: filter.py)
    centre = 0.5 * (filt.table[511] + filt.table[512])
    assert np.allclose(ex[first], centre, atol=1e-6) and np.allclose(ey[first], centre, atol=1e-6)
    ex += pixel % w
    ey += pixel // w
    assert np.array_equal(rx, ex) and np.array_equal(ry, ey)
    with pytest.raises(ValueError, match="2\\*\\*32"):
        dacrt.shading.pixel_samples(np.array([-1]), np.array([0]), w, 1, 2, 3, 4, filt.table)


@pytest.mark.parametrize('s0, ns', [(0, 1), (0, 3), (5, 7), (0, 64), (4000, 96), (0, 600), (1, 513)])
def test_block_samples_equal_pixel_samples_of_the_pairs(s0, ns):
    """The render loop's camera samples of a pixel-major block (every pixel for samples s0 ..
    s0 + ns - 1) are pixel_samples' of the (pixel, sample) pairs bit for bit, also where a
    thread's range or a chunk of sample words begins inside a pixel's run of samples."""
    import dacrt
    from addon.filter import PixelFilter
    rs, filt = RandomStream(7), PixelFilter('BLACKMAN_HARRIS', 1.5)
    w = 333
    rng = np.random.default_rng(ns)
    # enough paths for several threads' ranges (2**16 each) at the larger ns; pixels out of order
    pixels = rng.choice(w * 401, size=max(3, (1 << 17) // ns + 11), replace=False).astype(np.int64)
    pixels[:2] = [0, w * 401 - 1]
    keys, rx, ry = dacrt.shading.block_samples(pixels, s0, ns, w, *rs.seed_words, *rs.dim_words(0), filt.table)
    pixel = np.repeat(pixels, ns)
    sample = np.tile(np.arange(s0, s0 + ns, dtype=np.int64), len(pixels))
    ref = dacrt.shading.pixel_samples(pixel, sample, w, *rs.seed_words, *rs.dim_words(0), filt.table)
    assert keys.shape == (2, len(pixel)) and rx.shape == ry.shape == (len(pixel),)
    assert np.array_equal(keys, ref[0]) and np.array_equal(keys, rs.path_keys(pixel, sample))
    assert rx.view(np.uint32).tobytes() == ref[1].view(np.uint32).tobytes()
    assert ry.view(np.uint32).tobytes() == ref[2].view(np.uint32).tobytes()


def test_block_samples_refuse_pixels_and_samples_beyond_32_bits():
    import dacrt
    from addon.filter import PixelFilter
    table = PixelFilter('BOX', 1.0).table
    with pytest.raises(ValueError, match="2\\*\\*32"):
        dacrt.shading.block_samples(np.array([-1]), 0, 1, 8, 1, 2, 3, 4, table)
    with pytest.raises(ValueError, match="2\\*\\*32"):
        dacrt.shading.block_samples(np.array([3]), 2**32 - 2, 4, 8, 1, 2, 3, 4, table)
    with pytest.raises(ValueError, match="ns"):
        dacrt.shading.block_samples(np.array([3]), 0, 0, 8, 1, 2, 3, 4, table)
    keys, rx, ry = dacrt.shading.block_samples(np.zeros(0, np.int64), 0, 4, 8, 1, 2, 3, 4, table)
    assert keys.shape == (2, 0) and len(rx) == len(ry) == 0
