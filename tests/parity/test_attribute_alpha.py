"""An Alpha output read beside a mesh colour attribute agrees with Cycles: Object Info Alpha x a
corner colour attribute (collection instances and plain objects, each with its own viewport
colour alpha), an Object attribute's Alpha x the colour attribute, and a second colour
attribute's Alpha as a per-corner mask. Before, the several-attribute probes held every alpha at
1, so an Alpha output did not count as followed: the single-attribute path read the colour
attribute's values for it (its alpha), 2.06x Cycles for the per-object ones (every object as if
its alpha were 1), 2.61x and uniform for the mask, said only as an interpolation note. Small
quads under a straight-down sun, direct light only: exact per sample."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_color_attributes import _render_both

pytestmark = pytest.mark.usefixtures('parity_addon')

W, H, SCALE = 64, 48, 4.0           # 16 pixels a unit
XS = (-1.5, -0.5, 0.5, 1.5)
ALPHAS = (0.1, 0.35, 0.6, 0.87)
COL = (0.9, 0.6, 0.3, 0.4)          # (its alpha is none of the objects': reading it is seen)


def material(name, alpha_of):
    """Diffuse Color = mesh attribute 'col' x alpha_of(node tree) (Mix Multiply)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    c = nt.nodes.new('ShaderNodeAttribute')
    c.attribute_type, c.attribute_name = 'GEOMETRY', 'col'
    mix = scenes.mix_node(nt, 'MULTIPLY', c.outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(alpha_of(nt), mix.inputs['B'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def object_info_alpha(nt):
    return nt.nodes.new('ShaderNodeObjectInfo').outputs['Alpha']


def object_attribute_alpha(nt):
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = 'OBJECT', 'tint'
    return a.outputs['Alpha']


def mask_alpha(nt):
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = 'GEOMETRY', 'mask'
    return a.outputs['Alpha']


def quad(name, mat, location, hx=0.25, hy=0.25, mask=None):
    """A quad with corner colour 'col' (COL), and 'mask' white at these corner alphas."""
    ob = scenes.mesh(name, [(-hx, -hy, 0), (hx, -hy, 0), (hx, hy, 0), (-hx, hy, 0)], [(0, 1, 2, 3)],
                     location, [mat])
    col = ob.data.color_attributes.new('col', 'FLOAT_COLOR', 'CORNER')
    for loop in ob.data.loops:
        col.data[loop.index].color = COL
    if mask is not None:
        m = ob.data.color_attributes.new('mask', 'FLOAT_COLOR', 'CORNER')
        for loop in ob.data.loops:
            m.data[loop.index].color = (1, 1, 1, mask[loop.vertex_index])
    ob.data.color_attributes.active_color_index = 0
    return ob


def at(img, x, y):
    """The pixel at world (x, y)."""
    return img[int(H / 2 + y * W / SCALE), int(W / 2 + x * W / SCALE)]      # (rows bottom up)


def test_alpha_outputs_beside_a_colour_attribute_match_cycles(tmp_path, said):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    info = material("Info", object_info_alpha)
    # row 1.05: collection instances (the empties' colour alphas); row 0.35: plain objects
    src = quad("Src", info, (0, 0, 0))
    coll = bpy.data.collections.new("SrcC")
    coll.objects.link(src)
    sc.collection.objects.unlink(src)
    sc.collection.children.link(coll)
    sc.view_layers[0].layer_collection.children['SrcC'].exclude = True
    for x, a in zip(XS, ALPHAS):
        e = bpy.data.objects.new(f"E{x}", None)
        e.instance_type, e.instance_collection = 'COLLECTION', coll
        e.location, e.color = (x, 1.05, 0), (1, 1, 1, a)
        sc.collection.objects.link(e)
        quad(f"P{x}", info, (x, 0.35, 0)).color = (1, 1, 1, a)
    # row -0.35: an Object attribute's Alpha
    tint = material("Tint", object_attribute_alpha)
    for x, a in zip(XS, ALPHAS):
        quad(f"T{x}", tint, (x, -0.35, 0))['tint'] = (0.2, 0.5, 0.7, a)
    # row -1.1: one strip, a second colour attribute's Alpha as a mask varying along it
    quad("Mask", material("Mask", mask_alpha), (0, -1.1, 0), hx=1.9, hy=0.3, mask=(0.1, 0.9, 0.5, 0.2))
    sc.render.resolution_x, sc.render.resolution_y = W, H
    imgs = _render_both(sc, tmp_path, SCALE, 16)
    cells = [(x, y) for y in (1.05, 0.35, -0.35) for x in XS]
    c = np.array([at(imgs['CYCLES'], x, y) for x, y in cells])
    d = np.array([at(imgs['DACRT'], x, y) for x, y in cells])
    expected = np.array(COL[:3]) * np.array(ALPHAS)[:, None]
    assert np.allclose(c.reshape(3, 4, 3), expected, atol=0.01), c.round(3).tolist()      # the set-up
    assert np.abs(c - d).max() < 2e-3, (np.abs(c - d).max(axis=1).round(4).tolist(), c.round(3).tolist(),
                                        d.round(3).tolist())
    # the mask strip (x -1.9..1.9, y -1.4..-0.8) in 6 blocks of 10 x 8 pixels: means (the
    # gradient, ~0.012 a pixel, makes single pixels differ by where the filter samples them)
    rows = slice(int(H / 2 - 1.35 * W / SCALE), int(H / 2 - 0.85 * W / SCALE))
    cm, dm = ([img[rows, 2 + 10 * i:12 + 10 * i].mean(axis=(0, 1)) for i in range(6)]
              for img in (imgs['CYCLES'], imgs['DACRT']))
    cm, dm = np.array(cm), np.array(dm)
    assert np.ptp(cm[:, 0]) > 0.1, cm.round(3).tolist()                                    # the mask varies
    assert np.abs(cm - dm).max() < 5e-3, (cm.round(4).tolist(), dm.round(4).tolist())
    # (the per-object Alphas are exact: no interpolation note for them)
    assert not [s for s in said if "'Info'" in s or "'Tint'" in s], said


def test_an_attribute_missing_from_the_values_reads_no_other_attributes():
    """An attribute the albedo does not follow (absent from evaluated_albedo's values) reads
    colour and alpha 1, not the first attribute's values (as an Alpha output had)."""
    from addon.export.materials import MaterialBuilder
    b = MaterialBuilder()
    b._attribute_names = []
    b._attribute_pixels = {'col': np.full((1, 3, 4), 0.25, np.float32)}
    assert np.array_equal(b._pixels_of('mask'), np.ones((1, 3, 4), np.float32))
    assert np.array_equal(b._pixels_of('col'), np.full((1, 3, 4), 0.25, np.float32))
