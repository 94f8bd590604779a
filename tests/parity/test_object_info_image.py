"""An Image Texture times a per-object value (Object Info Color, Random through a Color Ramp,
Alpha, Object Index, Material Index, Location; each object and each collection instance its
own) renders as Cycles: the image per texel, the value per object. The export had taken the
value for a second image ("two image textures mixed; the second as its average colour") and
averaged the image away (the regression hunt's sphere: 1.012x Cycles, 8x6 blocks to 1.34x).
Eight planes under a straight-down sun, direct light only (exact per sample up to the pixel
filter): each plane's mean and its 2 x 2 quarters' means against Cycles'. A chain that is not
such a product (Random mixing the image with a tint) is still approximated, said as what it is."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image(name, seed):
    px = np.random.default_rng(seed).uniform(0.15, 1.0, (4, 4, 4)).astype(np.float32)
    px[..., 3] = 1.0
    return scenes.float_image(name, px)


def _material(name, value, seed, image_first=False, pass_index=0):
    """Diffuse of an image Mix Multiply'd with value(nt) (a colour or number socket)."""
    mat, nt, out = scenes._material(name)
    mat.pass_index = pass_index
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = _image(name, seed)
    a, b = (tex.outputs['Color'], value(nt)) if image_first else (value(nt), tex.outputs['Color'])
    nt.links.new(scenes.mix_node(nt, 'MULTIPLY', a, b, 1.0).outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _info(output, *after):
    def value(nt):
        s = nt.nodes.new('ShaderNodeObjectInfo').outputs[output]
        for make in after:
            s = make(nt, s)
        return s
    return value


def _times(k):
    def make(nt, s):
        m = nt.nodes.new('ShaderNodeMath')
        m.operation, m.inputs[1].default_value = 'MULTIPLY', k
        nt.links.new(s, m.inputs[0])
        return m.outputs[0]
    return make


def _ramp(nt, s):
    r = nt.nodes.new('ShaderNodeValToRGB')
    r.color_ramp.elements[0].color = (1, 0.1, 0, 1)
    r.color_ramp.elements[1].color = (0, 0.3, 1, 1)
    nt.links.new(s, r.inputs['Fac'])
    return r.outputs['Color']


def _absolute(nt, s):
    m = nt.nodes.new('ShaderNodeVectorMath')
    m.operation = 'ABSOLUTE'
    nt.links.new(s, m.inputs[0])
    return m.outputs['Vector']


def _plane(name, location, mat):
    """A 0.9-wide plane with its UV map (the image over it once)."""
    bpy.ops.mesh.primitive_plane_add(size=0.9, location=location)
    ob = bpy.context.object
    ob.name = name
    ob.data.materials.append(mat)
    return ob


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 128, 64
    colour = _material("Colour", _info('Color'), 1)
    ramp = _material("Ramp", _info('Random', _ramp), 2, image_first=True)
    cells = [(-1.5, 0.5), (-0.5, 0.5), (0.5, 0.5), (1.5, 0.5), (-1.5, -0.5), (-0.5, -0.5), (0.5, -0.5), (1.5, -0.5)]
    for i, col in enumerate(((0.9, 0.5, 0.2, 1), (0.2, 0.6, 0.9, 1))):
        _plane(f"Tinted{i}", (*cells[i], 0), colour).color = col
    kit = bpy.data.collections.new("Kit")          # instanced twice: a Random per instance
    piece = _plane("Piece", (0, 0, 0), ramp)
    kit.objects.link(piece)
    sc.collection.objects.unlink(piece)
    for i in (2, 3):
        empty = bpy.data.objects.new(f"Kit{i}", None)
        empty.instance_type, empty.instance_collection = 'COLLECTION', kit
        empty.location = (*cells[i], 0)
        sc.collection.objects.link(empty)
    alpha = _plane("Alpha", (*cells[4], 0), _material("AlphaMat", _info('Alpha'), 3))
    alpha.color = (1, 1, 1, 0.4)
    index = _plane("Index", (*cells[5], 0), _material("IndexMat", _info('Object Index', _times(0.25)), 4, True))
    index.pass_index = 3
    _plane("MatIndex", (*cells[6], 0), _material("MatIndexMat", _info('Material Index', _times(0.3)), 5,
                                                 pass_index=2))
    _plane("Location", (*cells[7], 0.4), _material("LocationMat", _info('Location', _absolute), 6))
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    scenes.light('SUN', math.pi, angle=0.0)
    scenes.black_world()
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    return sc


def _quarters(img):
    """(8 cells, 2 x 2 quarters, 3): each plane's quarters' mean colours (edges left out)."""
    return np.array([[[img[32 * r + 16 * qr + 3:32 * r + 16 * qr + 13, 32 * c + 16 * qc + 3:32 * c + 16 * qc + 13]
                       .mean((0, 1)) for qr in (0, 1) for qc in (0, 1)] for c in range(4)] for r in range(2)]
                    ).reshape(8, 4, 3)


def _both_quarters(sc, tmp_path):
    """(Cycles', DACRT's) _quarters of the scene rendered by each."""
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        rgb = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
        got[engine] = _quarters(rgb)
    return got['CYCLES'], got['DACRT']


def test_image_times_object_info_renders_per_texel_and_per_object(tmp_path, said):
    sc = _scene()
    c, d = _both_quarters(sc, tmp_path)
    assert not any("two image textures" in t or "average colour" in t for t in said), said
    assert c.min() > 0.02
    assert np.ptp(c.mean(1)[2:4], axis=0).max() > 0.02         # the two instances differ
    assert (np.ptp(c, axis=1) > 0.02).any(axis=1).all()        # each plane shows its image
    means = np.abs(d.mean(1) - c.mean(1)) / c.mean(1)
    quarters = np.abs(d - c) / c
    assert means.max() < 0.01 and quarters.max() < 0.02, (means.max(1).round(4).tolist(),
                                                         quarters.max((1, 2)).round(4).tolist())


def test_image_mixed_by_random_is_said_as_what_it_is(tmp_path, said):
    """Mix(Random, tint, image) is no product of the value and the image: still approximated
    (the image as its average), said so, naming the Object Info output, not 'two images'."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 8
    mat, nt, out = scenes._material("RandomMix")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = _image("RandomMix", 7)
    mix = scenes.mix_node(nt, 'MIX', (0.2, 0.4, 0.9), tex.outputs['Color'])
    nt.links.new(nt.nodes.new('ShaderNodeObjectInfo').outputs['Random'], mix.inputs['Factor'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    _plane("P", (0, 0, 0), mat)
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    sc.render.engine = 'DACRT'
    sc.dacrt.samples = 1
    scenes.render_exr(tmp_path / "d.exr", sc)
    text = ' '.join(said)
    assert "two image textures" not in text, said
    assert "Object Info Random" in text and "'RandomMix'" in text and "average" in text, said


def _several(image_first):
    """Object Info Color x the image x (Random x Alpha): three per-object values, each its own."""
    def value(nt):
        info = nt.nodes.new('ShaderNodeObjectInfo')
        times = nt.nodes.new('ShaderNodeMath')
        times.operation = 'MULTIPLY'
        nt.links.new(info.outputs['Random'], times.inputs[0])
        nt.links.new(info.outputs['Alpha'], times.inputs[1])
        return scenes.mix_node(nt, 'MULTIPLY', info.outputs['Color'], times.outputs[0], 1.0).outputs['Result']
    return value


def test_image_times_several_per_object_values_renders_as_cycles(tmp_path, said):
    """Several per-object values (Color, Random, Alpha) times an image, either order, on two
    objects and two collection instances each: the product per object and per texel (the image
    had been averaged, or the values read as the nodes' own, said)."""
    sc = _scene()
    for ob in list(sc.objects):
        if ob.type in ('MESH', 'EMPTY'):
            bpy.data.objects.remove(ob)
    cells = [(-1.5, 0.5), (-0.5, 0.5), (0.5, 0.5), (1.5, 0.5), (-1.5, -0.5), (-0.5, -0.5), (0.5, -0.5), (1.5, -0.5)]
    for row, first in ((0, False), (1, True)):
        mat = _material(f"Several{row}", _several(first), 10 + row, image_first=first)
        for i in (0, 1):
            ob = _plane(f"Own{row}{i}", (*cells[4 * row + i], 0), mat)
            ob.color = ((0.9, 0.5, 0.2, 0.7), (0.3, 0.7, 0.9, 0.5))[i]
        kit = bpy.data.collections.new(f"Kit{row}")
        piece = _plane(f"Piece{row}", (0, 0, 0), mat)
        piece.color = (0.8, 0.8, 0.4, 0.9)
        kit.objects.link(piece)
        sc.collection.objects.unlink(piece)
        for i in (2, 3):
            empty = bpy.data.objects.new(f"Kit{row}{i}", None)
            empty.instance_type, empty.instance_collection = 'COLLECTION', kit
            empty.location = (*cells[4 * row + i], 0)
            sc.collection.objects.link(empty)
    c, d = _both_quarters(sc, tmp_path)
    assert not any("Object Info" in t or "average colour" in t for t in said), said
    assert c.min() > 0.005 and (np.ptp(c, axis=1) > 0.005).any(axis=1).all()
    assert np.ptp(c.mean(1)[[2, 3, 6, 7]], axis=0).max() > 0.01          # the instances differ
    means = np.abs(d.mean(1) - c.mean(1)) / c.mean(1)
    quarters = np.abs(d - c) / c
    assert means.max() < 0.01 and quarters.max() < 0.02, (means.max(1).round(4).tolist(),
                                                         quarters.max((1, 2)).round(4).tolist())
