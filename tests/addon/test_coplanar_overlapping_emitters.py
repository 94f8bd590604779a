"""Emitters that overlap in their plane without repeating each other corner for corner: a twin
of an emissive quad sharing its mesh, turned 90 degrees, splits along the other diagonal, so no
triangle repeats another and neither coincident_copies nor near_copies finds it; both stay
light-sampled and next-event estimation adds the emission twice where BSDF hits count one
surface (1.82x Cycles, README "Coincident faces"), silently. lights/overlap.py finds them (and
panels laid over part of each other), and the render says so, naming the objects; a lamp alone,
lamps edge to edge, a grid, and a twin moved apart are not said."""
import math

import bpy
import numpy as np

from addon.lights.overlap import coplanar_overlaps

from . import scenes
from .emittertwins import lamp_scene, twin

SAID = "overlap other emissive triangles in their plane"


def _found(v, t, emitters=None):
    mask, _ = coplanar_overlaps(np.asarray(v, np.float32), np.asarray(t, np.int32),
                                np.ones(len(t), bool) if emitters is None else np.asarray(emitters, bool))
    return None if mask is None else np.flatnonzero(mask).tolist()


QUAD = np.array([[0, 0, 1.5], [1, 0, 1.5], [1, 1, 1.5], [0, 1, 1.5]], np.float32)
SPLIT, OTHER = np.array([[0, 1, 2], [0, 2, 3]]), np.array([[0, 1, 3], [1, 2, 3]])


def _two(w, first=SPLIT, second=OTHER):
    return np.concatenate([QUAD, w]), np.concatenate([first, second + 4])


def test_a_quad_split_along_the_other_diagonal_is_found_and_neighbours_are_not():
    assert _found(*_two(QUAD)) == [0, 1, 2, 3]
    assert _found(*_two(QUAD + np.float32([3e-7, -3e-7, 3e-7]))) == [0, 1, 2, 3]    # a few ulps off
    # in part: the first triangle meets the second quad at a corner only
    assert _found(*_two(QUAD + np.float32([0.5, 0.5, 0]), OTHER, SPLIT)) == [1, 2, 3]
    assert _found(QUAD, SPLIT) is None
    assert _found(*_two(QUAD + np.float32([1, 0, 0]))) is None                   # edge to edge
    assert _found(*_two(QUAD + np.float32([0, 0, 1e-3]))) is None                # apart
    # only emitters count, and only as many as overlap
    assert _found(*_two(QUAD), emitters=[1, 1, 0, 0]) is None
    assert _found(*_two(QUAD, SPLIT, SPLIT[:1]), emitters=[1, 1, 1]) == [0, 2]


def test_a_wavy_emissive_grid_has_no_overlaps():
    n = 60
    xs = np.linspace(-2, 2, n + 1, dtype=np.float32)
    X, Y = np.meshgrid(xs, xs, indexing='ij')
    v = np.stack([X.ravel(), Y.ravel(), (0.05 * np.sin(3 * X)).ravel()], 1)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    t = np.concatenate([np.stack([i, i + n + 1, i + n + 2], -1).reshape(-1, 3),
                        np.stack([i, i + n + 2, i + 1], -1).reshape(-1, 3)])
    assert _found(v, t) is None
    # a folded strip (faces meeting at an angle along a shared edge) neither
    fold = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 2, 0.01], [1, 2, 0.01]], np.float32)
    assert _found(fold, [[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4]]) is None


def _scene(sc, placed=None):
    lamp = lamp_scene(sc, 1.5, 4)
    if placed is not None:
        (dx, dz), turn = placed
        twin(lamp, (dx, 0.0, dz), turn)
    sc.render.resolution_x, sc.render.resolution_y = 32, 24


def _said(said):
    said.clear()
    scenes.render_rgba()
    return [t for t in said if SAID in t]


def test_a_twin_turned_90_degrees_is_said(scene, said):
    _scene(scene, ((0.0, 0.0), math.pi / 2))
    got = _said(said)
    assert len(got) == 1 and got[0].startswith("4 emissive triangles of 'Lamp', 'Twin' "), got
    assert "twice as bright" in got[0], got


def test_lamps_apart_alone_or_near_copies_are_not_said_as_overlapping(scene, said):
    for placed in (None, ((1.0, 0.0), 0.0), ((0.0, 1e-3), math.pi / 2), ((0.0, -1e-6), 0.0)):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        bpy.context.scene.render.engine = 'DACRT'
        _scene(bpy.context.scene, placed)
        assert _said(said) == [], (placed, said)
    # (the near copy 1e-6 below is said once, by its own message)
    assert sum("repeat other emissive triangles up to rounding" in t for t in said) == 1, said
