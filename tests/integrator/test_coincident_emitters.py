"""Coincident emitters (lights/coincident.py): an emissive quad modelled twice (a duplicated
import, a Mirror applied twice, a second object sharing the mesh in place) is one surface, as
coincident reflectors are (test_coincident.py): BSDF and camera hits return the lower-index
copy, so light sampling picks that copy alone. Its twin had been light-sampled as well, which
added its emission again: a floor under the quad and its twin 1.42x the single quad (2.1x
Cycles, which renders coincident faces darker; README "Coincident faces render as one
surface"). Where the lower-index copy does not emit, the surface does not.

The scene: a floor lit by a 1 m quad facing down 1 m above it, an orthographic camera under
the quad's plane looking at the floor beside it, 0 bounces."""
from __future__ import annotations

import numpy as np
import pytest

from addon import lightsetup
from addon import scenedata as sd
from addon.lights.coincident import coincident_copies

from .scenes import ALL_VIS, geometry, light, material, ortho_down, quad, render, translation

MESSAGE = "coincide with other triangles: rendered as one surface (Cycles renders "
DARKER = "Cycles renders coincident faces darker"
BRIGHTER = "Cycles renders these faces brighter"    # a reflecting copy on an emitting one
FLOOR, LAMP, DIFFUSE = 1, 2, 3


def _lamp(rotate=False, flip=False):
    """The emitting quad's (vertices, triangles), facing down at z = 1; rotate: its corners
    listed cyclically shifted; flip: the other winding."""
    v, t = quad((0.0, 0.0, 1.0), 0.5, 0.5, up=flip)
    if rotate:
        t = np.roll(t, 1, axis=1)
    return v, t


def _scene(parts, samples=16, lamp=False):
    mats = [material('default'), material('floor', (0.8, 0.8, 0.8)),
            material('lamp', (0.0, 0.0, 0.0), (5.0, 5.0, 5.0)), material('diffuse', (0.8, 0.8, 0.8))]
    v, t = quad((0.0, 0.0, 0.0), 4.0, 4.0)
    cam = ortho_down(height=0.5, width=24, px=18, view=2.0, target=(0.6, 0.0))
    # lamp: a point light beside the quad, so the light tree holds them (the MIS pdf by tree key)
    lights = [light('POINT', 20.0, translation(2.0, 0.0, 1.0))] if lamp else []
    return sd.SceneData(cam, geometry([(v, t, FLOOR, ALL_VIS)] + parts), mats, lights, np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=0, filter_type='BOX'))


def _image(parts, **kw):
    integ = render(_scene(parts, **kw))
    return integ.film.combined()[..., :3], [t for _, t in integ.messages if MESSAGE in t]


def _same_surface(image, single, how):
    """'exact' copies: bit-identical; another corner order listed after the original: the hit
    t of a BSDF ray may differ in the last bit, and either copy is hit ('close'); listed first,
    light samples pick the quad by other corners (other noise): the same mean ('mean')."""
    if how == 'exact':
        np.testing.assert_array_equal(image, single)
    elif how == 'close':
        np.testing.assert_allclose(image, single, rtol=1e-5, atol=1e-6)
    else:
        np.testing.assert_allclose(image.mean(), single.mean(), rtol=0.01)


@pytest.mark.parametrize('lamp', [False, True])
def test_twin_renders_as_the_single_quad(lamp):
    single, said = _image([(*_lamp(), LAMP, ALL_VIS)], lamp=lamp)
    assert single.mean() > 0.05 and not said
    for rotate, flip in ((False, False), (True, False), (False, True), (True, True)):
        exact = not (rotate or flip)
        for twin_first in (False, True):
            parts = [(*_lamp(), LAMP, ALL_VIS), (*_lamp(rotate, flip), LAMP, ALL_VIS)]
            doubled, said = _image(parts[::-1] if twin_first else parts, lamp=lamp)
            _same_surface(doubled, single, 'exact' if exact else 'mean' if twin_first else 'close')
            assert len(said) == 1 and said[0].startswith("4 emissive triangles of 'object 1', 'object 2' "), said


def test_a_diffuse_twin_decides_by_its_index():
    single, _ = _image([(*_lamp(), LAMP, ALL_VIS)])
    dark, _ = _image([(*_lamp(), DIFFUSE, ALL_VIS)])
    assert single.mean() > 0.05 and dark.max() == 0.0
    for rotate, flip in ((False, False), (True, True)):
        # the emitter first: the emitter alone; the diffuse copy first: the diffuse quad alone
        lit, said = _image([(*_lamp(), LAMP, ALL_VIS), (*_lamp(rotate, flip), DIFFUSE, ALL_VIS)])
        _same_surface(lit, single, 'close')
        assert len(said) == 1 and said[0].startswith("2 emissive triangles of 'object 1' "), said
        assert DARKER in said[0], said      # (the emitter is the lower copy; the rule reads no further)
        unlit, said = _image([(*_lamp(rotate, flip), DIFFUSE, ALL_VIS), (*_lamp(), LAMP, ALL_VIS)])
        np.testing.assert_array_equal(unlit, dark)
        assert len(said) == 1 and said[0].startswith("2 emissive triangles of 'object 2' "), said
        # (Cycles' bounce ray leaving the diffuse copy meets the emitter and gathers its light)
        assert BRIGHTER in said[0], said


def test_a_copy_bsdf_rays_pass_does_not_hide_the_emitter():
    # a lower-index copy hidden from diffuse rays is not what their hits return: the emitter stays
    single, _ = _image([(*_lamp(), LAMP, ALL_VIS)])
    hidden = sd.VIS_CAMERA | sd.VIS_SHADOW
    doubled, _ = _image([(*_lamp(), DIFFUSE, hidden), (*_lamp(), LAMP, ALL_VIS)])
    assert doubled.mean() == pytest.approx(single.mean(), rel=0.05)


def test_no_coincident_faces_is_bit_identical(monkeypatch):
    parts = [(*_lamp(), LAMP, ALL_VIS), (quad((0.0, 0.0, 1.0), 0.5, 0.4)[0], _lamp()[1], LAMP, ALL_VIS)]
    before, said = _image(parts)
    assert not said and before.mean() > 0.05
    monkeypatch.setattr(lightsetup, 'coincident_copies', lambda *a: (None, None, None))
    after, _ = _image(parts)
    np.testing.assert_array_equal(after, before)


def test_only_exact_copies_coincide():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                  [0, 0, 0], [1, 0, 0], [1, 1, 0], [-0.0, 1, 0], [1, 1, 1e-7]], np.float64)
    t = np.array([[0, 1, 2], [0, 2, 3], [4, 6, 5], [7, 4, 6], [1, 2, 0], [0, 1, 8]], np.int32)
    every = np.ones(len(t), bool)
    emit = np.array([0, 0, 1, 1, 1, 1], bool)
    copies, winners, grouped = coincident_copies(v, t, emit, every)
    np.testing.assert_array_equal(copies, [2, 3, 4])     # -0 is +0; 1e-7 off is another
    np.testing.assert_array_equal(winners, [0, 1, 0])
    np.testing.assert_array_equal(grouped, [0, 0, 1, 1, 1, 0])
    # the lowest copy among those rays stop at wins: triangle 0 passed, 2 wins over 4
    copies, winners, _ = coincident_copies(v, t, emit, np.array([0, 1, 1, 1, 1, 1], bool))
    np.testing.assert_array_equal(copies, [3, 4])
    np.testing.assert_array_equal(winners, [1, 2])
    assert coincident_copies(v, t, np.array([0, 0, 0, 0, 0, 1], bool), every) == (None, None, None)
