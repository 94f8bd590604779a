"""Coincident faces: a surface modelled twice (duplicated faces, as real scenes have: Sibenik
holds 215 groups of identical triangles) renders as that one surface.

Camera rays meeting both copies take the lower triangle index (exact ties), and a ray leaving
either copy starts off the shared plane (self-intersection offset), so it never meets the
twin. Cycles renders such a surface black: its bounce ray skips only the triangle it leaves,
meets the twin at t ~ 0 and alternates between the two until the bounces run out (README,
"Comparing with Cycles"). These tests pin DACRT's behaviour: the image of a box whose floor,
and back wall are duplicated is the image of the box without the copies.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from addon import scenedata as sd

from .scenes import cornell_box, render


def _with_copies(scene: sd.SceneData, tris: np.ndarray, rotate: bool) -> sd.SceneData:
    """scene with copies of triangles `tris` appended (same vertices, material and visibility;
    with `rotate` the copy lists its corners cyclically shifted: same winding, other order)."""
    g = scene.geometry
    t, n = g.triangles[tris], g.normals[tris]
    if rotate:
        t, n = np.roll(t, 1, axis=1), np.roll(n, 1, axis=1)
    geo = replace(g, triangles=np.concatenate([g.triangles, t]),
                  material=np.concatenate([g.material, g.material[tris]]),
                  normals=np.concatenate([g.normals, n]),
                  visibility=np.concatenate([g.visibility, g.visibility[tris]]),
                  object_index=np.concatenate([g.object_index, g.object_index[tris]]))
    return replace(scene, geometry=geo)


# the floor (triangles 0, 1) and the back wall (4, 5): reflectors only (duplicated emitters:
# test_coincident_emitters.py)
_DUPLICATED = np.array([0, 1, 4, 5])


def _pair(area_light: bool, rotate: bool):
    base = cornell_box(width=24, height=18, samples=8, area_light=area_light)
    if area_light:
        base = replace(base, world=np.full(3, 0.3, np.float32))
    copied = _with_copies(base, _DUPLICATED, rotate)
    return render(base).film.combined(), render(copied).film.combined()


def test_exact_copies_render_as_one_surface():
    # the same paths to float rounding: the copies step their whole 8 ULPs off the surface
    # (surfacetables.coincident), the single surface only its error along the normal (ULPs of
    # the floor's z = 0), so their rays start some 1e-6 apart (they had been bit-identical)
    for area_light in (False, True):      # an emissive quad, or an area lamp + a world (shadow rays)
        single, doubled = _pair(area_light, rotate=False)
        assert single.mean() > 0.01
        np.testing.assert_allclose(doubled, single, rtol=1e-5, atol=1e-6 * float(np.abs(single).max()))


def test_copies_in_another_corner_order_render_the_same_surface():
    # t of the copy may differ from the original's in the last bit, so either can be hit;
    # both are the same surface with the same material, so only rounding can differ
    single, doubled = _pair(area_light=False, rotate=True)
    assert single.mean() > 0.01
    np.testing.assert_allclose(doubled.mean(axis=(0, 1)), single.mean(axis=(0, 1)), rtol=1e-3)
    assert np.mean(np.abs(doubled - single) > 1e-3 * np.abs(single).max()) < 0.01


def test_twins_are_found_in_any_corner_order_and_keep_the_whole_step():
    """surfacetables.twins marks both copies (also listed in another corner order, or with
    -0 for 0), nothing else; the table then gives them the whole step along the normal, which a
    ray leaving one copy needs to clear the other (the float test errs by ULPs of the copy's
    coordinates along the ray), while the other triangles of the plane z = 0 step ULPs of 0."""
    import dacrt
    from addon.surfacetables import OFFSET_ULPS, Triangles, twins
    v = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, -0.0), (2, 0, 0), (0, 0, 0)], np.float32)
    t = np.array([(0, 1, 2), (0, 2, 3), (1, 4, 2), (2, 0, 1), (5, 1, 2), (1, 2, 4)], np.int32)
    keys = np.empty(len(t), np.uint64)
    dacrt.shading.triangle_table(v, t, OFFSET_ULPS, keys=keys)
    np.testing.assert_array_equal(twins(keys), [True, False, True, True, True, True])
    scene = cornell_box(width=4, height=3, samples=1)
    geometry = replace(scene.geometry, vertices=v.astype(np.float64), triangles=t,
                       material=np.ones(6, np.int32), normals=np.zeros((6, 3, 3), np.float32) + (0, 0, 1),
                       visibility=np.full(6, scene.geometry.visibility[0]), object_index=np.zeros(6, np.int32),
                       uvs=None)
    steps = np.linalg.norm(Triangles(geometry, []).geo[12:15].astype(np.float64), axis=0)
    top = np.array([1.0, 1.0, 2.0, 1.0, 1.0, 2.0], np.float32)     # each one's largest coordinate
    whole = float(OFFSET_ULPS) * np.spacing(top).astype(np.float64)
    np.testing.assert_allclose(steps[[0, 2, 3, 4, 5]], whole[[0, 2, 3, 4, 5]], rtol=1e-6)
    assert 0 < steps[1] < 1e-30
