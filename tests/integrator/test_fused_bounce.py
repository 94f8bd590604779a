"""Diffuse vertices shaded by one native pass (Integrator._diffuse_vertex, dacrt.shading.shade_bounce)
give the image the general steps give (continue_paths, next_event, cosine_scatter and the steps
between them): the same random numbers in the same order, the same float32 operations, so the
same bits."""
import numpy as np
import pytest

import dacrt
import addon.integrator as integrator_module
from addon import scenedata as sd

from .scenes import (ALL_VIS, cornell_box, geometry, icosphere, light, material, ortho_down, plane_scene, render,
                     rotation_x, translation)


def _both(scene, monkeypatch):
    """(fused, general) renders of scene, and how many vertices the fused one shaded."""
    calls = []
    fused_pass = dacrt.shading.shade_bounce
    monkeypatch.setattr(dacrt.shading, 'shade_bounce', lambda *a, **k: calls.append(1) or fused_pass(*a, **k))
    fused = render(scene)
    monkeypatch.setattr(integrator_module, 'FUSED_BOUNCE', False)
    general = render(scene)
    return fused, general, len(calls)


def _same(fused, general):
    assert np.array_equal(fused.film.combined(), general.film.combined())
    assert fused.stats['rays'] == general.stats['rays']
    assert fused.stats['skipped'] == general.stats['skipped']


@pytest.mark.parametrize('area_light', [True, False])
def test_cornell_box_is_bit_identical(monkeypatch, area_light):
    """An area lamp (its lanes), or an emissive quad (triangle samples, MIS with BSDF hits)."""
    fused, general, calls = _both(cornell_box(40, 30, 16, 4, area_light=area_light), monkeypatch)
    assert calls > 0
    _same(fused, general)
    assert fused.film.combined()[..., :3].mean() > 0


def test_several_lights_and_a_light_tree_are_bit_identical(monkeypatch):
    """Light choice by pick (several entries) and by the tree; roulette past bounce 2."""
    scene = cornell_box(40, 30, 16, 6, area_light=True)
    scene.lights += [light('POINT', 5.0, translation(0.2, 0.3, 0.7)),
                     light('SPOT', 30.0, translation(0.8, 0.5, 0.9), spot_size=np.radians(60.0))]
    for tree in (True, False):
        scene.settings.use_light_tree = tree
        fused, general, calls = _both(scene, monkeypatch)
        monkeypatch.setattr(integrator_module, 'FUSED_BOUNCE', True)
        assert calls > 0
        _same(fused, general)


def test_smooth_normals_and_black_surfaces_are_bit_identical(monkeypatch):
    """Interpolated shading normals (directions below the geometric surface are dropped) and
    paths that end on a black surface."""
    v, t = icosphere(0.3, 2, (0.0, 0.0, 0.3))
    c = v[t] - np.array([0.0, 0.0, 0.3])              # the sphere's normal at each corner
    base = plane_scene([light('AREA', 30.0, translation(0.4, 0.0, 1.5), size_x=0.5, size_y=0.5)], samples=8,
                       max_bounces=3)
    plane = base.geometry
    both = geometry([(plane.vertices, plane.triangles, 2, ALL_VIS), (v, t, 1, ALL_VIS)])
    both.normals[len(plane.triangles):] = c / np.linalg.norm(c, axis=2, keepdims=True)
    base.geometry = both
    base.materials = [material('default'), material('ball', (0.7, 0.6, 0.5)), material('black', (0.0, 0.0, 0.0))]
    base.camera = ortho_down(height=2.0, width=32, px=32, view=1.2)
    fused, general, calls = _both(base, monkeypatch)
    assert calls > 0
    _same(fused, general)
    assert fused.stats['skipped']['detail']['bounce_rays_black'] > 0


@pytest.mark.parametrize('tree', [False, True])
def test_bounces_a_coarse_smooth_sphere_sends_below_its_surface_are_dropped_bit_identically(monkeypatch, tree):
    """A coarse sphere's interpolated normals send many bounce directions below its facets:
    the fused pass drops them in place (shading.drop_columns, with their ray records and, with
    a light tree, the normals the next vertex weighs lamps with), as the general steps do from
    their own arrays; the same bits, and the drop did happen in the fused pass."""
    v, t = icosphere(0.4, 0, (0.0, 0.0, 0.4))
    c = v[t] - np.array([0.0, 0.0, 0.4])
    base = plane_scene([light('AREA', 30.0, translation(0.4, 0.0, 1.5), size_x=0.5, size_y=0.5),
                        light('POINT', 3.0, translation(-0.5, 0.3, 0.9))], samples=8, max_bounces=3)
    base.settings.use_light_tree = tree
    plane = base.geometry
    both = geometry([(plane.vertices, plane.triangles, 0, ALL_VIS), (v, t, 1, ALL_VIS)])
    both.normals[len(plane.triangles):] = c / np.linalg.norm(c, axis=2, keepdims=True)
    base.geometry = both
    base.materials = [material('floor', (0.6, 0.6, 0.6)), material('ball', (0.7, 0.6, 0.5))]
    base.camera = ortho_down(height=2.0, width=32, px=32, view=1.2)
    drops = []
    drop = dacrt.shading.drop_columns
    # (the fused render's drops: the general steps drop through drop_columns too,
    # test_general_bounce_drop.py)
    monkeypatch.setattr(dacrt.shading, 'drop_columns',
                        lambda keep, *a, **k: (integrator_module.FUSED_BOUNCE and drops.append(
                            int(len(keep) - np.count_nonzero(keep)))) or drop(keep, *a, **k))
    fused, general, calls = _both(base, monkeypatch)
    assert calls > 0 and sum(drops) > 0
    assert fused.stats['skipped']['detail']['bounce_rays_below_surface'] == \
        general.stats['skipped']['detail']['bounce_rays_below_surface'] == sum(drops)
    _same(fused, general)


def _with_flags(scene, monkeypatch):
    """(rendered, rendered with the hit flags made at every vertex) and the vertices (k) that
    went without them in the first."""
    bare = set()
    unread = integrator_module.Integrator._flags_unread

    def counted(self, camera, path, sinks, k):
        if not unread(self, camera, path, sinks, k):
            return False
        bare.add(k)
        return True
    monkeypatch.setattr(integrator_module.Integrator, '_flags_unread', counted)
    flagless = render(scene)
    monkeypatch.setattr(integrator_module.Integrator, '_flags_unread', lambda self, *a: False)
    return flagless, render(scene), bare


@pytest.mark.parametrize('extra', ['none', 'point', 'sun', 'world', 'environment', 'emissive', 'camera_lamp'])
def test_vertices_without_hit_flags_are_bit_identical(monkeypatch, extra):
    """Where the hit flags (prim >= 0) are read by nothing the records cannot tell, none are
    made: the fused pass takes the records with a triangle as the hits, the gathers of the
    lamps, the sun, the world (a colour or a map) and the emissive triangles read them too
    (a miss is prim < 0). The image, ray counts and ended paths bit for bit those of the flags
    made; an area lamp the camera sees (its gather ends at each camera ray's end) keeps them at
    the camera vertex, and renders alike too."""
    scene = cornell_box(40, 30, 16, 4, area_light=extra != 'emissive')
    if extra != 'emissive':
        scene.lights[0].visible_camera = extra == 'camera_lamp'    # (Blender's default: unseen)
    if extra == 'point':
        scene.lights.append(light('POINT', 5.0, translation(0.2, 0.3, 0.7)))
    elif extra == 'sun':
        scene.lights.append(light('SUN', 2.0, rotation_x(-1.2), angle=0.1))
    elif extra == 'world':
        scene.world = np.array([0.3, 0.4, 0.5], np.float32)
    elif extra == 'environment':
        texels = (np.random.default_rng(5).random((8, 16, 3)) ** 3).astype(np.float32) * 4
        scene.environment = sd.Environment(texels, np.ones(3, np.float32), np.eye(3), 'Linear')
    flagless, flagged, bare = _with_flags(scene, monkeypatch)
    # the camera vertex, 4 bounces and the last segment's end (K + 1: lamps gathered only)
    assert bare == (set(range(1, 6)) if extra == 'camera_lamp' else set(range(6)))
    _same(flagless, flagged)
    assert flagless.film.combined()[..., :3].mean() > 0
