"""The native Noise Texture kernel (dacrt.shading.noise_texture, used by addon/procedural.py)
against a float32 numpy reference written operation by operation from Cycles' formulas
(noise_reference.py): the same bits, for 2D and 3D, fractional and whole Detail, distortion,
normalisation on and off, per-point parameters and points far from the origin. Cycles itself
checks both in tests/parity/test_procedural.py."""
import dacrt
import numpy as np
import pytest

from . import noise_reference as ref

SETTINGS = {    # scale, detail, roughness, lacunarity, distortion, normalize
    'default': (5.0, 2.0, 0.5, 2.0, 0.0, True),
    'fractional_distorted': (3.3, 3.5, 0.6, 2.7, 0.7, True),
    'one_octave_raw': (1.0, 0.0, 0.5, 2.0, 2.0, False),
    'fifteen_octaves_clamped': (2.0, 40.0, 1.2, 0.8, -1.0, False),
    'negative_roughness_and_scale': (-2.5, 1.25, -0.3, 2.0, 0.0, True),
}


@pytest.mark.parametrize('dims', [2, 3])
@pytest.mark.parametrize('case', sorted(SETTINGS))
def test_native_noise_matches_the_reference_bit_for_bit(case, dims):
    rng = np.random.default_rng(len(case) + dims)
    p = ((rng.random((20000, 3)) - 0.5) * 40).astype(np.float32)
    p[:100] *= 1e4                                   # far from the origin too
    scale, detail, rough, lac, dist, norm = SETTINGS[case]
    f0, c0 = ref.noise_texture(p, scale, detail, rough, lac, dist, norm, dims, True)
    f1, c1 = dacrt.shading.noise_texture(p[:, :dims], scale, detail, rough, lac, dist, norm, True)
    np.testing.assert_array_equal(f1, f0)
    np.testing.assert_array_equal(c1, c0)
    assert np.ptp(f1) > 0.3                         # the noise varies over these points
    f2, c2 = dacrt.shading.noise_texture(p[:, :dims], scale, detail, rough, lac, dist, norm, False)
    assert c2 is None and np.array_equal(f2, f1)


@pytest.mark.parametrize('kind', ['MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN'])
@pytest.mark.parametrize('dims', [2, 3])
def test_multifractals_match_the_reference_bit_for_bit(kind, dims):
    rng = np.random.default_rng(dims + len(kind))
    n = 20000
    p = ((rng.random((n, 3)) - 0.5) * 20).astype(np.float32)
    # per point: Detail (whole on some: no fractional octave), Roughness, Lacunarity, Offset, Gain
    detail = rng.uniform(0, 6, n).astype(np.float32)
    detail[::5] = np.floor(detail[::5])
    rough, lac = rng.uniform(0, 1, n).astype(np.float32), rng.uniform(1.5, 3, n).astype(np.float32)
    offset, gain = rng.uniform(-0.5, 1.5, n).astype(np.float32), rng.uniform(0, 3, n).astype(np.float32)
    for normalize in (True, False):                 # (read by fBM only)
        f0, c0 = ref.noise_texture(p, 3.0, detail, rough, lac, 0.3, normalize, dims, True, kind, offset, gain)
        f1, c1 = dacrt.shading.noise_texture(p[:, :dims], 3.0, detail, rough, lac, 0.3, normalize, True, kind,
                                             offset, gain)
        np.testing.assert_array_equal(f1, f0)
        np.testing.assert_array_equal(c1, c0)
    assert np.ptp(f1) > 0.3


def test_per_point_parameters_are_each_points_own():
    rng = np.random.default_rng(9)
    n = 5000
    p = (rng.random((n, 3)) * 8).astype(np.float32)
    params = [rng.uniform(lo, hi, n).astype(np.float32) for lo, hi in ((0.5, 6), (0, 4), (0, 1), (1.5, 3), (-1, 1))]
    params[1][::7] = np.floor(params[1][::7])       # whole Detail on some points: no fractional octave
    params[4][::3] = 0.0                            # no distortion on some
    f0, c0 = ref.noise_texture(p, *params, True, 3, True)
    f1, c1 = dacrt.shading.noise_texture(p, *params, True, True)
    np.testing.assert_array_equal(f1, f0)
    np.testing.assert_array_equal(c1, c0)


def test_non_finite_points_give_nan_and_a_nan_detail_one_octave():
    """A NaN or infinite point gives NaN, as Cycles 5.0.1's snoise passes it on (measured: a
    point whose third octave overflows to inf renders black in Cycles; it had read Perlin noise
    0 here, an ensure_finite Cycles does not apply, grey 0.5); a NaN Detail is one octave;
    nothing reads out of bounds."""
    p = np.array([[np.nan, 0.2, 0.3], [np.inf, 1.0, 2.0], [0.3, 0.4, 0.5]], np.float32)
    f, c = dacrt.shading.noise_texture(p, 5.0, [2.0, np.nan, 2.0], 0.5, 2.0, 0.0, True, True)
    assert np.isnan(f[:2]).all() and np.isnan(c[:2]).all()
    assert np.isfinite(f[2]) and np.isfinite(c[2]).all()
    one, _ = dacrt.shading.noise_texture(p[2:], 5.0, 0.0, 0.5, 2.0, 0.0, True, False)
    nan_detail, _ = dacrt.shading.noise_texture(p[2:], 5.0, np.nan, 0.5, 2.0, 0.0, True, False)
    assert nan_detail[0] == one[0]


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="points must have shape"):
        dacrt.shading.noise_texture(np.zeros((4, 5), np.float32), 1.0, 2.0, 0.5, 2.0, 0.0, True, False)
    with pytest.raises(ValueError, match="kind must be one of"):
        dacrt.shading.noise_texture(np.zeros((4, 3), np.float32), 1.0, 2.0, 0.5, 2.0, 0.0, True, False, 'PERLIN')
    with pytest.raises(ValueError, match="scale must have shape"):
        dacrt.shading.noise_texture(np.zeros((4, 3), np.float32), np.ones(3), 2.0, 0.5, 2.0, 0.0, True, False)
