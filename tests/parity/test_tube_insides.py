"""Hair and Curves tubes are open at their ends; Cycles' curves have no inside. A camera ray
entering a tube's open end met its inner wall in DACRT: a strand 9.5 degrees off the view axis
covered 1.28x what Cycles' curve covers, 3000 strands pointing at the camera 1.098x. Rays now
pass the insides of tube walls (integrator._past_tube_insides). Cycles still shows a little more
than the outside alone near end-on (0.93x here), not modelled."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _means(sc, tmp_path):
    return {e: rendering.mean_of(sc, e, tmp_path / f'{e}.exr') for e in ('CYCLES', 'DACRT')}


def _setup(sc, samples, width, height):
    scenes.black_world()
    rendering.matched(sc, samples, 0)
    sc.render.resolution_x, sc.render.resolution_y = width, height


def test_a_strand_seen_near_its_axis_shows_no_inside(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    t = np.linspace(0, 1, 4)[:, None]
    scenes.hair_curves('Hair', [t * [0.05, 0.3, 0.0]], radius=0.01, material=scenes.emission('e', (1, 1, 1), 1.0))
    scenes.camera(location=(0, 1, 0), rotation=(math.radians(90), 0, math.radians(180)))
    _setup(sc, 256, 32, 24)
    m = _means(sc, tmp_path)
    assert m['CYCLES'] > 1e-3, m
    assert abs(m['DACRT'] / m['CYCLES'] - 1.0) < 0.12, m


def test_hair_pointing_at_the_camera_covers_what_cycles_covers(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    rng = np.random.default_rng(1)
    base = np.stack([rng.uniform(-0.05, 0.05, 3000), np.zeros(3000), rng.uniform(-0.05, 0.05, 3000)], 1)
    t = np.linspace(0, 1, 4)[:, None]
    curves = [b + t * [0.0, 0.06, 0.0] + t ** 2 * [0.01, 0.0, 0.01] for b in base]
    scenes.hair_curves('Hair', curves, radius=5e-4, material=scenes.emission('e', (1, 1, 1), 1.0))
    scenes.camera(location=(0, 0.12, 0), rotation=(math.radians(90), 0, math.radians(180)))
    _setup(sc, 16, 48, 36)
    m = _means(sc, tmp_path)
    assert m['CYCLES'] > 0.3, m
    assert abs(m['DACRT'] / m['CYCLES'] - 1.0) < 0.04, m
