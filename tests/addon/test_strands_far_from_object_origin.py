"""Hair tubes modelled far from their object's origin: a tube's vertices are its strand's centre
plus its ring's offset, and rounding them to float32 in object space (where the spacing at 1000
is 6.1e-5) put a hair 1e-4 across on a few grid points: rings of radius 0, 6.1e-5 or 8.6e-5,
some triangles of no area, and 3000 such strands covered 1.095x what Cycles' curves cover
(1.017x at the origin). The tessellation keeps them in float64 (meshes._anchored: float32
offsets from a float64 anchor placed by the object's matrix), so the tube has its shape and the
image is the image at the origin."""
import bpy
import numpy as np

from tests.parity import rendering

from . import scenes

R = 5e-5


def _hair(offset, n=1, seed=1):
    rng = np.random.default_rng(seed)
    base = np.stack([rng.uniform(-0.05, 0.05, n), np.zeros(n), rng.uniform(-0.05, 0.05, n)], 1) if n > 1 else \
        np.zeros((1, 3))
    curves = [b + np.outer(np.linspace(0, 1, 4), [0.0, 0.06, 0.0]) + np.asarray(offset) for b in base]
    return scenes.hair_curves('Hair', curves, radius=R, material=scenes.emission('e', (1, 1, 1), 1.0))


def test_a_thin_tube_far_from_its_origin_keeps_its_radius(scene, exported):
    _hair((1000.0, 0.0, 0.0))
    scenes.camera(location=(1000.0, 0.12, 0.0), rotation=(np.pi / 2, 0, np.pi))
    sd = exported()
    v = np.asarray(sd.geometry.vertices, np.float64)
    assert len(v) and len(sd.geometry.triangles)
    sides = len(v) // len(np.unique(np.round(v[:, 1], 9)))           # the rings lie across y
    ideal = R * np.pi / (sides * np.sin(np.pi / sides))              # hair.tubes' perimeter scale
    radius = np.hypot(v[:, 0] - 1000.0, v[:, 2])
    # at the origin the rings are exact to float32's rounding there (1e-11)
    assert np.abs(radius / ideal - 1.0).max() < 0.01, (radius.min(), radius.max(), ideal)


def test_hair_far_from_its_origin_renders_as_at_the_origin(scene):
    means = []
    for offset in (0.0, 1000.0):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        sc = bpy.context.scene
        sc.render.engine = 'DACRT'
        _hair((offset, 0.0, 0.0), n=1500)
        scenes.camera(location=(offset, 0.12, 0.0), rotation=(np.pi / 2, 0, np.pi))
        scenes.black_world()
        rendering.matched(sc, 16, 0)
        sc.render.resolution_x, sc.render.resolution_y = 48, 36
        means.append(scenes.render_rgba()[..., 0].mean())
    assert means[0] > 0.02, means
    assert abs(means[1] / means[0] - 1.0) < 0.01, means
