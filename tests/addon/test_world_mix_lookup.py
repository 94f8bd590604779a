"""A blended world (addon/export/worldmix.py: a world Mix Shader with a textured factor, an Add of
two maps) resamples each map exactly as the environment light renders it alone: an sRGB image's
encoded texels blended then decoded, a channel blending in a NaN texel read as 0. (It had its own
lookup, which blended the decoded texels and zeroed a NaN texel before blending, so its
neighbours blended towards 0.)"""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.export import worldmix
from addon.lights.environment import EnvironmentLight
from addon.texture import srgb_to_linear

F32 = np.float32


def _env(kind):
    rng = np.random.default_rng(7)
    if kind == "srgb_bytes":
        enc = rng.integers(0, 256, (8, 16, 4), dtype=np.uint8)
        px = srgb_to_linear(enc[..., :3] / F32(255.0)).astype(F32)
        return sd.Environment(px, np.array([1.5, 1.0, 0.5], F32), np.eye(3), 'Linear', encoded=enc)
    px = rng.uniform(0.0, 2.0, (8, 16, 3)).astype(F32)
    px[3, 5, 1] = np.nan
    px[6, 2, 0] = np.inf
    return sd.Environment(px, np.ones(3, F32), np.eye(3), kind)


def _directions(n, seed=3):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("kind", ["srgb_bytes", "Linear", "Closest"])
def test_the_blend_reads_each_map_as_the_light_does(kind):
    env = _env(kind)
    d = _directions(4000)
    light = EnvironmentLight(env)
    _, want, _ = light.eval_miss(d.T)
    got = worldmix.environment_radiance(env, d)
    assert np.all(np.isfinite(got))
    np.testing.assert_array_equal(got, np.asarray(want, F32).T)


def test_an_even_blend_of_a_map_with_itself_is_the_map():
    """(1 - f) A + f A at the blended map's texel centres is A's own lookup there."""
    env = _env("srgb_bytes")
    grid = {}

    def directions_of(width, h):
        v = (np.arange(h) + 0.5) / h
        u = (np.arange(width) + 0.5) / width
        theta, phi = np.pi * (1.0 - v)[:, None], 2 * np.pi * (0.5 - u)[None, :]
        d = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                         np.cos(theta)), -1)
        grid['d'] = d
        return d

    out = worldmix.blended_map([(np.zeros(3), env), (np.zeros(3), env)], directions_of, 32,
                               factor=lambda d: np.full((len(d), 1), 0.3))
    want = worldmix.environment_radiance(env, grid['d'].reshape(-1, 3)).reshape(out.pixels.shape)
    np.testing.assert_allclose(out.pixels, want, rtol=2e-6, atol=1e-7)
