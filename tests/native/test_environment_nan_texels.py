"""An environment image's NaN or infinite texel channel (an HDRI's bad pixel, a script's write).
Cycles' bilinear lookup is not finite in that channel wherever it blends the texel in (the
four cells between texel centres around it, two texels by two) and its film's ensure_finite
drops it: so the map's lookups read 0 there in that channel, its other channels and everywhere
else unchanged ('Closest': the texel's own area). The export had zeroed the texel, which dims
only about its own area: a diffuse plane under a 16x8 map of 0.5 with one NaN R, Cycles 0.3774
(denoiser off, 64 spp), DACRT 0.3995, 0.4073 without the NaN (session 74's measurement).

Checked against closed forms: the radiance at every direction of a grid, and the mean of the
sampler's radiance / pdf, which is the map's integral over the sphere, 0.5 x (4 pi - the solid
angle lost) in that channel. The lane loops (gather, sample_lanes) give eval's and sample's bits."""

import numpy as np
import pytest
from dacrt import lamps

F32 = np.float32
H, W, I, J = 8, 16, 5, 3        # the map, the bad texel's row (from the bottom) and column


def _map(bad, channel):
    px = np.full((H, W, 4), 0.5, F32)
    px[I, J, channel] = bad
    return px


def _lost(u, v, closest):
    """Where the bad texel's channel reads 0: lookups that blend it in (REPEAT wrapping does
    not reach it from (I, J) = (5, 3) of 8 x 16)."""
    x, y = u * W, v * H
    if closest:
        return (np.floor(x) == J) & (np.floor(y) == I)
    return (np.abs(x - (J + 0.5)) < 1.0) & (np.abs(y - (I + 0.5)) < 1.0)


def _lost_solid_angle(closest):
    """The solid angle of _lost's region: (u width) 2 pi x (cos theta between its rows)."""
    r = 0.5 if closest else 1.0
    v0, v1 = (I + 0.5 - r) / H, (I + 0.5 + r) / H
    theta0, theta1 = np.pi * (1.0 - v1), np.pi * (1.0 - v0)     # theta = pi (1 - v)
    return 2.0 * np.pi * (2.0 * r / W) * (np.cos(theta0) - np.cos(theta1))


@pytest.mark.parametrize("bad, channel", [(np.nan, 0), (np.inf, 1), (-np.inf, 2)], ids=["nan-r", "inf-g", "-inf-b"])
@pytest.mark.parametrize("closest", [False, True], ids=["linear", "closest"])
def test_lookups_blending_a_bad_texel_read_0_in_its_channel(bad, channel, closest):
    env = lamps.environment_map(_map(bad, channel), None, "Closest" if closest else "Linear", scale=np.full(3, 2.0, F32))
    # a grid of directions off the texel and cell edges (u, v at 1/7 and 3/7 of a texel's step)
    u = (np.arange(4 * W) + 1.0 / 7.0) / (4 * W)
    v = (np.arange(4 * H) + 3.0 / 7.0) / (4 * H)
    u, v = [g.ravel() for g in np.meshgrid(u, v)]
    theta, phi = np.pi * (1.0 - v), np.pi * (1.0 - 2.0 * u)
    D = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]).astype(F32)
    Le, pdf = env.eval(D)
    want = np.full((3, len(u)), 1.0, F32)              # 0.5 x the strength 2
    lost = _lost(u, v, closest)
    want[channel, lost] = 0.0
    assert lost.sum() == (4 * 4 if closest else 8 * 8)
    np.testing.assert_allclose(Le, want, rtol=1e-6, atol=0)
    assert np.isfinite(pdf).all() and (pdf > 0).all()
    # the lane loop of rays that missed everything: eval's bits
    L = np.zeros((3, len(u)), F32)
    env.gather(0.0, np.ascontiguousarray(D), np.ones(len(u), bool), None, None, np.arange(len(u), dtype=np.int64), L)
    np.testing.assert_array_equal(L, Le)


@pytest.mark.parametrize("closest", [False, True], ids=["linear", "closest"])
def test_samples_integrate_the_map_without_the_lost_area(closest):
    env = lamps.environment_map(_map(np.nan, 0), None, "Closest" if closest else "Linear")
    n = 1 << 20
    rng = np.random.default_rng(4)
    u1, u2 = rng.random(n, dtype=F32), rng.random(n, dtype=F32)
    wi, value, pdf = env.sample(u1, u2)
    _, value_lanes, pdf_lanes = env.sample_lanes(u1, u2)
    np.testing.assert_array_equal(value_lanes.view(np.uint32), value.view(np.uint32))
    np.testing.assert_array_equal(pdf_lanes.view(np.uint32), pdf.view(np.uint32))
    assert np.isfinite(value).all()
    mean = value.astype(np.float64).mean(axis=1)      # radiance / pdf: the integral over the sphere
    np.testing.assert_allclose(mean[1:], 0.5 * 4.0 * np.pi, rtol=2e-3)
    lost = _lost_solid_angle(closest)
    want = 0.5 * (4.0 * np.pi - lost)
    # (the lost area is 1.6% (linear) of the sphere: the mean must tell it from 0.5 x 4 pi)
    assert abs(mean[0] - want) < 0.15 * 0.5 * lost, (mean[0], want, 0.5 * 4.0 * np.pi)
