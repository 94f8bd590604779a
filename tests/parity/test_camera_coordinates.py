"""Texture Coordinate Camera agrees with Cycles: the hit in the render camera's space (Cycles'
worldtocamera: x right, y up, z into the view; a panorama's frame turned to look along the
camera's +X), read per point. A sphere and a tilted plane, the coordinate x 0.1 + 0.5 into an
Emission's Color, seen by a perspective camera (shifted), an orthographic one and an
equirectangular panorama; and its Z (the depth) through a Color Ramp into a Diffuse BSDF's Color
under a white world (no bounces), perspective. Interior pixels (away from silhouettes) within
0.003 of Cycles' (emission; measured 3e-4) and 4x4 blocks within 0.03 (diffuse; measured 0.007).
It had been read as the socket's own value, said: 0.33-0.65 off."""
import numpy as np
import pytest

from tests.addon import scenes

from .stats import block_means
from .test_reflection_coordinates import coordinates_view, object_interior, sphere_and_plane_rgb

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(kind):
    mat, nt, _ = scenes._material(kind)     # (its output node: 'Material Output')
    tc = nt.nodes.new('ShaderNodeTexCoord')
    if kind == 'emission':
        post = nt.nodes.new('ShaderNodeVectorMath')
        post.operation = 'MULTIPLY_ADD'
        post.inputs[1].default_value, post.inputs[2].default_value = (0.1, 0.1, 0.1), (0.5, 0.5, 0.5)
        nt.links.new(tc.outputs['Camera'], post.inputs[0])
        sh = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(post.outputs['Vector'], sh.inputs['Color'])
    else:
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        rng = nt.nodes.new('ShaderNodeMapRange')
        rng.inputs['From Min'].default_value, rng.inputs['From Max'].default_value = 4.0, 8.0
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].color = (0.9, 0.1, 0.05, 1)
        ramp.color_ramp.elements[1].color = (0.05, 0.3, 0.9, 1)
        nt.links.new(tc.outputs['Camera'], sep.inputs[0])
        nt.links.new(sep.outputs['Z'], rng.inputs['Value'])
        nt.links.new(rng.outputs[0], ramp.inputs[0])
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(ramp.outputs[0], sh.inputs['Color'])
    nt.links.new(sh.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


@pytest.mark.parametrize('kind, camera', [('emission', 'PERSP'), ('emission', 'ORTHO'), ('emission', 'PANO'),
                                          ('diffuse', 'PERSP')])
def test_camera_coordinates_match_cycles(kind, camera):
    sc, cam = coordinates_view(kind='ORTHO' if camera == 'ORTHO' else 'PERSP', ortho_scale=7.0)
    if camera == 'PANO':
        cam.data.type = 'PANO'
        cam.data.panorama_type = 'EQUIRECTANGULAR'
        cam.location = (0.2, -3.0, 1.0)          # (the whole sphere of directions: come closer)
        sc.render.resolution_x, sc.render.resolution_y = 128, 64
    else:
        cam.data.shift_x, cam.data.shift_y = 0.05, -0.08
    c, d = sphere_and_plane_rgb(sc, _material(kind))
    if kind == 'emission':
        inside = object_interior(c)
        assert inside.sum() > 100
        diff = np.abs(d - c)[inside]
        assert diff.max() < 0.003, (diff.max(), diff.mean(axis=0))
        assert np.ptp(c[inside], axis=0).max() > 0.1        # the test sees the coordinate vary
    else:
        cb, db = (block_means(x[None], 4)[0] for x in (c, d))
        assert np.abs(db - cb).max() < 0.03, np.abs(db - cb).max()
        assert np.ptp(cb[..., 0]) > 0.3
