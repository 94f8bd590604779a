"""Point clouds and hair curves against Cycles, which renders them as exact spheres and round
curves where DACRT traces tessellations (addon/pointcloud.py, addon/hair.py).

Both scenes are lit by a sun and a white world and seen by an orthographic camera on a
transparent film: the mean alpha measures the area the primitives cover, the mean colour the
light they catch (direct, and the world through their bounces). Before, point clouds, Curves
objects and hair particle systems were skipped (nothing rendered).
"""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 96
    sc.render.film_transparent = True
    scenes.camera(location=(0, -6, 0), rotation=(math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=3.0)
    scenes.world((1, 1, 1), 0.5)
    scenes.light('SUN', 3.0, rotation=(0.6, 0.4, 0.3))
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 3
    sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    # Cycles' 3D Curves, the round tubes DACRT tessellates (its Rounded Ribbons agree within
    # 0.5% for round strands, but render the elliptic strands of a scaled emitter 3% darker)
    sc.cycles_curves.shape = 'THICK'
    return sc


def _points():
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.1, 1.1, (40, 3)) * (1, 0.3, 1)
    scenes.point_cloud("Dots", pts, radius=0.18, material=scenes.diffuse("Orange", (0.8, 0.5, 0.2)))


def _curves():
    rng = np.random.default_rng(5)
    t = np.linspace(0, 1, 8)
    curves = []
    for _ in range(30):   # wavy strands, mostly vertical, so they overlap and shadow each other
        x0, y0, ph = rng.uniform(-1.2, 1.2), rng.uniform(-0.5, 0.5), rng.uniform(0, 2 * np.pi)
        curves.append(np.stack([x0 + 0.25 * np.sin(4 * t + ph), y0 + 0.2 * np.cos(3 * t + ph), -1.2 + 2.4 * t], 1))
    scenes.hair_curves("Strands", curves, radius=0.04, material=scenes.diffuse("Blue", (0.3, 0.6, 0.9)))


def _particle_hair():
    """A hair particle system with interpolated children and a tapered, closed tip, on a
    non-uniformly scaled emitter that is not rendered itself (Cycles makes the strands round in
    the emitter's object space: elliptic here, which renders them 7-12% brighter)."""
    em = scenes.plane("Emitter", size=2, materials=[scenes.diffuse("Skin", (0.2, 0.2, 0.2)),
                                                    scenes.diffuse("Fur", (0.9, 0.6, 0.3))])
    em.location, em.scale = (0, 0, -0.6), (1, 0.3, 1)
    em.show_instancer_for_render = False
    em.modifiers.new("Hair", 'PARTICLE_SYSTEM')
    s = em.particle_systems[0].settings
    s.type, s.count, s.hair_length, s.material = 'HAIR', 200, 0.8, 2
    s.root_radius, s.tip_radius, s.radius_scale, s.use_close_tip = 1.0, 0.3, 0.05, True
    s.child_type, s.rendered_child_count, s.child_percent = 'INTERPOLATED', 10, 10


@pytest.mark.parametrize('build', [_points, _curves, _particle_hair], ids=['point_cloud', 'hair_curves', 'particle_hair'])
def test_points_and_curves_cover_and_catch_light_as_in_cycles(build, tmp_path):
    sc = _scene()
    build()
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGBA'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    assert 0.1 < c[3] < 0.6, f"coverage {c[3]}: the primitives must fill part of the frame"
    np.testing.assert_allclose(d[3], c[3], rtol=0.01, err_msg="covered area (alpha)")
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.01, err_msg="colour")
