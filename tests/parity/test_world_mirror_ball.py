"""An Environment Texture of projection Mirror Ball in the world, against Cycles: the ball's image
is resampled into an equirectangular map through Cycles' direction_to_mirrorball (the ball's
normal halfway between the direction and the view along +Y), which the environment light
blends and samples (export/world.py _mirror_ball_map). Its mean colour had stood in as a uniform
world, said: 0.73-1.56x Cycles per channel (fuzz 1549, 1570).

The scene: the procedural-world set-up (an equirectangular camera at the origin seeing every
direction, a grey ball lit by the world), the ball image a smooth colour field with a bright
spot, through a Mapping rotation, Linear and Closest."""

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _ball_image(n=64):
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n
    px = np.ones((n, n, 4))
    px[..., 0] = 0.2 + 0.8 * x
    px[..., 1] = 0.2 + 0.8 * y
    px[..., 2] = 0.3 + 0.5 * np.sin(6.0 * x) ** 2
    px[(x - 0.3) ** 2 + (y - 0.6) ** 2 < 0.01, :3] = 6.0
    import bpy
    img = bpy.data.images.new("Ball", n, n, float_buffer=True, alpha=True)
    img.pixels.foreach_set(px.astype(np.float32).ravel())
    img.pack()
    return img


@pytest.mark.parametrize('interpolation', ['Linear', 'Closest'])
def test_mirror_ball_world_agrees_with_cycles(interpolation, tmp_path, said):
    sc, world = scenes.panorama_world("MirrorBall", samples=16)
    scenes.environment_world(_ball_image(), 1.0, rotation=(0.3, -0.2, 0.8), interpolation=interpolation, scene=sc)
    env = next(n for n in sc.world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    env.projection = 'MIRROR_BALL'
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c.mean() > 0.1
    for axis in (0, 1):         # quarters of rows, then of columns
        for part in np.array_split(np.arange(d.shape[axis]), 4):
            np.testing.assert_allclose(np.take(d, part, axis).mean(axis=(0, 1)),
                                       np.take(c, part, axis).mean(axis=(0, 1)), rtol=0.03, atol=0.003,
                                       err_msg=f"axis {axis} {part[0]}-{part[-1]}")
    assert not [t for t in said if "mean colour used as a uniform world" in t], said
    assert [t for t in said if "resampled into a 1024 x 512 equirectangular map" in t], said
