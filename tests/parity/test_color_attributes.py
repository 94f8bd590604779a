"""Colour attributes (Color Attribute and Attribute nodes into a diffuse colour) agree with
Cycles: float colours on points, byte colours on corners through a Mix Multiply tint, float
colours on faces read by an Attribute node; each read per point and interpolated over the
triangle as Cycles does (byte colours decoded per corner first). Three 4 x 4 grids of random
colours under a straight-down sun, direct light only, so each grid's mean is exact up to the
pixel filter's sampling: both engines agree within 0.5% per channel (measured 0.2%). Before,
the node's own (white) colour was used and the material reported as approximated. A fourth
grid multiplies an 8-bit image by the colours (a glTF import's vertex colours): the image is
looked up as Cycles stores it and the colours multiply it per point."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

CASES = (('point_float', 'POINT', 'FLOAT_COLOR', 'direct'), ('corner_byte', 'CORNER', 'BYTE_COLOR', 'tint'),
         ('face_float', 'FACE', 'FLOAT_COLOR', 'attribute'), ('point_image', 'POINT', 'FLOAT_COLOR', 'image'))


def _grid(name, x, domain, kind, chain):
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=4, size=0.9, location=(x, 0, 0))
    ob = bpy.context.object
    ob.name = name
    attr = ob.data.color_attributes.new('Col', kind, domain)
    c = np.random.default_rng(3).random((len(attr.data), 4)).astype(np.float32)
    c[:, 3] = 1.0
    attr.data.foreach_set('color', c.ravel())
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    s = scenes.colour_attribute(nt, 'Col', by_attribute_node=chain == 'attribute')
    if chain == 'tint':
        s = scenes.mix_node(nt, 'MULTIPLY', s, (0.5, 0.8, 1.0), 1.0).outputs['Result']
    elif chain == 'image':                    # an 8-bit image times the colours (glTF's COLOR_0)
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = bpy.data.images.new("Checker", 4, 4)
        tex.image.generated_type = 'COLOR_GRID'
        s = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], s, 1.0).outputs['Result']
    nt.links.new(s, d.inputs['Color'])
    ob.data.materials.append(mat)


def _render_both(sc, tmp_path, ortho_scale, samples):
    """Both engines' RGB (H, W, 3) of the scene under an orthographic view from above and a sun
    straight down, direct light only (exact per sample up to the pixel filter's sampling)."""
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=ortho_scale)
    scenes.light('SUN', math.pi, angle=0.0)
    scenes.black_world()
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    images = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        images[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
    return images


def test_colour_attributes_match_cycles(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 128, 32
    for i, case in enumerate(CASES):
        _grid(case[0], -1.5 + i, *case[1:])
    means = {engine: np.array([img[4:28, 32 * i + 4:32 * i + 28].mean(axis=(0, 1)) for i in range(len(CASES))])
             for engine, img in _render_both(sc, tmp_path, 4.0, 16).items()}
    assert means['CYCLES'].min() > 0.05 and np.ptp(means['CYCLES'], axis=0).max() > 0.05   # colours, not grey
    rel = np.abs(means['DACRT'] - means['CYCLES']) / means['CYCLES']
    assert rel.max() < 0.005, (rel.round(4).tolist(), means)


def _instancer(source, points):
    """An object whose Geometry Nodes put an instance of `source` on each of `points`."""
    me = bpy.data.meshes.new("Points")
    me.from_pydata(points, [], [])
    ob = bpy.data.objects.new("Scatter", me)
    bpy.context.scene.collection.objects.link(ob)
    ng = bpy.data.node_groups.new("Scatter", 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    iop, info = ng.nodes.new('GeometryNodeInstanceOnPoints'), ng.nodes.new('GeometryNodeObjectInfo')
    info.inputs[0].default_value = source
    ng.links.new(gi.outputs[0], iop.inputs['Points'])
    ng.links.new(info.outputs['Geometry'], iop.inputs['Instance'])
    ng.links.new(iop.outputs[0], go.inputs[0])
    ob.modifiers.new("GN", 'NODES').node_group = ng
    return ob


def test_object_info_random_and_colour_match_cycles(tmp_path):
    """Object Info per object: Random into a Color Ramp on six Geometry Nodes instances (Cycles:
    the instance's random_id / (2^32 - 1)) and on two objects of their own (Cycles: a hash of
    the name), Color (the object's colour) on two more. Each cell's centre pixel agrees with
    Cycles within 1e-3 (direct sun light, exact per sample); the ramp is evaluated on each
    object's value, so any node chain is exact."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 128, 32
    ramp_mat, nt, out = scenes._material("Ramp")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    info = nt.nodes.new('ShaderNodeObjectInfo')
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (1, 0, 0, 1)
    ramp.color_ramp.elements[1].color = (0, 0.2, 1, 1)
    nt.links.new(info.outputs['Random'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    colour_mat, nt, out = scenes._material("Colour")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(nt.nodes.new('ShaderNodeObjectInfo').outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    source = scenes.plane("Source", size=0.45, location=(0, 100, 0), materials=(ramp_mat,))
    xs = (-1.75, -1.25, -0.75)
    _instancer(source, [(x, y, 0) for x in xs for y in (-0.25, 0.25)])
    cells = [(x, y) for x in xs for y in (-0.25, 0.25)]
    for i, x in enumerate((-0.25, 0.25)):
        scenes.plane(f"Own{i}", size=0.45, location=(x, 0, 0), materials=(ramp_mat,))
        cells.append((x, 0.0))
    for i, (x, col) in enumerate(((1.0, (0.9, 0.2, 0.1, 1)), (1.5, (0.1, 0.8, 0.3, 1)))):
        scenes.plane(f"Tinted{i}", size=0.45, location=(x, 0, 0), materials=(colour_mat,)).color = col
        cells.append((x, 0.0))
    got = {engine: np.array([img[int(16 + y * 32), int(64 + x * 32)] for x, y in cells])
           for engine, img in _render_both(sc, tmp_path, 4.0, 4).items()}
    c, d = got['CYCLES'], got['DACRT']
    assert len({tuple(np.round(v, 3)) for v in c}) == len(cells)      # every object its own colour
    assert np.abs(c - d).max() < 1e-3, (c.round(4).tolist(), d.round(4).tolist())
