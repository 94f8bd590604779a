"""Coincident non-emissive faces are said (addon/coincidentfaces.py): a surface modelled twice
renders as one surface here and darker in Cycles (README "Coincident faces"), which had gone
unsaid unless the copies emitted (a mirrored cube under a grey world, 1 bounce: 1.094x
Cycles' image mean). Exact copies only (the same three float32 corners, any order or winding),
named by object, never for a near copy, the export's own ray-kind twins, a tube's own rounded
tip triangles, nor copies that emit (lightsetup says those)."""
from __future__ import annotations

import numpy as np

import dacrt
from addon import scenedata as sd
from addon.coincidentfaces import exact_groups, said_copies
from addon.surfacetables import OFFSET_ULPS, twins

from .scenes import ALL_VIS, geometry, material, ortho_down, quad, render

SAID = "coincide exactly with other triangles"
EMITTERS = "emissive triangles of"
FLOOR, BOX, LAMP, OTHER = 1, 2, 3, 4


def _box(center=(0.0, 0.0, 0.5), half=0.5):
    """A closed cube's (vertices, triangles), 12 triangles."""
    c = np.asarray(center, np.float64)
    v = c + half * np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64)
    t = np.array([(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
                  (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)], np.int64)
    return v, t


def _messages(parts):
    mats = [material('default'), material('floor'), material('box', (0.5, 0.5, 0.5)),
            material('lamp', (0.0, 0.0, 0.0), (5.0, 5.0, 5.0)), material('other', (0.2, 0.6, 0.2))]
    v, t = quad((0.0, 0.0, 0.0), 4.0, 4.0)
    scene = sd.SceneData(ortho_down(height=3.0, width=8, px=6, view=3.0), geometry([(v, t, FLOOR, ALL_VIS)] + parts),
                         mats, [], np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
    return [t for _, t in render(scene).messages]


def test_a_duplicated_box_is_said_once_naming_its_objects():
    box = (*_box(), BOX, ALL_VIS)
    assert not [m for m in _messages([box]) if SAID in m]
    got = [m for m in _messages([box, box]) if SAID in m]
    assert len(got) == 1 and got[0].startswith("24 triangles of 'object 1', 'object 2' coincide"), got
    assert "darker" in got[0] and "one surface" in got[0], got
    # a copy listed in another corner order and wound the other way is the same surface
    v, t = _box()
    got = [m for m in _messages([box, (v, t[:, ::-1], BOX, ALL_VIS)]) if SAID in m]
    assert len(got) == 1 and got[0].startswith("24 triangles of "), got


def test_only_the_copied_faces_are_counted_and_other_materials_are_said():
    v, t = _box()
    top = (v, t[2:4], OTHER, ALL_VIS)          # a second copy of two faces, another material
    got = [m for m in _messages([(v, t, BOX, ALL_VIS), top]) if SAID in m]
    assert len(got) == 1 and got[0].startswith("4 triangles of ") and "materials differ" in got[0], got


def test_near_copies_are_not_said():
    v, t = _box()
    for d in (1e-6, 1e-4):                     # moved by a few float32 ulps, and by 0.1 mm
        got = _messages([(v, t, BOX, ALL_VIS), (v + [0.0, 0.0, d], t, BOX, ALL_VIS)])
        assert not [m for m in got if SAID in m], (d, got)


def test_emissive_copies_keep_their_own_message_alone():
    v, t = quad((0.0, 0.0, 1.0), 0.5, 0.5, up=False)
    lamp = (v, t, LAMP, ALL_VIS)
    got = _messages([lamp, lamp])
    assert not [m for m in got if SAID in m], got
    assert len([m for m in got if EMITTERS in m and "coincide" in m]) == 1, got
    # a diffuse copy on the emitter: one set with an emitter, said by the emitters' message
    got = _messages([lamp, (v, t, BOX, ALL_VIS)])
    assert not [m for m in got if SAID in m], got


def test_copies_no_ray_kind_sees_alike_are_not_said():
    # the export's ray-type-mix twins: the clear side seen by camera rays, the original by the
    # others; a shadow-only copy under a camera-only one; zero-area copies
    v, t = _box()
    C, D, S = sd.VIS_CAMERA, sd.VIS_DIFFUSE, sd.VIS_SHADOW
    for a, b in ((C, D | S), (D | S, C), (C, C)):
        got = _messages([(v, t, BOX, a), (v, t, OTHER, b)])
        assert not [m for m in got if SAID in m], (a, b, got)
    flat = np.array([(0, 1, 2)], np.int64)
    line = np.array([(0, 0, 0.5), (1, 0, 0.5), (2, 0, 0.5)], np.float64)
    assert not [m for m in _messages([(line, flat, BOX, ALL_VIS)] * 2) if SAID in m]
    # shadow rays leaving a camera-seen copy meet a shadow-seen one: darker in Cycles, said
    got = [m for m in _messages([(v, t, BOX, C | S), (v, t, BOX, C | S)]) if SAID in m]
    assert len(got) == 1, got


def test_wholly_clear_copies_are_not_said_half_clear_ones_are():
    # a white Transparent BSDF twice renders as once in Cycles too (1.0 both, under a white
    # world); a half-clear one twice darker there (0.526 against 0.55)
    v, t = _box()
    for clear, says in ((1.0, False), (0.5, True)):
        mats = [material('default'), material('floor'),
                material('glassy', (0.1, 0.1, 0.1), transparency=np.full(3, clear, np.float32))]
        q, qt = quad((0.0, 0.0, 0.0), 4.0, 4.0)
        scene = sd.SceneData(ortho_down(height=3.0, width=8, px=6, view=3.0),
                             geometry([(q, qt, FLOOR, ALL_VIS), (v, t, 2, ALL_VIS), (v, t, 2, ALL_VIS)]),
                             mats, [], np.full(3, 0.5, np.float32), sd.Settings(samples=1, max_bounces=1))
        got = [m for _, m in render(scene).messages if SAID in m]
        assert len(got) == says, (clear, got)


def test_groups_are_exact_in_any_corner_order_and_twins_find_them_everywhere():
    # far from the origin as near it, and where a triangle's step keeps all its ULPs (the
    # keys had been written only where the step shrank: 50 of 350 copies found on a fuzz scene)
    rng = np.random.default_rng(5)
    # (half of them in one binade [1, 2) on every axis: a step that keeps all its ULPs)
    v = np.concatenate([rng.normal(size=(150, 3)) * [1.0, 50.0, 1e4],
                        rng.uniform(1.0, 2.0, size=(150, 3))]).astype(np.float32)
    v[5] = -0.0
    t = rng.integers(0, 300, size=(1000, 3)).astype(np.int32)
    t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])]
    copies = t[:100][:, [2, 0, 1]]
    copies[::2] = copies[::2, ::-1]
    t = np.concatenate([t, copies])
    v = np.concatenate([v, [[0.0, 0.0, 0.0]]]).astype(np.float32)       # +0 beside the -0 of vertex 5
    t = np.concatenate([t, np.where(t[:50] == 5, 300, t[:50])]).astype(np.int32)
    keys = np.empty(len(t), np.uint64)
    dacrt.shading.triangle_table(v, t, OFFSET_ULPS, keys=keys)
    cand = twins(keys)
    rows, group = exact_groups(v, t, cand)
    asc = np.argsort(rows)
    rows, group = rows[asc], group[asc]
    # float64 brute force: the sorted corner triples as tuples
    ref = {}
    for i, tri in enumerate(t):
        ref.setdefault(tuple(sorted(map(tuple, (v[tri] + np.float32(0.0)).tolist()))), []).append(i)
    want = sorted(i for same in ref.values() if len(same) > 1 for i in same)
    assert len(want) == 250                    # the 100 first ones, their 100 + 50 copies
    np.testing.assert_array_equal(rows, want)
    assert cand[want].all()
    for same in ref.values():
        assert len(set(group[np.searchsorted(rows, same)])) == 1 if len(same) > 1 else True
    # no set holds two different surfaces
    assert len(np.unique(group)) == sum(len(s) > 1 for s in ref.values())


def test_a_tubes_own_rounded_triangles_count_once():
    v = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0)], np.float32)
    t = np.zeros((3, 3), np.int32) + [0, 1, 2]
    rows, group = exact_groups(v, t, np.ones(3, bool))
    area, vis, emit = np.ones(3), np.full(3, ALL_VIS, np.uint8), np.zeros(3, bool)
    one, place = np.ones(3, bool), np.array([7, 7, 7])
    assert not said_copies(rows, group, area, vis, emit, (one, place)).any()
    place = np.array([7, 7, 8])                # another strand placement's copy: said
    assert said_copies(rows, group, area, vis, emit, (one, place)).all()
    assert said_copies(rows, group, area, vis, emit).all()
