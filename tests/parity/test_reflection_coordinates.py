"""Texture Coordinate Reflection agrees with Cycles: the incoming direction mirrored about the
shading normal, 2 (N . wi) N - wi in world space, read per point. A smooth sphere and a tilted
plane seen by a perspective camera: the vector x 0.5 + 0.5 into an Emission's Color (interior
pixels, away from silhouettes, within 0.01 of Cycles'; measured 0.003), a reflection map (an
8x16 image on it, Sphere projection) into an Emission's Color (within 0.06, 0.004 on average:
texels change within a pixel where the reflection turns fast; measured 0.029 / 0.0007), and its
Z through a Color Ramp into a Diffuse BSDF's Color under a white world, no bounces (4x4 blocks
within 0.03; measured 0.008). Reflection had been read as the socket's own value, or the image on
the UV map and flat, said: 0.50, 0.54 and 0.68 off."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering
from .stats import block_means, interior

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(kind):
    mat, nt, _ = scenes._material(kind)     # (its output node: 'Material Output')
    tc = nt.nodes.new('ShaderNodeTexCoord')
    if kind == 'image':          # a reflection map: an image on Reflection, Sphere projection
        img = nt.nodes.new('ShaderNodeTexImage')
        px = np.ones((8, 16, 4), np.float32)
        px[..., :3] = np.random.default_rng(2).uniform(0.05, 1.0, (8, 16, 3))
        img.image = scenes.float_image('refl', px)
        img.projection = 'SPHERE'
        nt.links.new(tc.outputs['Reflection'], img.inputs['Vector'])
        sh = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(img.outputs['Color'], sh.inputs['Color'])
    elif kind == 'emission':
        sh = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(scenes.as_colour(nt, tc.outputs['Reflection']), sh.inputs['Color'])
    else:
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].position = -1.0
        ramp.color_ramp.elements[0].color = (0.9, 0.1, 0.05, 1)
        ramp.color_ramp.elements[1].color = (0.05, 0.3, 0.9, 1)
        nt.links.new(tc.outputs['Reflection'], sep.inputs[0])
        nt.links.new(sep.outputs['Z'], ramp.inputs[0])
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(ramp.outputs[0], sh.inputs['Color'])
    nt.links.new(sh.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


def coordinates_view(**camera):
    """(scene, camera) of the coordinate tests: an empty 64 x 32 scene seen from (0.5, -6, 2)
    by a 35 mm lens (camera: scenes.camera's other keywords)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    return sc, scenes.camera((0.5, -6.0, 2.0), rotation=(1.25, 0.0, 0.08), lens=35, **camera)


def engines_rgb(sc):
    """Cycles' and DACRT's RGB of sc."""
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        got[engine] = scenes.render_rgba(sc)[..., :3]
    return got['CYCLES'], got['DACRT']


def sphere_and_plane_rgb(sc, mat, samples=64):
    """Cycles' and DACRT's RGB of a sphere and a tilted plane of mat under a white world
    (samples, direct light only, 1-pixel Box filter): the coordinate tests' scene."""
    scenes.world((1.0, 1.0, 1.0), 1.0)
    scenes.uv_sphere('S', radius=1.0, location=(-1.2, 0, 0.2), materials=(mat,))
    plane = scenes.plane('P', size=2.0, location=(1.4, 0, 0.2), materials=(mat,))
    plane.rotation_euler = (1.1, 0.3, 0.2)
    rendering.matched(sc, samples)
    return engines_rgb(sc)


def object_interior(c):
    """The pixels of RGB c (H, W, 3) whose 3x3 neighbourhood all shows an object, not the white
    world."""
    return interior(~np.all(np.abs(c - 1.0) < 1e-4, axis=-1))


@pytest.mark.parametrize('kind', ['emission', 'image', 'diffuse'])
def test_reflection_coordinates_match_cycles(kind):
    sc, _ = coordinates_view()
    c, d = sphere_and_plane_rgb(sc, _material(kind))
    if kind != 'diffuse':
        inside = object_interior(c)         # (no silhouette pixels)
        assert inside.sum() > 200
        diff = np.abs(d - c)[inside]
        # (an image's texels change within a pixel where the reflection turns fast: a pixel's
        # 64 samples then differ by more; its mean difference stays small)
        assert diff.max() < (0.01 if kind == 'emission' else 0.06), (diff.max(), diff.mean(axis=0))
        assert diff.mean() < 0.004, diff.mean(axis=0)
        assert np.ptp(c[inside], axis=0).max() > 0.3        # the test sees the vector vary
    else:
        cb, db = (block_means(x[None], 4)[0] for x in (c, d))
        assert np.abs(db - cb).max() < 0.03, np.abs(db - cb).max()
        assert np.ptp(cb[..., 0]) > 0.3
