"""A NaN in a colour attribute (a script's): Cycles interpolates it into every point of the
triangles around that corner and drops their closures, so they render black. DACRT read it
as 0 at that corner alone and blended it into the rest of each triangle, without a word (a
tester's cube: 27 pixels off Cycles by more than 0.1; now none)."""
import numpy as np

from . import scenes

NAN = float('nan')


def _attribute_plane(value):
    """A 2x1 grid of quads (vertices 0..5, vertex 0 in one quad only) whose Diffuse colour is
    a point colour attribute of 0.2 / 0.6 / 0.3, vertex 0 set to value."""
    verts = [(x, y, 0.0) for y in (-1.0, 1.0) for x in (-2.0, 0.0, 2.0)]
    mat, nt, out = scenes._material("AttrMat")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    n = nt.nodes.new('ShaderNodeVertexColor')
    n.layer_name = 'Col'
    nt.links.new(n.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob = scenes.mesh("Grid", verts, [(0, 1, 4, 3), (1, 2, 5, 4)], materials=(mat,))
    a = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    c = np.tile([0.2, 0.6, 0.3, 1.0], 6).astype(np.float32)
    c[0:3] = value
    a.data.foreach_set('color', c)
    return ob


def test_nan_colour_attribute_blackens_the_triangles_around_it(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    _attribute_plane(NAN)
    data = exported()
    g = data.geometry
    tri = np.asarray(g.triangles)
    colors = np.asarray(g.colors)
    at_nan = (tri == 0).any(axis=1)          # (vertex 0 is the mesh's first: the frame's first)
    assert at_nan.any() and (~at_nan).any()
    assert np.all(colors[at_nan] == 0.0)     # black, whole triangles (had been 0 at one corner)
    assert np.allclose(colors[~at_nan], (0.2, 0.6, 0.3))
    text = " | ".join(m for _, m in data.messages)
    assert "'Grid': a colour or attribute value NaN or infinite at some corner: the" in text
    assert "render black, as in Cycles" in text


def test_finite_colour_attribute_is_unchanged(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    _attribute_plane((0.2, 0.6, 0.3))
    data = exported()
    assert np.allclose(np.asarray(data.geometry.colors), (0.2, 0.6, 0.3))
    assert not any("NaN or infinite at some corner" in m for _, m in data.messages)
