"""An environment map whose texels are near float's largest (native/cpp/envbuild.cpp): a texel's
luminance, the mean of its RGB, had been summed in float, so three channels of 3e38 made it inf,
every CDF NaN, and every sample's direction NaN (value 0, pdf 0); and a 'Linear' cell's
placement squared its corners' sums, NaN past ~9e18. The map now samples as the same map
scaled into range does."""

import numpy as np
import pytest
from dacrt import lamps

F32 = np.float32
DOWN = F32(2.0 ** -100)        # exact in float: a scaled map's tables differ only by rounding


def _patched(bright, h=16, w=32):
    """A dim map (1) with a bright patch of value `bright` in every channel."""
    px = np.ones((h, w, 3), F32)
    px[5:8, 10:14] = bright
    return px


def _uniforms(n=20000):
    rng = np.random.default_rng(7)
    return rng.random(n, dtype=F32), rng.random(n, dtype=F32)


def _draws(env):
    return env.sample(*_uniforms())


@pytest.mark.parametrize("interp", ["Linear", "Closest"])
@pytest.mark.parametrize("bright", [1e20, 3e38])   # 1e20: only the Linear cell's squares overflowed
def test_a_bright_patch_samples_as_the_map_scaled_into_range(interp, bright):
    px = _patched(bright)
    env = lamps.environment_map(px, None, interp)
    ref = lamps.environment_map(px * DOWN, None, interp)
    assert np.isfinite(env.total) and env.total == pytest.approx(ref.total / float(DOWN), rel=1e-6)
    wi, value, pdf = _draws(env)
    wi_ref, value_ref, pdf_ref = _draws(ref)
    assert np.isfinite(wi).all() and np.isfinite(pdf).all() and (pdf > 0).all()
    np.testing.assert_allclose(np.linalg.norm(wi, axis=0), 1.0, rtol=1e-5)
    np.testing.assert_allclose(wi, wi_ref, atol=1e-5)
    np.testing.assert_allclose(pdf, pdf_ref, rtol=1e-5)
    # value is radiance / pdf: the patch's share of the integral, within float
    assert np.isfinite(value).all()
    np.testing.assert_allclose(value.astype(np.float64) * float(DOWN), value_ref, rtol=1e-5)
    # the lanes' sampler and eval agree with the loop's
    wi_lanes, value_lanes, pdf_lanes = env.sample_lanes(*_uniforms())
    np.testing.assert_array_equal(wi_lanes, wi)
    np.testing.assert_array_equal(pdf_lanes, pdf)
    np.testing.assert_array_equal(value_lanes, value)
    L, pdf_eval = env.eval(wi)
    np.testing.assert_allclose(pdf_eval, pdf, rtol=1e-4)


def test_a_map_of_3e38_everywhere_samples_uniformly():
    """The stress helper's case: every texel 3e38. Directions and pdfs are the map of ones';
    value, radiance / pdf, 3e38 x the ones' (~4 pi), is inf where that is beyond float."""
    for interp in ("Linear", "Closest"):
        wi, value, pdf = _draws(lamps.environment_map(np.full((4, 8, 3), 3e38, F32), None, interp))
        wi_one, value_one, pdf_one = _draws(lamps.environment_map(np.ones((4, 8, 3), F32), None, interp))
        assert np.isfinite(wi).all(), interp
        np.testing.assert_allclose(wi, wi_one, atol=1e-5)
        np.testing.assert_allclose(pdf, pdf_one, rtol=1e-4)     # (w h / total is a float denormal)
        want = value_one.astype(np.float64) * float(F32(3e38))
        past = want > np.finfo(F32).max
        assert past.mean() > 0.9 and (value[past] == np.inf).all(), interp
        np.testing.assert_allclose(value[~past], want[~past], rtol=1e-4)


def test_an_srgb_patch_decoding_past_float_keeps_the_sampling_finite():
    """Encoded 1e30 decodes to inf: those lookups are inf (as Cycles'), and the importance reads
    the patch as float's largest value, so every direction and pdf stays finite and the rest of
    the map's values too."""
    env = lamps.environment_map(_patched(1e30), None, "Closest", srgb=True)
    wi, value, pdf = _draws(env)
    assert np.isfinite(wi).all() and np.isfinite(pdf).all() and (pdf > 0).all()
    L, _ = env.eval(wi)
    dim = np.isfinite(L).all(axis=0)
    assert dim.any() and np.isfinite(value[:, dim]).all()

