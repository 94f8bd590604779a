"""Texture Coordinate Window agrees with Cycles: the hit projected to the render camera's frame,
0..1 across it, z 0 (Cycles' camera_world_to_ndc), read per point. A sphere and a tilted plane
whose Emission's Color is the Window vector, and a Checker texture on it, under perspective
(shifted), orthographic and an equirectangular panorama: interior pixels within 0.01 of Cycles'
(the vector) and 4x4 blocks within 0.03 (the checker, whose squares split pixels at their
edges). Window had been read as the socket's own value, said: pixels up to 1.0 off (the
checker's blocks 0.8)."""
import numpy as np
import pytest

from tests.addon import scenes

from .stats import block_means
from .test_reflection_coordinates import coordinates_view, object_interior, sphere_and_plane_rgb


pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(kind):
    mat, nt, _ = scenes._material(kind)
    tc = nt.nodes.new('ShaderNodeTexCoord')
    sh = nt.nodes.new('ShaderNodeEmission')
    if kind == 'vector':
        nt.links.new(tc.outputs['Window'], sh.inputs['Color'])
    else:
        chk = nt.nodes.new('ShaderNodeTexChecker')
        chk.inputs['Scale'].default_value = 4.0
        nt.links.new(tc.outputs['Window'], chk.inputs['Vector'])
        nt.links.new(chk.outputs['Color'], sh.inputs['Color'])
    nt.links.new(sh.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


def _render(camera, kind):
    sc, cam = coordinates_view()
    if camera == 'ortho':
        cam.data.type, cam.data.ortho_scale = 'ORTHO', 7.0
    elif camera == 'shifted':
        cam.data.shift_x, cam.data.shift_y = 0.15, -0.1
    elif camera == 'pano':                  # (closer: the objects fill more of the whole sphere)
        cam.location = (0.1, -1.8, 0.3)
        cam.data.type = 'PANO'
        cam.data.panorama_type = 'EQUIRECTANGULAR'
    return sphere_and_plane_rgb(sc, _material(kind), samples=16)


@pytest.mark.parametrize('camera', ['persp', 'shifted', 'ortho', 'pano'])
def test_window_vector_matches_cycles(camera):
    c, d = _render(camera, 'vector')
    inside = object_interior(c)
    assert inside.sum() > 40
    diff = np.abs(d - c)[inside]
    assert diff.max() < 0.01, (diff.max(), diff.mean(axis=0))
    assert np.ptp(c[inside][:, 0]) > 0.2                # the vector varies over the frame


@pytest.mark.parametrize('camera', ['persp', 'ortho'])
def test_window_checker_matches_cycles(camera):
    c, d = _render(camera, 'checker')
    cb, db = (block_means(x[None], 4)[0] for x in (c, d))
    assert np.abs(db - cb).max() < 0.03, np.abs(db - cb).max()
