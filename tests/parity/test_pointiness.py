"""The Geometry node's Pointiness agrees with Cycles: per vertex, the angle between the welded
vertex normal and the mean edge direction leaving it over pi, blurred with its edge neighbours'
(export/pointiness.py), interpolated over the triangles. A turned cube, a monkey (smooth) and an
icosphere split at its edges (Edge Split: vertices Cycles welds back), the value x 2 + 0.1 into
an Emission's Strength, seen by a perspective camera. Interior pixels (away from silhouettes)
within 0.03 of Cycles', 1e-3 on average (measured 0.015 and 1.7e-4); it had stood at the
reading input's own value, said: 0.39 off, 0.26 on average."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering
from .stats import interior

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material():
    mat, nt, _ = scenes._material('pointy')     # (its output node: 'Material Output')
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    post = nt.nodes.new('ShaderNodeMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = 2.0, 0.1     # (positive emission)
    nt.links.new(geo.outputs['Pointiness'], post.inputs[0])
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(post.outputs[0], em.inputs['Strength'])
    nt.links.new(em.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


def test_pointiness_matches_cycles():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 96, 32
    scenes.camera((0.0, -7.0, 2.5), rotation=(1.22, 0.0, 0.0), lens=40)
    scenes.black_world()
    mat = _material()
    bpy.ops.mesh.primitive_cube_add(size=1.3, location=(-2.2, 0, 0.3), rotation=(0.3, 0.4, 0.5))
    bpy.ops.mesh.primitive_monkey_add(size=1.4, location=(0.0, 0, 0.4), rotation=(0.3, 0, 0))
    bpy.ops.object.shade_smooth()
    bpy.ops.mesh.primitive_ico_sphere_add(radius=0.8, subdivisions=2, location=(2.2, 0, 0.3))
    bpy.context.active_object.modifiers.new('split', 'EDGE_SPLIT').split_angle = 0.3
    for ob in bpy.data.objects:
        if ob.type == 'MESH':
            ob.data.materials.append(mat)
    rendering.matched(sc, 64)
    sc.render.film_transparent = True            # (alpha finds the silhouettes)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        got[engine] = scenes.render_rgba(sc)
    c, d = got['CYCLES'], got['DACRT']
    inside = interior(c[..., 3] > 0.999)
    assert inside.sum() > 200
    diff = np.abs(d[..., :3] - c[..., :3])[inside]
    # (a pixel across an edge inside the monkey, where its parts overlap, mixes two values: its
    # 64 samples' spread; the mean shows a bias)
    assert diff.max() < 0.03 and diff.mean() < 1e-3, (diff.max(), diff.mean())
    assert np.ptp(c[..., 0][inside]) > 0.2           # the test sees the value vary
