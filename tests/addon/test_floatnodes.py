"""Float nodes (Math, Map Range, Clamp), the HSL conversions of Separate/Combine Color and the
RGB Curves lookup, against values worked by hand from Cycles' definitions and against Python's
colorsys; the export's evaluation of them per texel; Cycles renders of them are compared in
tests/parity/test_color_nodes.py."""
import colorsys
import math

import bpy
import numpy as np
import pytest

from addon import colornodes as cn
from addon import floatnodes as fn
from addon import nodeeval

from . import scenes

# (operation, a, b, c, expected): Cycles' svm_math with its safe_* rules (0 where undefined)
MATH_CASES = [
    ('ADD', 0.25, 0.5, 0, 0.75), ('SUBTRACT', 0.25, 0.5, 0, -0.25), ('MULTIPLY', 3, -2, 0, -6),
    ('DIVIDE', 1, 4, 0, 0.25), ('DIVIDE', 1, 0, 0, 0.0), ('MULTIPLY_ADD', 2, 3, 1, 7),
    ('POWER', 2, 10, 0, 1024), ('POWER', -2, 3, 0, -8), ('POWER', -2, 0.5, 0, 0.0),
    ('LOGARITHM', 8, 2, 0, 3), ('LOGARITHM', -1, 2, 0, 0.0), ('LOGARITHM', 8, 1, 0, 0.0),
    ('SQRT', 9, 0, 0, 3), ('SQRT', -4, 0, 0, 0.0), ('INVERSE_SQRT', 4, 0, 0, 0.5), ('INVERSE_SQRT', 0, 0, 0, 0.0),
    ('ABSOLUTE', -1.5, 0, 0, 1.5), ('EXPONENT', 1, 0, 0, math.e), ('MINIMUM', 2, -1, 0, -1), ('MAXIMUM', 2, -1, 0, 2),
    ('LESS_THAN', 1, 2, 0, 1), ('GREATER_THAN', 1, 2, 0, 0), ('SIGN', -3, 0, 0, -1), ('SIGN', 0, 0, 0, 0),
    ('COMPARE', 1, 1.05, 0.1, 1), ('COMPARE', 1, 1.2, 0.1, 0),
    ('SMOOTH_MIN', 1, 1.2, 0.5, 1 - 0.6 ** 3 * 0.5 / 6), ('SMOOTH_MAX', 1, 1.2, 0.5, 1.2 + 0.6 ** 3 * 0.5 / 6),
    ('SMOOTH_MIN', 1, 3, 0, 1), ('ROUND', -1.5, 0, 0, -1), ('ROUND', 2.5, 0, 0, 3), ('FLOOR', -1.5, 0, 0, -2),
    ('CEIL', -1.5, 0, 0, -1), ('TRUNC', -1.7, 0, 0, -1), ('FRACT', -1.25, 0, 0, 0.75),
    ('MODULO', -3.5, 2, 0, -1.5), ('MODULO', 3, 0, 0, 0.0), ('FLOORED_MODULO', -3.5, 2, 0, 0.5),
    ('WRAP', 5.5, 2, 0, 1.5), ('WRAP', 1, 2, 2, 2), ('SNAP', 3.7, 0.5, 0, 3.5), ('PINGPONG', 2.5, 1, 0, 0.5),
    ('PINGPONG', 1, 0, 0, 0.0), ('SINE', math.pi / 2, 0, 0, 1), ('COSINE', 0, 0, 0, 1), ('TANGENT', math.pi / 4, 0, 0, 1),
    ('ARCSINE', 2, 0, 0, math.pi / 2), ('ARCCOSINE', -2, 0, 0, math.pi), ('ARCTANGENT', 1, 0, 0, math.pi / 4),
    ('ARCTAN2', 1, -1, 0, 3 * math.pi / 4), ('ARCTAN2', 0, 0, 0, 0.0), ('SINH', 1, 0, 0, math.sinh(1)),
    ('COSH', 1, 0, 0, math.cosh(1)), ('TANH', 1, 0, 0, math.tanh(1)), ('RADIANS', 180, 0, 0, math.pi),
    ('DEGREES', math.pi, 0, 0, 180),
]


def test_math_operations_worked_by_hand():
    assert {c[0] for c in MATH_CASES} == fn.MATH_OPERATIONS
    for op, a, b, c, want in MATH_CASES:
        assert fn.math(op, a, b, c) == pytest.approx(want, abs=1e-12), op
    assert fn.math('ADD', 0.8, 0.5, 0, clamp=True) == 1.0
    assert fn.math('SUBTRACT', 0.2, 0.5, 0, clamp=True) == 0.0
    per_texel = fn.math('MULTIPLY', np.array([[[0.5], [2.0]]]), 3.0, 0.0)
    assert per_texel.shape == (1, 2, 1) and np.allclose(per_texel.ravel(), [1.5, 6.0])


def test_map_range_and_clamp_worked_by_hand():
    mr = fn.map_range
    assert mr('LINEAR', 0.25, 0, 0.5, 10, 20, 4, False) == pytest.approx(15)
    assert mr('LINEAR', 1.0, 0, 0.5, 10, 20, 4, False) == pytest.approx(30)
    assert mr('LINEAR', 1.0, 0, 0.5, 10, 20, 4, True) == pytest.approx(20)
    assert mr('LINEAR', 1.0, 0, 0.5, 20, 10, 4, True) == pytest.approx(10)        # To Min > To Max
    assert mr('LINEAR', 0.3, 0.5, 0.5, 10, 20, 4, False) == 0.0                   # empty From range
    assert mr('STEPPED', 0.3, 0, 1, 0, 1, 4, False) == pytest.approx(0.25)        # floor(0.3 * 5) / 4
    assert mr('STEPPED', 0.3, 0, 1, 0, 1, 0, False) == 0.0
    t = 0.65 / 0.7                                                                # smoothstep(0.1, 0.8, 0.75)
    assert mr('SMOOTHSTEP', 0.75, 0.1, 0.8, 0, 1, 4, True) == pytest.approx((3 - 2 * t) * t * t)
    assert mr('SMOOTHSTEP', 0.75, 0.8, 0.1, 0, 1, 4, True) == pytest.approx(1 - (3 - 2 * t) * t * t)
    assert mr('SMOOTHERSTEP', 0.75, 0.1, 0.8, 0, 1, 4, True) == pytest.approx(t ** 3 * (t * (6 * t - 15) + 10))
    assert mr('SMOOTHERSTEP', 2.0, 0.1, 0.8, 0, 1, 4, True) == pytest.approx(1.0)
    # the clamp holds for the smooth types too (Cycles' MapRangeNode::expand adds it for every
    # type): an empty From range gives 0, clamped to To Min 0.3 (it had stayed 0; Cycles 0.3)
    for kind in ('SMOOTHSTEP', 'SMOOTHERSTEP'):
        assert mr(kind, 0.6, 0.5, 0.5, 0.3, 0.8, 4, True) == pytest.approx(0.3), kind
        assert mr(kind, 0.6, 0.5, 0.5, 0.3, 0.8, 4, False) == 0.0, kind
    assert fn.clamp_range(0.2, 0.85, 0.3) == pytest.approx(0.3)
    assert fn.clamp_min_max(0.2, 0.85, 0.3) == pytest.approx(0.3)
    assert fn.clamp_min_max(0.9, 0.85, 0.3) == pytest.approx(0.3)                 # min > max: max wins
    assert fn.clamp_range(0.9, 0.85, 0.3) == pytest.approx(0.85)


def test_vector_map_range_is_cycles_per_component():
    """The vector Map Range against Cycles 5.0's values (emission read exactly) for the vector
    (0.2, 0.7, 1.6), From (0.1, 0.9, 0) -> (0.5, 0.3, 1), To (0.1, 0.2, 0.3) -> (0.9, 0.6,
    0.8), steps (3, 4, 2): it was not evaluated (the input's own value stood in)."""
    args = ((0.2, 0.7, 1.6), (0.1, 0.9, 0.0), (0.5, 0.3, 1.0), (0.1, 0.2, 0.3), (0.9, 0.6, 0.8), (3, 4, 2))
    for kind, clamp, want in (('LINEAR', True, (0.3, 0.3333, 0.8)), ('LINEAR', False, (0.3, 0.3333, 1.1)),
                              ('STEPPED', True, (0.3667, 0.3, 0.8)), ('STEPPED', False, (0.3667, 0.3, 1.3)),
                              ('SMOOTHSTEP', False, (0.225, 0.3037, 0.8)),
                              ('SMOOTHERSTEP', True, (0.1828, 0.284, 0.8))):
        got = fn.map_range_vector(kind, *[np.array(a, np.float64) for a in args], clamp)
        assert np.allclose(got, want, atol=1e-4), (kind, clamp, got, want)


def test_hsl_against_colorsys_and_separate_combine():
    rng = np.random.default_rng(2)
    rgb = rng.uniform(0, 1, (200, 3))
    rgb[:5] = [(0.5, 0.5, 0.5), (1, 0, 0), (0, 1, 0), (0.2, 0.2, 0.7), (0.9, 0.1, 0.2)]
    hsl = cn.rgb_to_hsl(rgb)
    ref = np.array([colorsys.rgb_to_hls(*c) for c in rgb])[:, [0, 2, 1]]          # colorsys: H, L, S
    assert np.allclose(hsl, ref, atol=1e-9)
    assert np.allclose(cn.hsl_to_rgb(hsl), rgb, atol=1e-9)
    assert np.allclose(cn.separate_color('HSV', rgb), [colorsys.rgb_to_hsv(*c) for c in rgb], atol=1e-9)
    assert np.allclose(cn.combine_color('HSV', cn.separate_color('HSV', rgb)), rgb, atol=1e-9)
    assert np.array_equal(cn.separate_color('RGB', rgb), rgb)


def test_rgb_curves_lookup():
    """Identity curves give the input back; an S curve bends it; beyond the range the table is
    extended linearly (Extrapolated) or held (Extended); the factor mixes with the input."""
    identity = lambda k, x: x          # noqa: E731
    table, lo, hi = cn.curves_table(identity, [[0, 1]] * 4)
    c = np.array([[0.1, 0.5, 0.9], [1.5, -0.25, 0.3]])
    assert (lo, hi) == (0, 1) and len(table) == cn.RAMP_TABLE_SIZE + 1
    assert np.allclose(cn.curves_lookup(table, lo, hi, c, 1.0, True), c)
    assert np.allclose(cn.curves_lookup(table, lo, hi, c, 1.0, False)[1], [1.0, 0.0, 0.3])
    square = lambda k, x: x * x if k == 3 else x   # noqa: E731  (combined curve x^2)
    table, lo, hi = cn.curves_table(square, [[0, 1]] * 4)
    got = cn.curves_lookup(table, lo, hi, c[:1], 1.0, True)
    assert np.allclose(got, c[:1] ** 2, atol=2e-5)            # piecewise linear over 257 entries
    assert np.allclose(cn.curves_lookup(table, lo, hi, c[:1], 0.5, True), 0.5 * (c[:1] + c[:1] ** 2), atol=2e-5)
    table, lo, hi = cn.curves_table(identity, [[0, 1], [0, 1], [-1, 2], [0, 1]])  # range from all curves
    assert (lo, hi) == (-1, 2) and np.allclose(cn.curves_lookup(table, lo, hi, c, 1.0, False), c)


def test_export_bakes_separate_math_combine_per_texel(scene, exported):
    """Image -> Separate HSV -> (hue + 0.5 wrapped, saturation x 0.5) -> Combine HSV, baked per
    texel, equals the same steps written out with colorsys; nothing reported."""
    scenes.camera((0, 0, 5), (0, 0, 0))
    px = np.ones((2, 2, 4), np.float32)
    px[..., :3] = [[(0.9, 0.2, 0.1), (0.1, 0.6, 0.3)], [(0.3, 0.3, 0.8), (0.5, 0.5, 0.5)]]
    mat, nt, out = scenes._material("Channels")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Px", px)
    sep, comb = nt.nodes.new('ShaderNodeSeparateColor'), nt.nodes.new('ShaderNodeCombineColor')
    sep.mode = comb.mode = 'HSV'
    hue, sat = nt.nodes.new('ShaderNodeMath'), nt.nodes.new('ShaderNodeMath')
    hue.operation, sat.operation = 'WRAP', 'MULTIPLY'
    hue.inputs[1].default_value, hue.inputs[2].default_value = 1.0, 0.0
    add = nt.nodes.new('ShaderNodeMath')
    add.inputs[1].default_value = 0.5
    sat.inputs[1].default_value = 0.5
    nt.links.new(tex.outputs['Color'], sep.inputs['Color'])
    nt.links.new(sep.outputs['Red'], add.inputs[0])
    nt.links.new(add.outputs[0], hue.inputs[0])
    nt.links.new(sep.outputs['Green'], sat.inputs[0])
    nt.links.new(hue.outputs[0], comb.inputs['Red'])
    nt.links.new(sat.outputs[0], comb.inputs['Green'])
    nt.links.new(sep.outputs['Blue'], comb.inputs['Blue'])
    nt.links.new(comb.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("P", materials=(mat,)).data.uv_layers.new(name="UVMap")
    data = exported()
    got = data.materials[data.geometry.material[0]]
    assert got.name == "Channels" and not got.approximated
    want = np.empty((2, 2, 3))
    for i in range(2):
        for j in range(2):
            h, s, v = colorsys.rgb_to_hsv(*px[i, j, :3].astype(np.float64))
            want[i, j] = colorsys.hsv_to_rgb((h + 0.5) % 1.0, s * 0.5, v)
    assert np.allclose(got.texture[..., :3] * got.base_color, want, atol=1e-5)


def test_unsupported_math_inputs_are_reported(scene, exported):
    """A Vector Transform is not evaluated: its own value, reported. (A Map Range of vectors and
    a Float Curve, once the examples here, are: test_vector_map_range_and_mix_are_evaluated,
    tests/parity/test_curve_nodes.py.)"""
    scenes.camera((0, 0, 5), (0, 0, 0))
    mat, nt, out = scenes._material("Curved")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    r = nt.nodes.new('ShaderNodeVectorTransform')
    nt.links.new(r.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("P", materials=(mat,))
    data = exported()
    got = data.materials[data.geometry.material[0]]
    assert "colour from 'Vector Transform' node; its own value used" in got.approximated
    assert np.allclose(got.base_color, d.inputs['Color'].default_value[:3])


def test_constant_inputs_evaluate_chains_of_constant_nodes(dacrt_addon):
    """nodeeval.constant: what a Value/RGB -> Math / Mix chain computes for an input, with
    Cycles' conversions (float -> (v, v, v), colour -> luminance); an image or an unsupported
    node anywhere in the chain gives the socket's own value and exact False."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    nt = bpy.data.node_groups.new("Consts", 'ShaderNodeTree')
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Strength'].default_value = 9.0
    e.inputs['Color'].default_value = (0.1, 0.2, 0.3, 1.0)
    assert nodeeval.constant_value(e.inputs['Strength']) == (9.0, True)
    value = nt.nodes.new('ShaderNodeValue')
    value.outputs[0].default_value = 2.0
    power = nt.nodes.new('ShaderNodeMath')
    power.operation = 'POWER'
    power.inputs[1].default_value = 3.0
    nt.links.new(value.outputs[0], power.inputs[0])
    nt.links.new(power.outputs[0], e.inputs['Strength'])
    assert nodeeval.constant_value(e.inputs['Strength']) == (8.0, True)
    nt.links.new(power.outputs[0], e.inputs['Color'])     # a float on a colour: (v, v, v)
    assert nodeeval.constant_color(e.inputs['Color']) == ((8.0, 8.0, 8.0), True)
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    mix.blend_type = 'MULTIPLY'
    mix.inputs['Factor'].default_value = 1.0
    mix.inputs['B'].default_value = (0.5, 0.5, 2.0, 1.0)
    nt.links.new(rgb.outputs[0], mix.inputs['A'])
    nt.links.new(mix.outputs['Result'], e.inputs['Color'])
    color, exact = nodeeval.constant_color(e.inputs['Color'])
    assert exact and np.allclose(color, (0.1, 0.2, 1.2))
    nt.links.new(mix.outputs['Result'], power.inputs[0])  # a colour on a float: its luminance
    strength, exact = nodeeval.constant_value(e.inputs['Strength'])
    assert exact and np.isclose(strength, float(np.asarray(cn.gray(np.array([0.1, 0.2, 1.2]))).reshape(-1)[0]) ** 3)
    noise = nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(noise.outputs['Fac'], mix.inputs['Factor'])
    assert nodeeval.constant_value(e.inputs['Strength']) == (9.0, False)
    img = nt.nodes.new('ShaderNodeTexImage')
    nt.links.new(img.outputs['Color'], mix.inputs['A'])
    nt.links.new(value.outputs[0], mix.inputs['Factor'])
    assert nodeeval.constant_color(e.inputs['Color'])[1] is False


def test_combine_and_separate_xyz_with_cycles_vector_conversions(dacrt_addon):
    """Combine XYZ makes a vector, Separate XYZ takes one apart; a vector into a float input is
    its average (Cycles' svm_node_convert, NODE_CONVERT_VF), a colour its luminance, a float
    into a vector input (v, v, v)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    nt = bpy.data.node_groups.new("Vectors", 'ShaderNodeTree')
    e = nt.nodes.new('ShaderNodeEmission')
    comb = nt.nodes.new('ShaderNodeCombineXYZ')
    comb.inputs['X'].default_value, comb.inputs['Y'].default_value, comb.inputs['Z'].default_value = 0.3, 0.6, 2.1
    nt.links.new(comb.outputs[0], e.inputs['Color'])
    color, exact = nodeeval.constant_color(e.inputs['Color'])
    assert exact and np.allclose(color, (0.3, 0.6, 2.1))
    nt.links.new(comb.outputs[0], e.inputs['Strength'])
    strength, exact = nodeeval.constant_value(e.inputs['Strength'])
    assert exact and np.isclose(strength, 1.0)            # (0.3 + 0.6 + 2.1) / 3, not luminance
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(comb.outputs[0], sep.inputs['Vector'])
    for k, name in enumerate('XYZ'):
        nt.links.new(sep.outputs[name], e.inputs['Strength'])
        strength, exact = nodeeval.constant_value(e.inputs['Strength'])
        assert exact and np.isclose(strength, (0.3, 0.6, 2.1)[k])
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.2, 0.4, 0.8, 1.0)
    nt.links.new(rgb.outputs[0], sep.inputs['Vector'])   # a colour into a vector input: as it is
    nt.links.new(sep.outputs['Z'], e.inputs['Strength'])
    strength, exact = nodeeval.constant_value(e.inputs['Strength'])
    assert exact and np.isclose(strength, 0.8)
    nt.links.new(rgb.outputs[0], e.inputs['Strength'])   # a colour into a float: its luminance
    strength, _ = nodeeval.constant_value(e.inputs['Strength'])
    assert np.isclose(strength, float(np.asarray(cn.gray(np.array([0.2, 0.4, 0.8]))).reshape(-1)[0]))
    assert not np.isclose(strength, (0.2 + 0.4 + 0.8) / 3)
    value = nt.nodes.new('ShaderNodeValue')
    value.outputs[0].default_value = 0.7
    nt.links.new(value.outputs[0], sep.inputs['Vector'])  # a float into a vector: (v, v, v)
    nt.links.new(sep.outputs['Y'], e.inputs['Strength'])
    strength, exact = nodeeval.constant_value(e.inputs['Strength'])
    assert exact and np.isclose(strength, 0.7)
