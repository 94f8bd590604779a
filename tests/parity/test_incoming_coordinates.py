"""The Geometry node's Incoming agrees with Cycles: the direction back along the ray that met the
point (Cycles' sd->wi, world space), read per point. A smooth sphere and a tilted plane seen by
a perspective camera under a white world: the vector x 0.5 + 0.5 into an Emission's Color
(interior pixels within 0.01 of Cycles'), and its dot product with Geometry Normal (a facing
ratio) through a Color Ramp into a Diffuse BSDF's Color (4x4 blocks within 0.03). Incoming had
stood at its socket's own value (0), said: the emission read a flat 0.5 grey."""
import numpy as np
import pytest

from tests.addon import scenes

from .stats import block_means
from .test_reflection_coordinates import coordinates_view, object_interior, sphere_and_plane_rgb

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(kind):
    mat, nt, _ = scenes._material(kind)
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    if kind == 'emission':
        sh = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(scenes.as_colour(nt, geo.outputs['Incoming']), sh.inputs['Color'])
    else:
        dot = nt.nodes.new('ShaderNodeVectorMath')
        dot.operation = 'DOT_PRODUCT'
        nt.links.new(geo.outputs['Incoming'], dot.inputs[0])
        nt.links.new(geo.outputs['Normal'], dot.inputs[1])
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].color = (0.9, 0.1, 0.05, 1)
        ramp.color_ramp.elements[1].color = (0.05, 0.3, 0.9, 1)
        nt.links.new(dot.outputs['Value'], ramp.inputs[0])
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(ramp.outputs[0], sh.inputs['Color'])
    nt.links.new(sh.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


@pytest.mark.parametrize('kind', ['emission', 'diffuse'])
def test_incoming_matches_cycles(kind):
    sc, _ = coordinates_view()
    c, d = sphere_and_plane_rgb(sc, _material(kind))
    if kind == 'emission':
        inside = object_interior(c)
        assert inside.sum() > 200
        diff = np.abs(d - c)[inside]
        assert diff.max() < 0.01, (diff.max(), diff.mean(axis=0))
        assert np.ptp(c[inside], axis=0).max() > 0.3        # the test sees the vector vary
    else:
        cb, db = (block_means(x[None], 4)[0] for x in (c, d))
        assert np.abs(db - cb).max() < 0.03, np.abs(db - cb).max()
        assert np.ptp(cb[..., 0]) > 0.3
