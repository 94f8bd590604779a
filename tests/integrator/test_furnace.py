"""Bounce semantics (Cycles: max_bounces K gives up to K+1 diffuse reflections) in a furnace:
inside a closed sphere with emission 1 and albedo 0.5 every path sees
L = sum_{k=0..K+1} 0.5^k (reference blender-cycles.md 2.5, Cycles: 1.4995 / 1.7496 / 1.8748 /
1.9682). Exercises NEE on emissive triangles, MIS, Russian roulette and the self-intersection
offset at once: every shadow ray must reach the emitter, every bounce ray must leave the wall."""
import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, icosphere, material, pixel_stats, render


def furnace(K, samples=32, seed=0):
    v, t = icosphere(radius=1.0, subdiv=2)
    cam = sd.Camera('PERSP', np.eye(4), (-1.0, 1.0, -1.0, 1.0), 0.8, 0.01, 10.0, 16, 16)
    mats = [material('default'), material('furnace', (0.5, 0.5, 0.5), (1.0, 1.0, 1.0))]
    return sd.SceneData(cam, geometry([(v, t, 1, ALL_VIS)]), mats, [], np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=K, seed=seed, filter_type='BOX'))


@pytest.mark.parametrize('K', [0, 1, 2, 4])
def test_furnace(K):
    expected = sum(0.5 ** k for k in range(K + 2))
    integ = render(furnace(K, samples=64))
    mean, err = pixel_stats(integ)
    assert err < 0.003 * expected
    assert mean == pytest.approx(expected, rel=0.01)
    assert integ.film.nan_dropped == 0
    if K == 0:
        # K = 0 is direct light only: no bounce beyond the last BSDF ray
        assert integ.stats['rays']['bounce'] <= integ.stats['rays']['camera']


def test_furnace_offset_never_leaks():
    """A closed sphere: no camera, bounce or shadow ray may escape or be stopped by the wall it
    leaves (the world is bright, so an escaping ray would add light)."""
    scene = furnace(1, samples=16)
    scene.world = np.array([100.0, 100.0, 100.0], np.float32)
    integ = render(scene)
    mean, err = pixel_stats(integ)
    assert mean == pytest.approx(1.75, rel=0.01)
