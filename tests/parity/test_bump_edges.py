"""Bump edge cases against Cycles: back faces, see-through surfaces and the passes, far-side
light of translucent surfaces, points and curves, the Filter Width (tests/parity/test_bump.py
holds the base cases and the helpers)."""
import math

import bpy
import numpy as np
import pytest

from tests.parity.test_bump import _bumped, _compare, _plane_scene, _render, _wave

pytestmark = pytest.mark.usefixtures('parity_addon')


def _wave_on(coordinate):
    def make(nt):
        w = _wave()(nt)
        if coordinate is not None:
            nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs[coordinate], w.inputs['Vector'])
        return w
    return make


@pytest.mark.parametrize('case', ['below', 'mirrored', 'displacement mirrored', 'object coordinates below'])
def test_a_bump_seen_from_behind_matches_cycles(case, tmp_path):
    """On a back face Cycles' taps of interpolated attributes (Generated, UV) move opposite to
    the position's, so a Generated relief seen from behind is the front's negated (a bump is a
    dent from there), while an Object-coordinate relief keeps its shape mirrored in N. A plane
    seen from below under a sun 20 degrees below it, and one scaled (1, 1, -1) seen from above.
    Before: Generated bands 0.2498 vs Cycles 0.2704, 4x4 blocks 153% off, lit and dark slopes
    swapped."""
    coordinate = 'Object' if 'object' in case else None
    distance = 0.1 if coordinate else 0.4        # (Object coordinates span 4x Generated's: as steep)
    if case.startswith('displacement'):
        def make():
            return _bumped("Disp", _wave_on(coordinate), 'Fac', displacement=(0.5, 0.3))
    else:
        def make():
            return _bumped("Waves", _wave_on(coordinate), 'Fac', distance=distance)
    sc = _plane_scene(make)
    plane = next(o for o in sc.objects if o.type == 'MESH')
    if 'below' in case:
        sc.camera.location, sc.camera.rotation_euler = (0, 0, -5), (math.pi, 0, 0)
        sun = next(o for o in sc.objects if o.type == 'LIGHT')
        sun.rotation_euler = (0.0, math.radians(110.0), 0.0)
    else:
        plane.scale = (1, 1, -1)
    img, nrm = _render(sc, tmp_path)
    # (Cycles' Object-coordinate normals seen from behind lean 0.017 along y: its differentials)
    _compare(img, nrm, normal_atol=0.02 if coordinate else 0.01)
    c = img['CYCLES']
    assert c.max() > 1.5 * c.min(), "the relief must show"
