"""Emitters that repeat each other only up to rounding: a twin of an emissive quad 1e-6 below it
(or coincident after another transform) is not a bit-for-bit copy, so lights/coincident.py's
exact coincident_copies leaves both light-sampled and next-event estimation adds each copy's
emission: the quad and its twin 1e-6 below rendered 1.41x Cycles (64x48, 0 bounces, Cycles 512
spp 0.2280, DACRT 256 spp 0.3224; Cycles renders the quad alone), silently. near_copies finds
triangles repeated within a few float32 ulps, and the render says so (a WARNING naming the
objects). A quad turned 90 degrees splits along its other diagonal and is not found here (1.82x;
lights/overlap.py finds it: test_coplanar_overlapping_emitters.py)"""
import bpy
import numpy as np

from addon.lights import coincident

from . import scenes
from .emittertwins import lamp_scene, twin

SAID = "repeat other emissive triangles up to rounding"


def _quad(z=0.0, dz=0.0):
    v = np.array([[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]], np.float32)
    w = v.copy()
    w[:, 2] += np.float32(dz)
    return np.concatenate([v, w]), np.array([[0, 1, 2], [0, 2, 3]], np.int32)


def _near(v, t, emitters=None):
    mask, _ = coincident.near_copies(v, t, np.ones(len(t), bool) if emitters is None else emitters)
    return None if mask is None else np.flatnonzero(mask).tolist()


def test_copies_up_to_rounding_are_found_in_any_corner_order():
    v, t = _quad(1.5, -1e-6)
    twin = t + 4
    for other in (twin, np.roll(twin, 1, axis=1), twin[:, ::-1]):
        assert _near(v, np.concatenate([t, other])) == [0, 1, 2, 3]
    # exact copies are coincident_copies' (rendered as one surface), apart ones are no copies
    assert _near(v, np.concatenate([t, t[:, ::-1]])) is None
    assert _near(*_quad(1.5, -1e-3)[:1], np.concatenate([t, twin])) is None
    # only emitters are looked at
    assert _near(v, np.concatenate([t, twin]), np.array([1, 1, 0, 0], bool)) is None
    assert _near(v, np.concatenate([t, twin]), np.array([1, 0, 1, 0], bool)) == [0, 2]


def test_a_near_copy_among_many_emitters_is_found_and_a_grid_alone_is_not():
    n = 60
    xs = np.linspace(-2, 2, n + 1, dtype=np.float32)
    X, Y = np.meshgrid(xs, xs, indexing='ij')
    v = np.stack([X.ravel(), Y.ravel(), (0.05 * np.sin(3 * X)).ravel()], 1).astype(np.float32)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    t = np.concatenate([np.stack([i, i + n + 1, i + n + 2], -1).reshape(-1, 3),
                        np.stack([i, i + n + 2, i + 1], -1).reshape(-1, 3)]).astype(np.int32)
    assert _near(v, t) is None
    k = 1234
    moved = v[t[k]] + np.float32(2e-7)                      # a few ulps of the grid's extent
    tt = np.concatenate([t, [np.arange(len(v), len(v) + 3)[[1, 2, 0]]]])
    assert _near(np.concatenate([v, moved]), tt) == [k, len(t)]


def _scene(sc, dz):
    lamp = lamp_scene(sc, 1.5, 4)
    if dz is not None:
        twin(lamp, (0.0, 0.0, dz))
    sc.render.resolution_x, sc.render.resolution_y = 32, 24


def _said(said):
    said.clear()
    scenes.render_rgba()
    return [t for t in said if SAID in t]


def test_a_twin_just_below_the_lamp_is_said(scene, said):
    _scene(scene, -1e-6)
    got = _said(said)
    assert len(got) == 1 and got[0].startswith("4 emissive triangles of 'Lamp', 'Twin' "), got
    assert "twice as bright" in got[0], got


def test_the_lamp_alone_an_exact_twin_and_one_moved_apart_are_not(scene, said):
    for dz in (None, 0.0, 1e-3):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        bpy.context.scene.render.engine = 'DACRT'
        _scene(bpy.context.scene, dz)
        assert _said(said) == [], dz
        # (rendered by DACRT: the exact twin is said as coincident instead)
        assert (dz == 0.0) == any("coincide with other triangles" in t for t in said), (dz, said)
