"""Mesh attributes on the Edge domain agree with Cycles: Blender hands them to Cycles moved to
the points (each point the mean of its edges' values, mixed as the type mixes: an integer
rounded, a boolean true where any edge is, a byte colour stored back in 8 bits, a quaternion
through its exponential map), and Cycles interpolates them over each triangle as a point
attribute. Six 4 x 4 grids, one per type (float, integer, boolean, vector, byte colour,
quaternion), of random values per edge, read by an Attribute node into a diffuse colour under a
straight-down sun, direct light only: each grid's mean agrees within 0.5% per channel. Before,
an edge attribute read 0 (black) under a warning that Cycles does not read the edge domain."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.test_color_attributes import _render_both

pytestmark = pytest.mark.usefixtures('parity_addon')

TYPES = ('FLOAT', 'INT', 'BOOLEAN', 'FLOAT_VECTOR', 'BYTE_COLOR', 'QUATERNION')


def _values(kind, n, rng):
    if kind == 'FLOAT':
        return 'value', rng.random(n)
    if kind == 'INT':
        return 'value', rng.integers(0, 2, n)
    if kind == 'BOOLEAN':
        return 'value', rng.random(n) < 0.3
    if kind == 'FLOAT_VECTOR':
        return 'vector', rng.random((n, 3))
    if kind == 'BYTE_COLOR':
        c = rng.random((n, 4))
        c[:, 3] = 1.0
        return 'color', c
    q = 0.2 + rng.random((n, 4))                  # (w, x, y, z), all positive: a colour (w, x, y)
    return 'value', q / np.linalg.norm(q, axis=1, keepdims=True)


def _edge_grid(kind, x, y, rng):
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=4, size=0.9, location=(x, y, 0))
    ob = bpy.context.object
    ob.name = kind
    attr = ob.data.attributes.new('attr', kind, 'EDGE')
    prop, v = _values(kind, len(attr.data), rng)
    attr.data.foreach_set(prop, np.asarray(v).ravel())
    mat, nt, out = scenes._material(kind)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    node = nt.nodes.new('ShaderNodeAttribute')
    node.attribute_name = 'attr'
    nt.links.new(node.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob.data.materials.append(mat)


def test_edge_attributes_match_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 44
    rng = np.random.default_rng(5)
    cells = [(-1.0 + (i % 3), 0.5 - (i // 3)) for i in range(len(TYPES))]
    for kind, (x, y) in zip(TYPES, cells):
        _edge_grid(kind, x, y, rng)
    # (ortho 3 over 64 pixels: 21.3 per unit, rows from the bottom; each grid's inner 13 x 13 pixels)
    px = 64 / 3.0
    means = {engine: np.array([img[int(22 + y * px) - 6:int(22 + y * px) + 7,
                                   int(32 + x * px) - 6:int(32 + x * px) + 7].mean(axis=(0, 1)) for x, y in cells])
             for engine, img in _render_both(sc, tmp_path, 3.0, 16).items()}
    c, d = means['CYCLES'], means['DACRT']
    assert c.min() > 0.05, c.round(4).tolist()
    rel = np.abs(d - c) / c
    assert rel.max() < 0.005, (rel.round(4).tolist(), c.round(4).tolist(), d.round(4).tolist())


def _two_attribute_grid(name, x, chain, rng):
    """A 4 x 4 grid whose face attributes 'a' (float colour, red varying) and 'b' (float, per
    face) a material reads together: 'add' a Mix Add of Color Attribute 'a' and Attribute 'b'
    (an affine chain: applied per point); 'product' Combine Color (a's red x b, a's red, b) (a
    product: evaluated per corner, exact on face values)."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=4, size=0.9, location=(x, 0, 0))
    ob = bpy.context.object
    ob.name = name
    n = len(ob.data.polygons)
    a = ob.data.attributes.new('a', 'FLOAT_COLOR', 'FACE')
    c = np.zeros((n, 4))
    c[:, 0], c[:, 2], c[:, 3] = 0.1 + 0.8 * rng.random(n), 0.1, 1.0
    a.data.foreach_set('color', c.ravel())
    ob.data.attributes.new('b', 'FLOAT', 'FACE').data.foreach_set('value', 0.1 + 0.8 * rng.random(n))
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    ca = nt.nodes.new('ShaderNodeVertexColor')
    ca.layer_name = 'a'
    ab = nt.nodes.new('ShaderNodeAttribute')
    ab.attribute_name = 'b'
    if chain == 'add':
        s = scenes.mix_node(nt, 'ADD', ca.outputs['Color'], (0, 0, 0), 1.0)
        nt.links.new(ab.outputs['Color'], s.inputs['B'])
        s = s.outputs['Result']
    else:
        sep, mul, cc = (nt.nodes.new(t) for t in ('ShaderNodeSeparateColor', 'ShaderNodeMath',
                                                  'ShaderNodeCombineColor'))
        mul.operation = 'MULTIPLY'
        nt.links.new(ca.outputs['Color'], sep.inputs[0])
        nt.links.new(sep.outputs[0], mul.inputs[0])
        nt.links.new(ab.outputs['Fac'], mul.inputs[1])
        nt.links.new(mul.outputs[0], cc.inputs[0])
        nt.links.new(sep.outputs[0], cc.inputs[1])
        nt.links.new(ab.outputs['Fac'], cc.inputs[2])
        s = cc.outputs[0]
    nt.links.new(s, d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob.data.materials.append(mat)


def test_two_attributes_in_one_material_match_cycles(tmp_path):
    """Two mesh attributes read together, each with its own values (they had been probed as one:
    the chain learned as f(p, p) and applied to one of them, a Mix Add of A and B rendering
    B + B, silently): each face of both grids within 0.5% of Cycles (direct sun light; face
    values, so per-corner evaluation is exact)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    rng = np.random.default_rng(9)
    for i, chain in enumerate(('add', 'product')):
        _two_attribute_grid(chain, -1.0 + 2.0 * i, chain, rng)
    # (ortho 4 over 64 pixels: 16 a unit, a face 3.6 pixels: its centre pixel)
    imgs = _render_both(sc, tmp_path, 4.0, 4)
    centres = [(gx + (i - 1.5) * 0.225, (j - 1.5) * 0.225) for gx in (-1.0, 1.0) for j in range(4) for i in range(4)]
    got = {e: np.array([img[int(16 + y * 16), int(32 + x * 16)] for x, y in centres]) for e, img in imgs.items()}
    c, d = got['CYCLES'], got['DACRT']
    assert np.ptp(c[:, 0]) > 0.2 and np.ptp(c[:, 2]) > 0.2       # both attributes vary
    rel = np.abs(d - c) / np.maximum(c, 0.05)
    assert rel.max() < 0.005, (rel.max(), c.round(3).tolist(), d.round(3).tolist())


def test_two_instancer_attributes_match_cycles(tmp_path, said):
    """Two Instancer attributes read together (a colour times a number, a Mix Multiply), each
    instance with its own values of both (they had fallen into 'two image textures mixed; the
    second as its average colour'): each instance's centre within 2e-3 of Cycles, nothing said
    of images."""
    from tests.parity.test_instancer_attributes import (XS, at, colour_of, fraction_of, fresh, instancer, quad,
                                                        render_both)
    sc = fresh()
    mat, nt, out = scenes._material("Two")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    ia, ib = nt.nodes.new('ShaderNodeAttribute'), nt.nodes.new('ShaderNodeAttribute')
    ia.attribute_type, ia.attribute_name = 'INSTANCER', 'icol'
    ib.attribute_type, ib.attribute_name = 'INSTANCER', 'ifac'
    s = scenes.mix_node(nt, 'MULTIPLY', ia.outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(ib.outputs['Color'], s.inputs['B'])
    nt.links.new(s.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    instancer("Scatter", [(x, 0, 0) for x in XS], quad("Src", materials=(mat,)),
              [('icol', 'FLOAT_COLOR', colour_of), ('ifac', 'FLOAT', fraction_of)])
    imgs = render_both(sc, tmp_path)
    c, d = (np.array([at(imgs[e], x, 0.0) for x in XS]) for e in ('CYCLES', 'DACRT'))
    assert len({tuple(np.round(v, 3)) for v in c}) == len(XS) and c.min() > 0.01
    assert np.abs(c - d).max() < 2e-3, (c.round(4).tolist(), d.round(4).tolist())
    assert not [t for t in said if 'image' in t], said


def test_an_attribute_node_without_a_name_reads_nothing_as_cycles(tmp_path):
    """An Attribute node (type Geometry) with an empty Name beside the mesh's render colour
    attribute (orange): Cycles reads nothing (Color and Fac 0, Alpha 1); only a Color Attribute
    node's empty layer means the render colour attribute (the fourth grid). It had read the
    render colour attribute (orange where Cycles is black)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 16
    for i, output in enumerate(('Color', 'Fac', 'Alpha', 'layer')):
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=2, y_subdivisions=2, size=0.9, location=(-1.5 + i, 0, 0))
        ob = bpy.context.object
        col = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'CORNER')
        col.data.foreach_set('color', np.tile([0.8, 0.3, 0.1, 1.0], len(col.data)))
        ob.data.color_attributes.render_color_index = 0
        mat, nt, out = scenes._material(output)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        if output == 'layer':
            node = nt.nodes.new('ShaderNodeVertexColor')
            s = node.outputs['Color']
        else:
            node = nt.nodes.new('ShaderNodeAttribute')
            node.attribute_name = ''
            s = node.outputs[output]
        nt.links.new(s, d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        ob.data.materials.append(mat)
    means = {e: np.array([img[4:12, 16 * i + 4:16 * i + 12].mean(axis=(0, 1)) for i in range(4)])
             for e, img in _render_both(sc, tmp_path, 4.0, 4).items()}
    c, d = means['CYCLES'], means['DACRT']
    assert c[:2].max() < 1e-4 and c[2:].min() > 0.05, c.round(4).tolist()     # black, black, lit, orange
    assert np.abs(d - c).max() < 1e-3 + 0.005 * c.max(), (c.round(4).tolist(), d.round(4).tolist())
