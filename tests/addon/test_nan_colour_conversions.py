"""A NaN into colour conversions and rotations, as Cycles 5.0.1 renders it (measured on an
emitting plane, each case constant, so Blender folds it, and linked, so Cycles' kernel computes
it; the expected values are those measurements):
- Separate Color HSV / HSL takes max(r, max(g, b)) with max(a, b) = (a > b) ? a : b (min alike;
  HSV's max is fmaxf), passing a NaN red or green over: (NaN, 0.3, 0.2) is S 0.333, V 0.3 (HSL
  S 0.2, L 0.25), (0.5, 0.3, NaN) V 0.5, where DACRT had rendered each black (numpy's max passes
  the NaN on); a Hue/Saturation/Value node of (0.5, 0.3, NaN) is (0.5, 0.5, 0) likewise;
- a Mix Dodge or Burn of a NaN channel is NaN there (black), where A's had been kept; a folded
  Hue, Saturation, Value or Color blend of a NaN is black (Blender's own rgb_to_hsv);
- Combine Color HSL clamps a NaN hue to 0 (Cycles' clamp): a grey of the lightness, 0.25, black before;
- a Color Ramp's NaN Factor is its last stop folded, its first in the kernel (red, DACRT blue);
- a Vector Rotate of a constant NaN axis keeps the vector (Blender's axis_angle_to_mat3: an axis
  that does not normalise is no rotation), black where the kernel computes it (DACRT black both);
- a Float / RGB / Vector Curve(s) of a constant NaN reads its table's first entry (Blender's
  curvemap_evaluateF), unmixed at Factor 1 (DACRT black: the kernel's NaN)."""
import numpy as np
import pytest

from addon import colornodes as cn

from . import scenes

NAN = float('nan')


@pytest.mark.parametrize("rgb, hsv, hsl", [
    ((NAN, 0.3, 0.2), (NAN, 1 / 3, 0.3), (NAN, 0.2, 0.25)),
    ((0.5, NAN, 0.2), (NAN, 0.6, 0.5), (NAN, 0.3 / 0.7, 0.35)),
    # a NaN blue: passed over by HSV's fmaxf (V 0.5), taken by the ternary min (S, H NaN) and HSL's max
    ((0.5, 0.3, NAN), (NAN, NAN, 0.5), (NAN, NAN, NAN)),
    ((0.5, 0.3, 0.2), (1 / 18, 0.6, 0.5), (1 / 18, 3 / 7, 0.35)),    # (finite: unchanged)
])
def test_separate_hsv_and_hsl_take_cycles_max_and_min(rgb, hsv, hsl):
    c = np.array(rgb, np.float32)
    np.testing.assert_allclose(cn.rgb_to_hsv(c), hsv, rtol=1e-5)
    np.testing.assert_allclose(cn.rgb_to_hsl(c), hsl, rtol=1e-5)


def test_combine_hsl_of_a_nan_hue_is_the_grey_of_its_lightness():
    np.testing.assert_allclose(cn.hsl_to_rgb(np.array([NAN, 0.5, 0.5], np.float32)), [0.25, 0.25, 0.25])
    np.testing.assert_allclose(cn.hsl_to_rgb(np.array([0.0, 1.0, 0.5], np.float32)), [1.0, 0.0, 0.0])


def _socket(sockets, key):
    """The enabled socket of that identifier or name (a Mix node has an 'A' per data type)."""
    return next(s for s in sockets if key in (s.identifier, s.name) and s.enabled)


def _emit(scene, node_type, settings, nan_input, value, output, linked, props=None, setup=None):
    """The centre pixel of a plane emitting a new node's `output` (black world), its input
    `nan_input` set to value, or fed it through a kernel addition of a linked 0 (Object Z on the
    plane z = 0), so Blender cannot fold the node; setup(node) completes the node."""
    mat, nt, _, out = scenes.small_view(scene, eye=(0, 0, 5), background=None)
    em, n = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new(node_type)
    for k, v in (props or {}).items():
        setattr(n, k, v)
    if node_type == 'ShaderNodeValToRGB':
        n.color_ramp.elements[0].color, n.color_ramp.elements[1].color = (1, 0, 0, 1), (0, 0, 1, 1)
    if setup is not None:
        setup(n)
    for name, v in settings.items():
        _socket(n.inputs, name).default_value = v
    target = _socket(n.inputs, nan_input)
    if linked:
        tc, sep = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(tc.outputs['Object'], sep.inputs[0])
        if isinstance(value, tuple):
            comb, add = nt.nodes.new('ShaderNodeCombineXYZ'), nt.nodes.new('ShaderNodeVectorMath')
            for i in range(3):
                nt.links.new(sep.outputs['Z'], comb.inputs[i])
            add.operation = 'ADD'
            add.inputs[1].default_value = value[:3]
            nt.links.new(comb.outputs[0], add.inputs[0])
        else:
            add = nt.nodes.new('ShaderNodeMath')
            add.operation = 'ADD'
            nt.links.new(sep.outputs['Z'], add.inputs[0])
            add.inputs[1].default_value = value
        nt.links.new(add.outputs[0], target)
    else:
        target.default_value = value[:len(target.default_value)] if isinstance(value, tuple) else value
    nt.links.new(_socket(n.outputs, output), em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))
    return scenes.render_rgba(scene)[1, 2, :3]


_SEP, _COMB = 'ShaderNodeSeparateColor', 'ShaderNodeCombineColor'


@pytest.mark.parametrize("linked", [False, True], ids=['folded', 'kernel'])
@pytest.mark.parametrize("node_type, props, settings, nan_input, value, output, want", [
    (_SEP, {'mode': 'HSV'}, {}, 'Color', (NAN, 0.3, 0.2, 1.0), 'Green', 1 / 3),
    (_SEP, {'mode': 'HSV'}, {}, 'Color', (0.5, NAN, 0.2, 1.0), 'Blue', 0.5),
    (_SEP, {'mode': 'HSV'}, {}, 'Color', (0.2, 0.3, NAN, 1.0), 'Blue', 0.3),
    (_SEP, {'mode': 'HSL'}, {}, 'Color', (0.5, NAN, 0.2, 1.0), 'Green', 0.3 / 0.7),
    (_SEP, {'mode': 'HSL'}, {}, 'Color', (NAN, 0.3, 0.2, 1.0), 'Blue', 0.25),
    (_COMB, {'mode': 'HSL'}, {'Green': 0.5, 'Blue': 0.5}, 'Red', NAN, 'Color', 0.25),
], ids=['hsv-s', 'hsv-v', 'hsv-v-nan-blue', 'hsl-s', 'hsl-l', 'combine-hsl'])
def test_nan_colour_conversions_render_as_cycles(scene, node_type, props, settings, nan_input, value, output,
                                                 want, linked):
    px = _emit(scene, node_type, settings, nan_input, value, output, linked, props)
    np.testing.assert_allclose(px, [want] * 3, rtol=1e-4)


@pytest.mark.parametrize("linked", [False, True], ids=['folded', 'kernel'])
@pytest.mark.parametrize("blend, want", [('DODGE', (0.0, 0.3529, 0.2857)), ('BURN', (0.0, 0.0, 0.0))])
def test_dodge_and_burn_of_a_nan_are_nan_in_that_channel(scene, blend, want, linked):
    """A Mix of A (0.5, 0.3, 0.2) and B (NaN, 0.3, 0.6): Cycles 5.0.1's red 0 (NaN), DACRT had kept A's 0.5."""
    px = _emit(scene, 'ShaderNodeMix', {'A_Color': (0.5, 0.3, 0.2, 1.0)}, 'B_Color', (NAN, 0.3, 0.6, 1.0), 'Result',
               linked, {'data_type': 'RGBA', 'blend_type': blend})
    np.testing.assert_allclose(px, want, atol=1e-4)


@pytest.mark.parametrize("linked", [False, True], ids=['folded', 'kernel'])
def test_hue_saturation_of_a_nan_blue_keeps_the_value(scene, linked):
    px = _emit(scene, 'ShaderNodeHueSaturation', {'Hue': 0.6}, 'Color', (0.5, 0.3, NAN, 1.0), 'Color', linked)
    np.testing.assert_allclose(px, (0.5, 0.5, 0.0), atol=1e-6)


@pytest.mark.parametrize("linked, want", [(False, (0, 0, 1)), (True, (1, 0, 0))], ids=['folded', 'kernel'])
def test_nan_color_ramp_factor_is_the_last_stop_folded_and_the_first_in_the_kernel(scene, linked, want):
    np.testing.assert_allclose(_emit(scene, 'ShaderNodeValToRGB', {}, 'Fac', NAN, 'Color', linked), want, atol=1e-6)


@pytest.mark.parametrize("linked, want", [(False, (0.5, 0.3, 0.2)), (True, (0, 0, 0))], ids=['folded', 'kernel'])
def test_vector_rotate_of_a_nan_axis_keeps_the_vector_only_when_folded(scene, linked, want):
    px = _emit(scene, 'ShaderNodeVectorRotate', {'Vector': (0.5, 0.3, 0.2), 'Angle': 0.5}, 'Axis', (NAN, NAN, NAN),
               'Vector', linked, {'rotation_type': 'AXIS_ANGLE'})
    np.testing.assert_allclose(px, want, atol=1e-6)


def _curve_first_at(node, y):
    for c in node.mapping.curves:
        c.points[0].location = (c.points[0].location[0], y)
    node.mapping.update()


@pytest.mark.parametrize("linked", [False, True], ids=['folded', 'kernel'])
@pytest.mark.parametrize("node_type, settings, nan_input, value, output, folded_want", [
    ('ShaderNodeFloatCurve', {}, 'Value', NAN, 'Value', (0.3, 0.3, 0.3)),
    ('ShaderNodeRGBCurve', {}, 'Color', (NAN, 0.5, 0.5, 1.0), 'Color', (0.51, 0.755, 0.755)),
    ('ShaderNodeVectorCurve', {}, 'Vector', (NAN, 0.5, 0.5), 'Vector', (0.3, 0.825, 0.825)),
    # (a Factor of 0.5 mixes the NaN in, folded too: Cycles 0 / 0.6275 / 0.6275)
    ('ShaderNodeRGBCurve', {'Fac': 0.5}, 'Color', (NAN, 0.5, 0.5, 1.0), 'Color', (0.0, 0.6275, 0.6275)),
], ids=['float', 'rgb', 'vector', 'rgb-half'])
def test_a_curve_of_a_nan_reads_its_first_entry_where_blender_folds_it(scene, node_type, settings, nan_input, value,
                                                                       output, folded_want, linked):
    """Each curve's first point at y 0.3 (Cycles 5.0.1, measured: the folded values; linked, the
    kernel's NaN, black in that channel)."""
    px = _emit(scene, node_type, settings, nan_input, value, output, linked,
               setup=lambda n: _curve_first_at(n, 0.3))
    want = np.array(folded_want)
    if linked:
        want = want * np.isfinite(np.array(value[:3] if isinstance(value, tuple) else (value,) * 3))
    np.testing.assert_allclose(px, want, atol=2e-3)


@pytest.mark.parametrize("linked", [False, True], ids=['folded', 'kernel'])
@pytest.mark.parametrize("blend, a, b, kernel_want", [
    ('HUE', (0.5, 0.3, 0.2, 1.0), (NAN, 0.3, 0.6, 1.0), (0.5, 0.25, 0.0)),
    ('SATURATION', (0.5, 0.3, 0.2, 1.0), (0.2, 0.3, NAN, 1.0), (0.5, 0.0, 0.0)),
    ('VALUE', (NAN, 0.3, 0.6, 1.0), (0.5, 0.3, 0.2, 1.0), (0.55, 0.275, 0.0)),
    ('COLOR', (0.5, 0.3, 0.2, 1.0), (NAN, 0.3, 0.6, 1.0), (0.5, 0.275, 0.0)),
])
def test_hsv_blends_of_a_nan_are_black_where_blender_folds_them(scene, blend, a, b, kernel_want, linked):
    """Blender folds a Mix of constants with its own rgb_to_hsv / hsv_to_rgb (BLI), which give NaN
    here: Cycles 5.0.1 black folded, the kernel's values linked (DACRT had given those folded too)."""
    nan_input, value, fixed = ('A_Color', a, {'B_Color': b}) if blend == 'VALUE' else ('B_Color', b, {'A_Color': a})
    px = _emit(scene, 'ShaderNodeMix', fixed, nan_input, value, 'Result', linked,
               {'data_type': 'RGBA', 'blend_type': blend})
    np.testing.assert_allclose(px, kernel_want if linked else (0.0, 0.0, 0.0), atol=1e-4)
