"""Export-level checks of what Attribute and Color Attribute nodes read and what is said about
it: an attribute on the mesh's edges is read on the points as Blender hands it to Cycles (each
point the mean of its edges' values), without a warning (it had read 0 under "a domain Cycles
does not read"). Renders against Cycles: tests/parity/test_attribute_domains.py."""
import numpy as np

from . import scenes


def _attribute_material(name, attribute):
    """A Diffuse whose colour is an Attribute node (type Geometry) reading `attribute`."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = attribute
    nt.links.new(a.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _text(data):
    return " | ".join(m for _, m in data.messages)


def test_an_edge_attribute_reads_its_points_mean_of_edges_silently(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    verts = [(x, y, 0.0) for y in (-1.0, 0.0, 1.0) for x in (-1.0, 0.0, 1.0)]
    faces = [(0, 1, 4, 3), (1, 2, 5, 4), (3, 4, 7, 6), (4, 5, 8, 7)]
    ob = scenes.mesh("Grid", verts, faces, materials=(_attribute_material("EdgeMat", 'e'),))
    me = ob.data
    a = me.attributes.new('e', 'FLOAT', 'EDGE')
    v = np.linspace(0.1, 0.9, len(me.edges)).astype(np.float32)
    a.data.foreach_set('value', v)
    want = np.zeros(len(verts))
    for e, value in zip(me.edges, v):        # (the reference: a loop over the edges)
        for i in e.vertices:
            want[i] += value / sum(i in f.vertices for f in me.edges)
    data = exported()
    g = data.geometry
    got = np.asarray(g.colors)[..., 0].ravel()
    at = np.asarray(g.triangles).ravel()
    assert np.allclose(got, want[at], atol=1e-6), (got, want[at])
    assert "edges" not in _text(data), _text(data)
