"""An Environment Texture whose texels the Background's Strength takes past float32's range (an
HDR's 1e30 sun at Strength 1e9): Cycles' radiance is infinite there and its film drops those
samples, as it drops an infinite texel's. The native map refused the product, so the render failed
("environment map: pixel value inf ... is negative or not finite"); those texels now read as an
infinite texel does (0 in the lookups blending them in), said."""
import numpy as np
import pytest

from . import scenes


def _world(scene, patch, strength):
    scenes.camera(location=(0, 0, 0), rotation=(1.2, 0, 0.3))
    px = np.full((16, 32, 4), 0.5, np.float32)
    px[6:9, 10:14, :3] = patch
    w = scenes.environment_world(scenes.float_image("Sun", px), strength)
    scene.world = w
    scene.dacrt.samples = 4
    return w


def test_texels_past_float32_at_the_strength_render_as_infinite_ones(scene):
    _world(scene, 1e30, 1e9)
    image = scenes.render_rgba(scene)
    assert np.isfinite(image).all() and image[..., :3].max() > 0
    _world(scene, np.inf, 1e9)
    assert np.array_equal(image, scenes.render_rgba(scene))


def test_the_overflow_is_said(scene, exported):
    _world(scene, 1e30, 1e9)
    data = exported()
    said = [t for _, t in data.messages if "12 pixel(s) at Strength 1e+09 beyond float32's range" in t]
    assert said, data.messages
    # (Cycles blends before the strength: only lookups weighing such a texel enough are infinite there;
    # the message had said its film drops them all)
    assert "infinite, samples its film drops, or near float32's largest" in said[0], said
    assert np.isnan(data.environment.pixels[7, 11, :3]).all()


@pytest.mark.parametrize('strength', [1.0, 5.0])
def test_an_ordinary_map_is_passed_as_it_is(scene, exported, strength):
    _world(scene, 4.0, strength)
    data = exported()
    assert data.environment.pixels.shape[-1] == 4        # (the image's own RGBA, not a copy)
    assert not any("beyond float32's range" in t for _, t in data.messages)
