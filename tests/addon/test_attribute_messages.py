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


def _two_attribute_material(name, first, second, blend='MULTIPLY'):
    """A Diffuse whose colour is a Mix `blend` of two Attribute nodes' colours: first and second
    are (attribute type, name)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nodes = []
    for kind, attribute in (first, second):
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_type, a.attribute_name = kind, attribute
        nodes.append(a)
    mix = scenes.mix_node(nt, blend, nodes[0].outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(nodes[1].outputs['Color'], mix.inputs['B'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _quads(name, material):
    verts = [(x, y, 0.0) for y in (-1.0, 1.0) for x in (-2.0, 0.0, 2.0)]
    return scenes.mesh(name, verts, [(0, 1, 4, 3), (1, 2, 5, 4)], materials=(material,))


def test_two_mesh_attributes_are_each_read_and_a_product_is_said_by_name(scene, exported):
    """A product of two point attributes: each corner the product of its own two values (it
    had been one attribute's square), and the per-corner evaluation said naming both."""
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    ob = _quads("Grid", _two_attribute_material("Product", ('GEOMETRY', 'a'), ('GEOMETRY', 'b')))
    va, vb = np.linspace(0.2, 0.7, 6), np.linspace(0.9, 0.4, 6)
    ob.data.attributes.new('a', 'FLOAT', 'POINT').data.foreach_set('value', va)
    ob.data.attributes.new('b', 'FLOAT', 'POINT').data.foreach_set('value', vb)
    data = exported()
    g = data.geometry
    got = np.asarray(g.colors)[..., 0].ravel()
    at = np.asarray(g.triangles).ravel()
    assert np.allclose(got, (va * vb)[at], atol=1e-6), (got, (va * vb)[at])
    m = next(m for m in data.materials if m.name == "Product")
    assert "attribute 'a', attribute 'b' applied at the mesh's corners" in m.approximated, m.approximated
    assert "image" not in _text(data), _text(data)


def test_a_mesh_and_an_object_attribute_are_each_read(scene, exported):
    """A face attribute times an object's custom property (Attribute of type Object): each
    object's corners its own product, nothing said (a sum: affine, exact per corner)."""
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    mat = _two_attribute_material("Mixed", ('GEOMETRY', 'a'), ('OBJECT', 'o'), blend='ADD')
    for i, o in enumerate((0.1, 0.3)):
        ob = _quads(f"Grid{i}", mat)
        ob.location.y = 3.0 * i
        ob.data.attributes.new('a', 'FLOAT', 'FACE').data.foreach_set('value', (0.2 + 0.1 * i, 0.5))
        ob['o'] = o
    data = exported()
    g = data.geometry
    y = np.asarray(g.vertices)[np.asarray(g.triangles)][..., 1].mean(axis=1)
    colors = np.asarray(g.colors)[..., 0]
    x = np.asarray(g.vertices)[np.asarray(g.triangles)][..., 0].mean(axis=1)
    for i, o in enumerate((0.1, 0.3)):
        for face, a in ((x < 0, 0.2 + 0.1 * i), (x > 0, 0.5)):
            sel = (np.abs(y - 3.0 * i) < 1.5) & face
            assert sel.any() and np.allclose(colors[sel], a + o, atol=1e-6), (i, colors[sel], a + o)
    m = next(m for m in data.materials if m.name == "Mixed")
    assert "image" not in m.approximated and "applied at the mesh's corners" not in m.approximated, m.approximated
    assert "image" not in _text(data), _text(data)


def test_two_object_attributes_say_nothing_of_images(scene, exported):
    """Two object attributes (custom properties) multiplied: each object's own product, exact
    per object (it had said 'two image textures mixed' and averaged the second)."""
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    mat = _two_attribute_material("Objects", ('OBJECT', 'p'), ('OBJECT', 'q'))
    for i, (p, q) in enumerate(((0.2, 0.5), (0.8, 0.9))):
        ob = _quads(f"Obj{i}", mat)
        ob.location.y = 3.0 * i
        ob['p'], ob['q'] = p, q
    data = exported()
    g = data.geometry
    y = np.asarray(g.vertices)[np.asarray(g.triangles)][..., 1].mean(axis=1)
    colors = np.asarray(g.colors)[..., 0]
    for i, (p, q) in enumerate(((0.2, 0.5), (0.8, 0.9))):
        sel = np.abs(y - 3.0 * i) < 1.5
        assert sel.any() and np.allclose(colors[sel], p * q, atol=1e-6), (i, colors[sel], p * q)
    m = next(m for m in data.materials if m.name == "Objects")
    assert "image" not in m.approximated, m.approximated


def test_an_attribute_node_without_a_name_reads_0_and_says_so(scene, exported):
    """An Attribute node (type Geometry) with an empty Name reads nothing, as Cycles (black),
    not the render colour attribute (only a Color Attribute node's empty layer means that), and
    the material says which node."""
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    ob = _quads("Grid", _attribute_material("Unnamed", ''))
    col = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    col.data.foreach_set('color', np.tile([0.8, 0.3, 0.1, 1.0], len(col.data)))
    ob.data.color_attributes.render_color_index = 0
    data = exported()
    m = next(m for m in data.materials if m.name == "Unnamed")
    g = data.geometry
    k = [x.name for x in data.materials].index("Unnamed")
    albedo = m.base_color if g.colors is None else np.asarray(g.colors)[np.asarray(g.material) == k]
    assert np.allclose(albedo, 0.0), albedo
    assert "Attribute node 'Attribute' has no name: it reads 0, as in Cycles" in m.approximated, m.approximated
