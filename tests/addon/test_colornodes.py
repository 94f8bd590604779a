"""Colour nodes: the numpy formulas against independent scalar references (Python's colorsys
for HSV; per-channel transcriptions of the blend modes' definitions), and the export's
evaluation of colour-node chains on constants and image texels (bpy)."""
import colorsys

import bpy
import numpy as np
import pytest

from addon import colornodes as cn
from addon import export
from addon.procedural import ProceduralTexels
from addon.texture import stored_texels

from . import scenes

RNG = np.random.default_rng(5)
COLOURS = np.concatenate([RNG.random((200, 3)), [[0, 0, 0], [1, 1, 1], [0.5, 0.5, 0.5], [1, 0, 0], [0, 1, 0],
                                                  [0, 0, 1], [1, 1, 0], [0.2, 0.2, 0.9]]])


def test_hsv_round_trip_matches_colorsys():
    hsv = cn.rgb_to_hsv(COLOURS)
    ref = np.array([colorsys.rgb_to_hsv(*c) for c in COLOURS])
    assert np.allclose(hsv, ref, atol=1e-12)
    assert np.allclose(cn.hsv_to_rgb(hsv), COLOURS, atol=1e-12)
    assert np.allclose(cn.hsv_to_rgb([1.0, 0.5, 0.8]), colorsys.hsv_to_rgb(0.0, 0.5, 0.8))   # hue 1 is hue 0


def _scalar_blend(blend, t, a, b):
    """One channel, written from the definitions (Cycles' kernel/svm/color_util.h)."""
    tm = 1 - t
    if blend == 'MIX':
        return tm * a + t * b
    if blend == 'MULTIPLY':
        return tm * a + t * a * b
    if blend == 'SCREEN':
        return 1 - (tm + t * (1 - b)) * (1 - a)
    if blend == 'OVERLAY':
        return a * (tm + 2 * t * b) if a < 0.5 else 1 - (tm + 2 * t * (1 - b)) * (1 - a)
    if blend == 'DIVIDE':
        return tm * a + t * a / b if b != 0 else a
    if blend == 'DODGE':
        if a == 0:
            return a
        d = 1 - t * b
        return 1.0 if d <= 0 else min(a / d, 1.0)
    if blend == 'BURN':
        d = tm + t * b
        return 0.0 if d <= 0 else min(max(1 - (1 - a) / d, 0.0), 1.0)
    if blend == 'EXCLUSION':
        return max(tm * a + t * (a + b - 2 * a * b), 0.0)
    if blend == 'LINEAR_LIGHT':
        return a + t * (2 * b - 1)
    if blend == 'SOFT_LIGHT':
        return tm * a + t * ((1 - a) * b * a + a * (1 - (1 - b) * (1 - a)))
    raise KeyError(blend)


@pytest.mark.parametrize('blend', ['MIX', 'MULTIPLY', 'SCREEN', 'OVERLAY', 'DIVIDE', 'DODGE', 'BURN',
                                   'EXCLUSION', 'LINEAR_LIGHT', 'SOFT_LIGHT'])
def test_blend_modes_per_channel(blend):
    a, b = COLOURS, COLOURS[::-1].copy()
    b[3] = 0.0                                  # a zero divisor
    for t in (0.0, 0.35, 1.0):
        got = cn.mix(blend, t, a, b)
        ref = np.vectorize(lambda x, y: _scalar_blend(blend, t, x, y))(a, b)
        assert np.allclose(got, ref, atol=1e-12), (blend, t)


def test_hsv_blends_and_hue_saturation():
    a, b = COLOURS, COLOURS[::-1]
    t = 0.4
    for i in range(len(a)):
        h1, h2 = colorsys.rgb_to_hsv(*a[i]), colorsys.rgb_to_hsv(*b[i])
        hue = np.array(colorsys.hsv_to_rgb(h2[0], h1[1], h1[2])) if h2[1] != 0 else a[i]
        assert np.allclose(cn.mix('HUE', t, a[i], b[i]), (1 - t) * a[i] + t * hue if h2[1] != 0 else a[i])
        val = colorsys.hsv_to_rgb(h1[0], h1[1], (1 - t) * h1[2] + t * h2[2])
        assert np.allclose(cn.mix('VALUE', t, a[i], b[i]), val)
        h, s, v = colorsys.rgb_to_hsv(*a[i])
        shifted = np.array(colorsys.hsv_to_rgb((h + 0.1 + 0.5) % 1.0, min(s * 1.5, 1.0), v * 0.8))
        ref = np.maximum(0.7 * shifted + 0.3 * a[i], 0.0)
        assert np.allclose(cn.hue_saturation(a[i], 0.1, 1.5, 0.8, 0.7), ref)


def test_constant_colours_under_per_texel_inputs_broadcast():
    """A constant colour under a per-texel Hue, Saturation or Value (Hue/Saturation/Value node)
    or factor (Mix in Value or Saturation blend) is each texel's own result (it raised a numpy
    broadcast error, failing the render)."""
    c, c2 = np.array([0.8, 0.3, 0.1]), np.array([0.2, 0.5, 0.9])
    per = np.array([[0.0, 0.25], [0.6, 1.0]])
    for k in range(3):
        args = [0.0, 1.0, 1.0]
        args[k] = per
        got = cn.hue_saturation(c, *args, 1.0)
        assert got.shape == (2, 2, 3)
        for i in np.ndindex(per.shape):
            one = [a[i] if np.ndim(a) else a for a in args]
            assert np.allclose(got[i], cn.hue_saturation(c, *one, 1.0)), (k, i)
    for blend in ('VALUE', 'SATURATION', 'HUE', 'COLOR'):
        got = cn.mix(blend, per[..., None], c, c2)
        assert got.shape == (2, 2, 3)
        for i in np.ndindex(per.shape):
            assert np.allclose(got[i], cn.mix(blend, per[i], c, c2)), (blend, i)


def test_simple_nodes():
    c = np.array([0.0, 0.25, 2.0])
    assert np.allclose(cn.invert(0.5, c), 0.5)
    assert np.allclose(cn.gamma(np.array([-0.5, 0.0, 0.25]), 2.0), [-0.5, 0.0, 0.0625])
    assert np.allclose(cn.brightness_contrast(c, 0.1, 0.5), np.maximum(1.5 * c + 0.1 - 0.25, 0))
    assert np.allclose(cn.gray([1.0, 1.0, 1.0]), 1.0, atol=1e-6)


def test_ramp_table_lookup():
    """A two-stop linear ramp is reproduced between table entries; Constant picks an entry."""
    table = cn.ramp_table(lambda p: (p, 1 - p, 0.5, 1.0))
    f = np.array([0.0, 0.1234, 0.5, 0.999, 1.0, -1.0, 2.0, np.nan])
    got = cn.ramp_lookup(table, f, True)
    ref = np.clip(np.nan_to_num(f, nan=1.0), 0, 1)        # NaN: the last stop, as in Cycles
    assert np.allclose(got[:, 0], ref, atol=1e-12) and np.allclose(got[:, 1], 1 - ref, atol=1e-12)
    # (Cycles: 257 entries at i / 256, so a Constant ramp at 0.5 reads entry 128, position 0.5)
    assert len(table) == cn.RAMP_TABLE_SIZE + 1
    assert np.allclose(cn.ramp_lookup(table, np.array([0.5, 0.499]), False)[:, 0], [0.5, 127 / 256])


# -- the export (bpy) ------------------------------------------------------------------------

def _image_material(name, px, chain, interpolation='Closest'):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image(name + " image", px)
    tex.interpolation = interpolation
    nt.links.new(chain(nt, tex), d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _exported_material(mat):
    builder = export.materials.MaterialBuilder()
    return builder.materials[builder.index(mat)]


PX = np.ones((2, 2, 4), np.float32)
PX[0, 0, :3], PX[0, 1, :3], PX[1, 0, :3], PX[1, 1, :3] = (0.25, 0.5, 0.75), (0.9, 0.1, 0.2), (0.05, 0.6, 0.3), \
    (0.7, 0.7, 0.1)
PX[0, 1, 3] = 0.3


def test_chain_on_an_image_is_baked_per_texel(scene):
    def chain(nt, tex):
        m = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], (0.5, 1.0, 0.0), 0.5)
        hs = nt.nodes.new('ShaderNodeHueSaturation')
        hs.inputs['Saturation'].default_value = 0.5
        nt.links.new(m.outputs['Result'], hs.inputs['Color'])
        return hs.outputs['Color']
    m = _exported_material(_image_material("Chain", PX, chain))
    expect = cn.hue_saturation(cn.mix('MULTIPLY', 0.5, PX[..., :3].astype(np.float64), np.array([0.5, 1.0, 0.0])),
                               0.5, 0.5, 1.0, 1.0)
    assert not m.approximated and m.texture is not None and m.texture_interpolation == 'Closest'
    assert np.allclose(m.texture[..., :3], expect, atol=1e-6) and np.allclose(m.texture[..., 3], PX[..., 3])
    assert np.allclose(m.base_color, 1.0)


def test_hue_outside_the_unit_range_falls_in_cycles_last_sector():
    """Cycles' hsv_to_rgb takes sectors 0-4 by i == k and everything else as sector 5, without
    wrapping the hue: Combine Color (HSV) of hue 1.2 is (v, p, q), not hue 0.2's (q, v, p)."""
    assert np.allclose(cn.hsv_to_rgb([1.2, 1.0, 0.8]), (0.8, 0.0, 0.64))
    assert np.allclose(cn.hsv_to_rgb([-0.25, 1.0, 0.8]), (0.8, 0.0, 0.4))


def test_float_mix_ignores_a_hidden_clamp_result(scene):
    """Clamp Result set in Color mode stays set (hidden) after a switch to Float; Cycles' float
    Mix has no result clamp: 0.4 and 2 mixed half and half are 1.2, not 1."""
    mat, nt, out = scenes._material("FloatMix")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    mix = nt.nodes.new('ShaderNodeMix')
    mix.clamp_result = True
    mix.data_type = 'FLOAT'
    mix.inputs['Factor'].default_value = 0.5
    mix.inputs['A'].default_value, mix.inputs['B'].default_value = 0.4, 2.0
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    assert np.allclose(m.base_color, 1.2, atol=1e-6), m.base_color


def test_constant_chain_folds_to_a_colour(scene):
    mat, nt, out = scenes._material("Folded")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    inv = nt.nodes.new('ShaderNodeInvert')
    inv.inputs['Fac'].default_value = 0.25
    nt.links.new(scenes.mix_node(nt, 'ADD', rgb.outputs[0], (0.1, 0.1, 0.1), 1.0).outputs['Result'], inv.inputs['Color'])
    nt.links.new(inv.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    c = np.array([0.3, 0.5, 0.7])
    assert m.texture is None and not m.approximated
    assert np.allclose(m.base_color, 0.75 * c + 0.25 * (1 - c), atol=1e-6)


def test_vector_map_range_and_mix_are_evaluated(scene):
    """A vector Map Range and a Mix in Vector mode (uniform and non-uniform factor) are
    evaluated (they fell back to the colour's own value, 'colour from Map Range node'); a
    vector into a float input is its average, as every vector output's (values: Cycles 5.0's)."""
    def node_io(node, ident, outputs=False):
        return next(s for s in (node.outputs if outputs else node.inputs) if s.identifier == ident)

    built = {}
    for name in ("MapRange", "MixUniform", "MixPerAxis", "MapRangeToFloat"):
        mat, nt, out = scenes._material(name)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        xyz = nt.nodes.new('ShaderNodeCombineXYZ')
        for i, v in enumerate((0.2, 0.7, 1.6)):
            xyz.inputs[i].default_value = v
        if name.startswith("MapRange"):
            n = nt.nodes.new('ShaderNodeMapRange')
            n.data_type, n.interpolation_type = 'FLOAT_VECTOR', 'LINEAR'
            for ident, v in (('From_Min_FLOAT3', (0.1, 0.9, 0.0)), ('From_Max_FLOAT3', (0.5, 0.3, 1.0)),
                             ('To_Min_FLOAT3', (0.1, 0.2, 0.3)), ('To_Max_FLOAT3', (0.9, 0.6, 0.8))):
                node_io(n, ident).default_value = v
            nt.links.new(xyz.outputs[0], node_io(n, 'Vector'))
            result = node_io(n, 'Vector', True)
        else:
            n = nt.nodes.new('ShaderNodeMix')
            n.data_type = 'VECTOR'
            if name == "MixPerAxis":
                n.factor_mode = 'NON_UNIFORM'
                node_io(n, 'Factor_Vector').default_value = (0.2, 0.5, 1.3)
            else:
                node_io(n, 'Factor_Float').default_value = 0.25
            node_io(n, 'B_Vector').default_value = (0.9, 0.1, 0.4)
            nt.links.new(xyz.outputs[0], node_io(n, 'A_Vector'))
            result = node_io(n, 'Result_Vector', True)
        if name == "MapRangeToFloat":
            result = scenes.read_as_float(nt, result)
        nt.links.new(result, d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        built[name] = _exported_material(mat)
    a, b = np.array([0.2, 0.7, 1.6]), np.array([0.9, 0.1, 0.4])
    mapped = np.array([0.3, 1.0 / 3.0, 0.8])
    for name, want in (("MapRange", mapped), ("MixUniform", 0.75 * a + 0.25 * b),
                       ("MixPerAxis", np.array([0.34, 0.4, 0.4])), ("MapRangeToFloat", np.full(3, mapped.mean()))):
        m = built[name]
        assert m.texture is None and not m.approximated, (name, m.approximated)
        assert np.allclose(m.base_color, want, atol=1e-5), (name, m.base_color, want)


def test_ramp_of_an_alpha_mask_beside_a_noise_and_a_second_image(scene):
    """A Color Ramp fed by the image's alpha, mixed with a Noise Texture (at factor 0) and a
    second image: the chain is compiled per point with both images looked up there (the Noise
    had read as its own value and the second image as its average, each reported)."""
    def chain(nt, tex):
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].color = (1, 0, 0, 1)
        ramp.color_ramp.elements[1].color = (0, 0, 1, 1)
        nt.links.new(tex.outputs['Alpha'], ramp.inputs['Fac'])
        noise = nt.nodes.new('ShaderNodeTexNoise')
        m = scenes.mix_node(nt, 'MIX', ramp.outputs['Color'], noise.outputs['Color'], 0.0)
        other = nt.nodes.new('ShaderNodeTexImage')
        other.image = scenes.float_image("Other", np.full((4, 4, 4), 0.5, np.float32))
        return scenes.mix_node(nt, 'MIX', m.outputs['Result'], other.outputs['Color'], 0.5).outputs['Result']
    m = _exported_material(_image_material("Ramp", PX, chain))
    a = PX[..., 3:4].astype(np.float64)
    ramp = np.concatenate([1 - a, 0 * a, a], axis=-1)
    assert isinstance(m.texture, ProceduralTexels) and 'uv' in m.texture.needs
    centres = np.array([[(j + 0.5) / 2, (i + 0.5) / 2, 0.0] for i in range(2) for j in range(2)], np.float32)
    got = m.texture.evaluate({'uv': centres, 'generated': centres, 'object': centres}).T.reshape(2, 2, 3)
    assert np.allclose(got, 0.5 * ramp + 0.25, atol=1e-5), got
    assert "Noise" not in m.approximated and "two image textures" not in m.approximated, m.approximated


@pytest.mark.parametrize('which', ['Hue', 'Saturation', 'Value'])
def test_an_image_into_hue_saturation_of_a_constant_colour(scene, which):
    """An image's texels into one of a Hue/Saturation/Value node's scalar inputs over a constant
    Color: baked per texel (the render failed with a broadcast error)."""
    def chain(nt, tex):
        hs = nt.nodes.new('ShaderNodeHueSaturation')
        hs.inputs['Color'].default_value = (0.8, 0.3, 0.1, 1.0)
        nt.links.new(tex.outputs['Color'], hs.inputs[which])
        return hs.outputs['Color']
    m = _exported_material(_image_material("HSV " + which, PX, chain))
    args = {'Hue': 0.5, 'Saturation': 1.0, 'Value': 1.0}
    args[which] = cn.gray(PX[..., :3].astype(np.float64))[..., 0]
    expect = cn.hue_saturation(np.array([0.8, 0.3, 0.1]), args['Hue'], args['Saturation'], args['Value'], 1.0)
    assert not m.approximated and m.texture is not None
    assert np.allclose(m.texture[..., :3], expect, atol=1e-6)


def _alpha_used(nt, tex):
    """The image's Color through a Mix whose Factor is Alpha > 2 (0 at every texel): the Alpha is
    used by the shader (Cycles folds no comparison of a linked value), the colour unchanged. (Not
    the Alpha into A of a Mix at factor 1: Cycles folds that Mix to its B and drops the Alpha.)"""
    gt = nt.nodes.new('ShaderNodeMath')
    gt.operation, gt.inputs[1].default_value = 'GREATER_THAN', 2.0
    nt.links.new(tex.outputs['Alpha'], gt.inputs[0])
    m = scenes.mix_node(nt, 'MIX', tex.outputs['Color'], (0.0, 0.0, 0.0), 0.0)
    nt.links.new(gt.outputs[0], m.inputs['Factor'])
    return m.outputs['Result']


def test_float_image_with_alpha_linked_is_unassociated(scene):
    """Cycles divides a float image's colour by its alpha when the Alpha output is linked
    (measured: 0.9 at alpha 0.3 reads 3.0); not when only Color is used."""
    def with_alpha(nt, tex):
        return _alpha_used(nt, tex)
    m = _exported_material(_image_material("Alpha", PX, with_alpha))
    assert np.allclose(m.texture[0, 1, :3], PX[0, 1, :3] / 0.3, atol=1e-6)
    assert np.allclose(m.texture[0, 0, :3], PX[0, 0, :3])
    plain = _exported_material(_image_material("Plain", PX, lambda nt, tex: tex.outputs['Color']))
    assert np.allclose(plain.texture[..., :3], PX[..., :3])
    # an Alpha linked only to a node the shader does not use: Cycles removes that node first,
    # and the colour stays associated (measured: DACRT was 4.6x Cycles with such a leftover)
    def dangling(nt, tex):
        nt.links.new(tex.outputs['Alpha'], nt.nodes.new('ShaderNodeMath').inputs[0])
        return tex.outputs['Color']
    left = _exported_material(_image_material("Leftover", PX, dangling))
    assert np.allclose(left.texture[..., :3], PX[..., :3])


def _byte_image(name, texel, alpha_mode='STRAIGHT', space='sRGB'):
    """A packed 8-bit image of one RGBA texel given in bytes."""
    img = bpy.data.images.new(name, 1, 1, alpha=True)
    img.pixels.foreach_set(np.asarray(texel, np.float32) / 255)
    img.pack()
    img.alpha_mode, img.colorspace_settings.name = alpha_mode, space
    return img


def _srgb_decode(c):
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


@pytest.mark.parametrize("alpha_linked", [False, True])
def test_byte_image_alpha_associated_in_its_encoding_as_cycles(scene, alpha_linked):
    """Cycles multiplies an 8-bit image's colour by its alpha on load, in bytes (c * a / 255,
    truncated) and before the sRGB decoding; a linked Alpha output divides it again, also before
    decoding (measured in Cycles 5.0: texel (255, 128, 51, 64) reads 0.0513, 0.0144, 0.0037
    with Alpha unlinked; the linked case gives back nearly the straight colour). Data and
    channel-packed images keep the straight colour."""
    def chain(tex):
        def build(nt, _):
            if alpha_linked:
                return _alpha_used(nt, tex)
            return tex.outputs['Color']
        return build

    def texel(alpha_mode='STRAIGHT', space='sRGB'):
        mat, nt, out = scenes._material(f"Decal {alpha_mode} {space} {alpha_linked}")
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = _byte_image(mat.name, (255, 128, 51, 64), alpha_mode, space)
        nt.links.new(chain(tex)(nt, tex), d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        return _exported_material(mat).texture[0, 0]
    premultiplied = np.array([64, 32, 12])          # (255, 128, 51) * 64 // 255
    expect = _srgb_decode(premultiplied / 64 if alpha_linked else premultiplied / 255)
    got = texel()
    assert np.allclose(got[:3], expect, atol=1e-6) and got[3] == np.float32(64 / 255)
    straight = np.array([255, 128, 51]) / 255
    assert np.allclose(texel('CHANNEL_PACKED')[:3], _srgb_decode(straight), atol=1e-6)
    assert np.allclose(texel(space='Non-Color')[:3], straight, atol=1e-6)


def test_udim_tile_without_a_file_reported_and_magenta(scene):
    """A generated UDIM image: bpy gives the first tile's pixels; a tile added in Python has no
    file to read, so it renders magenta (Cycles' missing image) and the render says why. The
    tiles' texels go through colour nodes tile by tile (here an Invert)."""
    mat, nt, out = scenes._material("Tiled")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.new("Tiles", 4, 2, tiled=True, float_buffer=True)
    tex.image.generated_color = (0.25, 0.5, 0.75, 1.0)
    tex.image.tiles.new(1002)
    inv = nt.nodes.new('ShaderNodeInvert')
    nt.links.new(tex.outputs['Color'], inv.inputs['Color'])
    nt.links.new(inv.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    assert ("UDIM image 'Tiles': tile 1002 could not be read from '' (magenta); packed or generated tiles "
            "other than the first are not supported") in m.approximated
    assert m.texture.numbers == (1001, 1002) and m.texture.shapes == ((2, 4), (1, 1))
    # a float generated tile holds its colour converted from sRGB; then inverted
    assert np.allclose(m.texture.tile(0)[..., :3], 1 - _srgb_decode(np.array([0.25, 0.5, 0.75])), atol=1e-4)
    assert np.allclose(m.texture.tile(1)[..., :3], [0.0, 1.0, 0.0])       # magenta, inverted


def test_fair_editor_keeps_colour_nodes(scene):
    """The benchmark's fair-material editor keeps what the export evaluates (the image, the Mix
    and Hue/Saturation nodes) and unlinks only the Noise Texture of Geometry Tangent (not
    evaluated), where the export reads the Mix input's own value."""
    from tests.bench import fairmaterials
    state = {}

    def chain(nt, tex):
        noise = nt.nodes.new('ShaderNodeTexNoise')
        geometry = nt.nodes.new('ShaderNodeNewGeometry')          # (Tangent: not read per point)
        nt.links.new(geometry.outputs['Tangent'], noise.inputs['Vector'])
        m = scenes.mix_node(nt, 'MULTIPLY', tex.outputs['Color'], noise.outputs['Color'], 0.5)
        hs = nt.nodes.new('ShaderNodeHueSaturation')
        nt.links.new(m.outputs['Result'], hs.inputs['Color'])
        state.update(noise=noise, mix=m, hs=hs)
        return hs.outputs['Color']
    mat = _image_material("Kept", PX, chain)
    assert "Noise Texture" in fairmaterials.remaining_approximations([mat])["Kept"]
    fairmaterials.make_diffuse([mat])
    assert fairmaterials.remaining_approximations([mat]) == {}
    assert not state['noise'].outputs['Color'].is_linked
    assert state['mix'].outputs['Result'].is_linked and state['hs'].outputs['Color'].is_linked


def test_negative_texels_from_colour_nodes_become_zero(scene):
    """Subtract can make texels negative; like a negative constant colour, they become 0 and
    the material says so."""
    m = _exported_material(_image_material(
        "Sub", PX, lambda nt, tex: scenes.mix_node(nt, 'SUBTRACT', tex.outputs['Color'], (0.5, 0.5, 0.5),
                                                   1.0).outputs['Result']))
    expect = np.maximum(PX[..., :3] - 0.5, 0.0)
    assert np.allclose(m.texture[..., :3], expect, atol=1e-6)
    assert "4 texel(s) of negative or non-finite colour from colour nodes set to 0" in m.approximated


def test_blackbody_is_blenders_light_temperature_colour(scene):
    """colornodes.blackbody against Blender's own computation, a light's Temperature colour
    (read from the evaluated light), across the fit's ranges and its two ends."""
    import bpy
    light = bpy.data.lights.new("Warm", 'POINT')
    light.use_temperature = True
    ob = bpy.data.objects.new("Warm", light)
    bpy.context.scene.collection.objects.link(ob)
    for kelvin in (850.0, 1000.0, 1300.0, 1700.0, 2700.0, 4000.0, 6500.0, 9000.0, 13000.0):
        light.temperature = kelvin
        dg = bpy.context.evaluated_depsgraph_get()
        dg.update()
        want = np.array(ob.evaluated_get(dg).data.temperature_color)
        np.testing.assert_allclose(cn.blackbody(np.array([[kelvin]]))[0], want, rtol=1e-5, atol=1e-6,
                                   err_msg=f"{kelvin} K")


def test_what_loading_an_image_says_reaches_every_material_that_reads_it(scene, monkeypatch):
    """Images are loaded once per export; what loading one says (a colour space read as
    another, say) is said in every material reading it. A material that read an image already
    loaded by another had lost those notes, and _build's rebuilds (a colour attribute beside
    an image, the glTF wiring) always did."""
    from addon.export import imagetextures
    load = imagetextures.image_pixels

    def noting(img, reasons, *args):
        reasons.append(f"loaded '{img.name}'")
        return load(img, reasons, *args)
    monkeypatch.setattr(imagetextures, 'image_pixels', noting)
    image = scenes.float_image("Shared", PX)

    def material(name):
        mat, nt, out = scenes._material(name)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = image
        nt.links.new(tex.outputs['Color'], d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        return mat
    builder = export.materials.MaterialBuilder()
    first, second = (builder.materials[builder.index(material(n))] for n in ("First", "Second"))
    assert "loaded 'Shared'" in first.approximated and "loaded 'Shared'" in second.approximated


def test_an_image_into_emission_strength_is_blended_as_stored(scene):
    """An 8-bit sRGB image (and nodes reading it) into an Emission's Strength: Cycles blends the
    stored bytes, decodes, runs the nodes, then scales the colour; baked before the blend, the
    hunter's screen emitted 5-6% more than Cycles. Halfway between texels 0 and 255 the strength
    is decode(0.5) = 0.214, not the mean of the decoded texels, 0.5."""
    from addon.texture import srgb_to_linear, stored_texels
    img = bpy.data.images.new("Strength map", 2, 1)
    img.pixels.foreach_set(np.array([0, 0, 0, 1, 1, 1, 1, 1], np.float32))
    mat, nt, out = scenes._material("Strength")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (1.0, 0.5, 0.25, 1.0)
    nt.links.new(tex.outputs['Color'], em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    stored = stored_texels(m.emission_texture)
    assert stored is not None
    got = stored.lookup(np.array([0.5], np.float32), np.array([0.5], np.float32), 'Linear', 'REPEAT')[:, 0]
    assert np.allclose(got, srgb_to_linear(0.5) * np.array([1.0, 0.5, 0.25]), rtol=1e-5)
    # what the light's choice and 'Closest' read: the texels themselves
    assert np.allclose(m.emission_texture[0, :, :3], [[0, 0, 0], [1.0, 0.5, 0.25]], atol=1e-6)


@pytest.mark.parametrize("interpolation", ['Closest', 'Linear'])
def test_alpha_mask_through_math_nodes_is_an_opacity_texture(scene, interpolation):
    """Blender's glTF importer wires an alpha mask as Principled Alpha <- 1 - (image alpha <
    cutoff): evaluated per texel into the opacity texture (before: 'driven by nodes; its own
    value used', an opaque card, 0.05x Cycles where the cut-out showed the ground)."""
    px = np.ones((2, 2, 4), np.float32)
    px[..., 3] = [[0.2, 0.7], [0.5, 0.0]]
    mat, nt, out = scenes._material(f"Mask {interpolation}")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image(f"Leaf {interpolation}", px)
    tex.interpolation = interpolation
    less = nt.nodes.new('ShaderNodeMath')
    less.operation, less.inputs[1].default_value = 'LESS_THAN', 0.5
    sub = nt.nodes.new('ShaderNodeMath')
    sub.operation, sub.inputs[0].default_value = 'SUBTRACT', 1.0
    nt.links.new(tex.outputs['Alpha'], less.inputs[0])
    nt.links.new(less.outputs[0], sub.inputs[1])
    nt.links.new(sub.outputs[0], p.inputs['Alpha'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    assert m.opacity is not None and "Principled alpha driven by nodes" not in m.approximated
    np.testing.assert_array_equal(m.opacity[..., 0], [[0, 1], [1, 0]])
    assert m.opacity_interpolation == interpolation
    assert ("evaluated per texel before the blend" in m.approximated) == (interpolation != 'Closest')


def test_mix_shader_with_an_image_factor_mixes_per_texel(scene):
    """A Mix Shader between two constant diffuse colours, its factor an 8-bit image: the
    albedo per texel, a + (b - a) x factor, the factor looked up as stored and decoded first
    (as Cycles blends, decodes, then mixes). It was mixed at the factor's own value, 0.5:
    0.83/1.00/1.24x Cycles' mean on the hunter's scene."""
    from addon.texture import srgb_to_linear, stored_texels
    img = bpy.data.images.new("Factor map", 2, 1)
    img.pixels.foreach_set(np.array([0, 0, 0, 1, 1, 1, 1, 1], np.float32))
    mat, nt, out = scenes._material("Mixed by an image")
    red, blue = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    red.inputs['Color'].default_value = (0.8, 0.1, 0.1, 1.0)
    blue.inputs['Color'].default_value = (0.1, 0.2, 0.9, 1.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    nt.links.new(tex.outputs['Color'], mix.inputs['Fac'])
    nt.links.new(red.outputs[0], mix.inputs[1])
    nt.links.new(blue.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    a, b = np.array([0.8, 0.1, 0.1]), np.array([0.1, 0.2, 0.9])
    assert "factor not computed" not in m.approximated
    np.testing.assert_allclose(m.texture[0, :, :3], [a, b], atol=1e-6)
    got = stored_texels(m.texture).lookup(np.array([0.5], np.float32), np.array([0.5], np.float32),
                                          'Linear', 'REPEAT')[:, 0]
    np.testing.assert_allclose(got, a + (b - a) * srgb_to_linear(0.5), rtol=1e-5)


@pytest.mark.parametrize('shader', ['diffuse', 'emission'])
def test_alpha_reading_chain_on_an_8bit_image_runs_after_the_lookup_for_emission_too(scene, tmp_path, shader):
    """An 8-bit RGBA image's Alpha mixing its colour over a constant (a decal) runs after the
    lookup on the blended colour and alpha, as Cycles runs it, for an emission colour as for a
    diffuse one: nothing said (it had been baked into the texels before the blend, said;
    tests/parity/test_image_alpha_chains.py compares the renders)."""
    path = scenes.write_image(tmp_path / "decal.png", (PX * 255).round().astype(np.uint8))
    mat, nt, out = scenes._material("Decal")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.load(path)
    mix = scenes.mix_node(nt, 'MIX', (0.2, 0.3, 0.4), tex.outputs['Color'], 0.5)
    nt.links.new(tex.outputs['Alpha'], mix.inputs['Factor'])
    node = nt.nodes.new('ShaderNodeEmission' if shader == 'emission' else 'ShaderNodeBsdfDiffuse')
    nt.links.new(mix.outputs['Result'], node.inputs['Color'])
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    m = _exported_material(mat)
    assert not [t for t in m.approximated if 'before the blend' in t], m.approximated
    stored = stored_texels(m.emission_texture if shader == 'emission' else m.texture)
    assert stored is not None and stored.reads_alpha


def test_emission_colour_and_strength_from_two_images(scene):
    """An emission's Color from one image and its Strength from another of another size: the
    strength's average, said (the render had failed: 'operands could not be broadcast together
    with shapes (4,4,3) (3,5,1)'); from the same image, multiplied per texel and said unless
    the lookup is Closest."""
    colour = scenes.float_image("Colour", np.full((4, 4, 4), 0.5, np.float32))
    mask_px = np.zeros((3, 5, 4), np.float32)
    mask_px[..., :3] = np.linspace(0, 1, 15, dtype=np.float32).reshape(3, 5)[..., None]
    mask_px[..., 3] = 1.0
    mask = scenes.float_image("Mask", mask_px)

    def material(name, strength_image):
        mat, nt, out = scenes._material(name)
        em = nt.nodes.new('ShaderNodeEmission')
        a, b = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeTexImage')
        a.image, b.image = colour, strength_image
        nt.links.new(a.outputs['Color'], em.inputs['Color'])
        nt.links.new(b.outputs['Color'], em.inputs['Strength'])
        nt.links.new(em.outputs[0], out.inputs['Surface'])
        return _exported_material(mat)
    two = material("Two", mask)
    assert "strength from image 'Mask' beside a colour from image 'Colour'" in two.approximated
    np.testing.assert_allclose(two.emission, 0.5 * cn.gray(mask_px[..., :3]).mean(), rtol=1e-5)
    same = material("Same", colour)
    assert "colour and strength from image 'Colour' multiplied per texel" in same.approximated
