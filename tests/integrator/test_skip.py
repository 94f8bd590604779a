"""Work the renderer skips because it cannot change the image: each skip leaves the image as it
is (exactly, where the skipped work would only have added zeros; the random numbers are keyed
by path vertex, so skipping one path's work never moves another's) while the counters in
Integrator.stats['skipped'] show the work saved."""
import numpy as np
import pytest

import addon.integrator as integrator_module
from addon import scenedata as sd

from .scenes import ALL_VIS, cornell_box, geometry, light, plane_scene, quad, render, translation


def _both(scene, monkeypatch):
    """Render with the skips and with every skip disabled (SKIP_WORK = False)."""
    fast = render(scene)
    monkeypatch.setattr(integrator_module, 'SKIP_WORK', False)
    slow = render(scene)
    monkeypatch.setattr(integrator_module, 'SKIP_WORK', True)
    return fast, slow


def test_black_surfaces_end_paths_without_changing_the_image(monkeypatch):
    scene = cornell_box(40, 30, 16, 4, area_light=True)
    scene.materials[2].base_color = np.zeros(3, np.float32)          # the red wall turns black
    fast, slow = _both(scene, monkeypatch)
    assert np.array_equal(fast.film.combined(), slow.film.combined())
    done = fast.stats['skipped']
    assert done['detail']['bounce_rays_black'] > 1000
    assert fast.stats['rays']['bounce'] < slow.stats['rays']['bounce']
    assert fast.stats['rays']['shadow'] < slow.stats['rays']['shadow']


def test_translucent_surfaces_keep_the_skips_exact(monkeypatch):
    """A wall of black reflection but translucent (diffuse transmission) is not a black surface:
    its paths go on, and the skips (light samples behind a side, black walls) leave the image
    as every piece of work would."""
    scene = cornell_box(40, 30, 16, 4, area_light=True)
    scene.materials[2].base_color = np.zeros(3, np.float32)
    scene.materials[2].translucency = np.full(3, 0.6, np.float32)
    scene.materials[3].base_color = np.zeros(3, np.float32)        # and a truly black one
    fast, slow = _both(scene, monkeypatch)
    assert np.array_equal(fast.film.combined(), slow.film.combined())
    assert fast.stats['skipped']['detail']['bounce_rays_black'] > 0
    assert fast.film.combined()[..., :3].mean() > 0


def test_light_samples_that_cannot_contribute_cast_no_shadow_ray(monkeypatch):
    # a spot light aimed away from most of the plane, and a point light below it: most light
    # samples are outside the cone or behind the surface
    # (with the global choice: the light tree would not pick the point below the surface)
    lights = [light('SPOT', 500.0, translation(z=3.0), spot_size=np.radians(30.0)),
              light('POINT', 50.0, translation(z=-2.0))]
    scene = plane_scene(lights, samples=16, max_bounces=0, use_light_tree=False)
    fast, slow = _both(scene, monkeypatch)
    assert np.array_equal(fast.film.combined(), slow.film.combined())
    # (the light choice favours the spot, which delivers; the point below still gets its
    # uniform share of samples, none of which can contribute)
    assert fast.stats['skipped']['shadow_rays'] > 0.05 * slow.stats['rays']['shadow']
    assert fast.stats['rays']['shadow'] + fast.stats['skipped']['shadow_rays'] == slow.stats['rays']['shadow']
    # the tree sends no sample to the light below the plane's horizon: fewer wasted
    tree_fast, tree_slow = _both(plane_scene(lights, samples=16, max_bounces=0), monkeypatch)
    assert np.array_equal(tree_fast.film.combined(), tree_slow.film.combined())
    assert tree_fast.stats['skipped']['shadow_rays'] < 0.5 * fast.stats['skipped']['shadow_rays']


def test_last_bounce_ray_not_cast_when_nothing_it_could_hit_emits(monkeypatch):
    # a point light (radius 0: only light sampling finds it) in a box without emitters: the
    # BSDF ray after the last vertex could only collect emission
    scene = cornell_box(32, 24, 8, 1)
    scene.materials[4].emission = np.zeros(3, np.float32)
    scene.lights = [light('POINT', 20.0, translation(0.5, 0.5, 0.8))]
    fast, slow = _both(scene, monkeypatch)
    assert np.array_equal(fast.film.combined(), slow.film.combined())
    assert fast.stats['skipped']['detail']['bounce_rays_last_bounce'] > 0
    assert fast.stats['rays']['bounce'] < slow.stats['rays']['bounce']


def test_triangles_no_cast_ray_can_meet_are_left_out():
    v, t = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    rv, rt = quad((0.0, 0.0, 1.0), 5.0, 5.0, up=False)
    # a roof only shadow rays see: under a sun it casts shadows and stays ...
    lit = plane_scene([light('SUN', 3.0, np.eye(4))], samples=4, max_bounces=2)
    lit.geometry = geometry([(v, t, 1, ALL_VIS), (rv, rt, 1, sd.VIS_SHADOW)])
    assert render(lit).stats['skipped']['detail']['triangles_unreachable'] == 0
    # ... without any light no shadow ray is cast, and it is in no tracer scene
    dark = plane_scene([], samples=4, max_bounces=2)
    dark.geometry = lit.geometry
    c = render(dark)
    assert c.stats['skipped']['detail']['triangles_unreachable'] == 2
    assert c.stats['tracer_scenes'] == 1 and not c.film.combined()[..., :3].any()
    # diffuse-only triangles when no bounce ray is cast (K = 0, no emitter for BSDF rays)
    lamp = [light('POINT', 100.0, translation(z=2.0))]
    direct = plane_scene(lamp, samples=4, max_bounces=0)
    direct.geometry = geometry([(v, t, 1, ALL_VIS), (rv, rt, 1, sd.VIS_DIFFUSE)])
    d = render(direct)
    assert d.stats['skipped']['detail']['triangles_unreachable'] == 2
    plain = render(plane_scene(lamp, samples=4, max_bounces=0))
    assert np.array_equal(d.film.combined(), plain.film.combined())


def test_skip_summary_adds_export_counts():
    scene = plane_scene([light('POINT', 0.0, translation(z=2.0)), light('POINT', 10.0, translation(z=2.0))],
                        samples=2)
    scene.skipped = dict(objects_hidden=2, objects_invisible=1, objects_unsupported=1, materials_unused=3,
                         triangles_degenerate=5, triangles_nonfinite=4)
    s = render(scene).stats['skipped']
    assert s['objects'] == 4 and s['materials'] == 3 and s['lights'] == 1
    assert s['triangles'] == 9
    assert s['detail']['objects_hidden'] == 2
