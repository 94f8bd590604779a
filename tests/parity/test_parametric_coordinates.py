"""The Geometry node's Parametric agrees with Cycles: (1 - u - v, u, 0) of the hit's barycentric
coordinates on its triangle, the triangles split from quads as Cycles splits them. A tilted
plane and a turned cube whose Emission's Color is the vector, under a white world: pixels within
0.004 of Cycles' on average and under 2% of them more than 0.05 off (a pixel across a triangle's
edge averages both sides' values by its samples). Parametric had stood at its socket's own value
(0), said."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering
from .test_reflection_coordinates import coordinates_view, engines_rgb, object_interior

pytestmark = pytest.mark.usefixtures('parity_addon')


def test_parametric_matches_cycles():
    sc, _ = coordinates_view()
    mat, nt, _ = scenes._material('Parametric')
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(geo.outputs['Parametric'], em.inputs['Color'])
    nt.links.new(em.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    scenes.world((1.0, 1.0, 1.0), 1.0)
    plane = scenes.plane('P', size=2.0, location=(1.4, 0, 0.2), materials=(mat,))
    plane.rotation_euler = (1.1, 0.3, 0.2)
    bpy.ops.mesh.primitive_cube_add(location=(-1.2, 0, 0.2), rotation=(0.5, 0.3, 0.7))
    bpy.context.object.data.materials.append(mat)
    rendering.matched(sc, 64)
    c, d = engines_rgb(sc)
    inside = object_interior(c)
    assert inside.sum() > 300
    diff = np.abs(d - c)[inside]
    assert diff.mean() < 0.004 and np.mean(diff.max(axis=-1) > 0.05) < 0.02, (diff.mean(), np.mean(diff.max(-1) > 0.05))
    assert np.ptp(c[inside][:, 0]) > 0.5 and np.ptp(c[inside][:, 1]) > 0.5     # the vector varies
