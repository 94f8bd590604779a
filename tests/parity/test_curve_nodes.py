"""Float Curve and Vector Curves agree with Cycles, on constants and per shading point: emissive
strips seen by an orthographic camera with a 1-pixel box filter, so each pixel is its emission
(per point: the mean over the pixel of a smooth function of Generated coordinates, whose
sub-pixel spread is well under the tolerance at 16 spp). Cycles bakes each curve into a table of
257 entries over the range of its points' x, linearly extrapolated beyond it when the mapping is
Extrapolated (svm_node_curve, svm_node_curves). Both nodes had not been evaluated: their input's
own value stood in, reported (a per-point Strength through a Float Curve: Cycles 0.892, DACRT 1.0).
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

W = 64          # pixels across a strip (more than the strips' rows: ortho_scale spans the width)


def _material(name):
    """A material of an Emission alone: (material, node tree, the Emission node)."""
    mat, nt, out = scenes._material(name)
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat, nt, em


def _float_curve(nt, extend='EXTRAPOLATED', factor=1.0):
    c = nt.nodes.new('ShaderNodeFloatCurve')
    m = c.mapping
    curve = m.curves[0]
    curve.points[0].location = (0.1, 0.15)
    curve.points[1].location = (0.9, 0.35)
    curve.points.new(0.45, 0.9)
    m.extend = extend
    m.update()
    c.inputs['Factor'].default_value = factor
    return c


def _vector_curves(nt, extend='EXTRAPOLATED', factor=1.0):
    c = nt.nodes.new('ShaderNodeVectorCurve')
    m = c.mapping
    m.curves[0].points.new(0.0, 0.6)                 # X: a bump
    m.curves[1].points[0].location = (-0.5, 0.2)     # Y: a narrower range, lifted
    m.curves[1].points.new(0.3, -0.4)
    m.curves[2].points[1].location = (0.6, 0.9)      # Z: ends at 0.6
    m.extend = extend
    m.update()
    c.inputs['Fac'].default_value = factor
    return c


def _post(nt, socket, scale=0.5, offset=0.5):
    """x scale + offset (a Vector Math node): curve outputs, extrapolated ones too, become
    positive emission (DACRT clamps a negative one to 0, reported; Cycles emits it)."""
    post = nt.nodes.new('ShaderNodeVectorMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = (scale,) * 3, (offset,) * 3
    nt.links.new(socket, post.inputs[0])
    return post.outputs['Vector']


def _coordinate(nt, lo, hi):
    """Generated X mapped to [lo, hi] across the strip (a Vector Math node)."""
    tc = nt.nodes.new('ShaderNodeTexCoord')
    vm = nt.nodes.new('ShaderNodeVectorMath')
    vm.operation = 'MULTIPLY_ADD'
    vm.inputs[1].default_value = (hi - lo, hi - lo, hi - lo)
    vm.inputs[2].default_value = (lo, lo, lo)
    nt.links.new(tc.outputs['Generated'], vm.inputs[0])
    return vm.outputs['Vector']


def float_strength(name, extend, factor, per_point, value=0.0):
    """A Float Curve driving the Emission Strength of white (through x 0.1 + 0.7, a Math node):
    per point on Generated X from -0.3 to 1.3 (both sides extrapolated or clamped), else at
    `value`."""
    mat, nt, em = _material(name)
    em.inputs['Color'].default_value = (1, 1, 1, 1)
    c = _float_curve(nt, extend, factor)
    if per_point:
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(_coordinate(nt, -0.3, 1.3), sep.inputs[0])
        nt.links.new(sep.outputs['X'], c.inputs['Value'])
    else:
        c.inputs['Value'].default_value = value
    post = nt.nodes.new('ShaderNodeMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = 0.1, 0.7
    nt.links.new(c.outputs['Value'], post.inputs[0])
    nt.links.new(post.outputs[0], em.inputs['Strength'])
    return mat


def vector_color(name, extend, factor, per_point, value=(0.0, 0.0, 0.0)):
    """Vector Curves driving the Emission Color (through x 0.25 + 0.6): per point on Generated
    from -1.4 to 1.4 in every component, else at `value`."""
    mat, nt, em = _material(name)
    c = _vector_curves(nt, extend, factor)
    if per_point:         # (x, -x, x): each curve across its whole range
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(_coordinate(nt, -1.4, 1.4), sep.inputs[0])
        neg = nt.nodes.new('ShaderNodeMath')
        neg.operation = 'MULTIPLY'
        neg.inputs[1].default_value = -1.0
        nt.links.new(sep.outputs['X'], neg.inputs[0])
        comb = nt.nodes.new('ShaderNodeCombineXYZ')
        nt.links.new(sep.outputs['X'], comb.inputs['X'])
        nt.links.new(neg.outputs[0], comb.inputs['Y'])
        nt.links.new(sep.outputs['X'], comb.inputs['Z'])
        nt.links.new(comb.outputs[0], c.inputs['Vector'])
    else:
        c.inputs['Vector'].default_value = value
    nt.links.new(_post(nt, c.outputs['Vector'], 0.25, 0.6), em.inputs['Color'])
    return mat


def float_beside_procedural(name):
    """A Float Curve of constant inputs beyond its range (Extended: its end point's y, 0.15, as
    Cycles folds it; its table's end is 0.1723) added to a Gradient's Fac x 0.5 per point."""
    mat, nt, em = _material(name)
    em.inputs['Color'].default_value = (1, 1, 1, 1)
    c = _float_curve(nt, 'HORIZONTAL')
    c.inputs['Value'].default_value = -0.2
    g = nt.nodes.new('ShaderNodeTexGradient')
    half = nt.nodes.new('ShaderNodeMath')
    half.operation = 'MULTIPLY_ADD'
    half.inputs[1].default_value = 0.5
    nt.links.new(g.outputs['Fac'], half.inputs[0])
    nt.links.new(c.outputs['Value'], half.inputs[2])
    nt.links.new(half.outputs[0], em.inputs['Strength'])
    return mat


CASES = [
    ('float_const_beside_pp', float_beside_procedural),
    ('float_pp', lambda n: float_strength(n, 'EXTRAPOLATED', 1.0, True)),
    ('float_pp_clamped_fac', lambda n: float_strength(n, 'HORIZONTAL', 0.7, True)),
    ('float_in', lambda n: float_strength(n, 'EXTRAPOLATED', 1.0, False, 0.3)),
    # (Cycles' constant folding reads a Float Curve beyond its range as 0 when Extrapolated, else
    # as the end point's y (0.35 here, where the table ends at 0.3531))
    ('float_below', lambda n: float_strength(n, 'EXTRAPOLATED', 1.0, False, -0.2)),
    ('float_above_fac', lambda n: float_strength(n, 'EXTRAPOLATED', 0.5, False, 1.2)),
    ('float_above_clamped', lambda n: float_strength(n, 'HORIZONTAL', 1.0, False, 1.4)),
    ('float_fac', lambda n: float_strength(n, 'EXTRAPOLATED', 0.4, False, 0.7)),
    ('vector_pp', lambda n: vector_color(n, 'EXTRAPOLATED', 1.0, True)),
    ('vector_pp_clamped_fac', lambda n: vector_color(n, 'HORIZONTAL', 0.6, True)),
    ('vector_in', lambda n: vector_color(n, 'EXTRAPOLATED', 1.0, False, (0.2, -0.1, 0.4))),
    ('vector_out', lambda n: vector_color(n, 'EXTRAPOLATED', 1.0, False, (-1.1, 0.8, 0.9))),
    ('vector_out_clamped', lambda n: vector_color(n, 'HORIZONTAL', 0.8, False, (-1.1, 0.8, 0.9))),
]


def _render(cases, spp=16):
    """{engine: (len(cases), W, 3) per-column means of each case's strip}."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    n = len(cases)
    sc.render.resolution_x, sc.render.resolution_y = W, 4 * n
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0)     # 2 units across W pixels
    scenes.black_world()
    for i, (name, make) in enumerate(cases):
        # strip i: 2 units wide, 8 / W units tall (4 pixels), top to bottom
        y = 1.0 * 4 * n / W - (4 * i + 2) * 2.0 / W
        mat = make(name)
        ob = scenes.plane(name, size=2, location=(0, y, 0), materials=(mat,))
        ob.scale = (1.0, 4.0 / W, 1.0)
    rendering.fair_scene_settings(sc)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device = spp, False, 'CPU'
        sc.dacrt.samples = spp
        sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
        sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
        img = scenes.render_rgba(sc)[::-1]         # (row 0 at the top)
        got[engine] = np.array([img[4 * i + 1:4 * i + 3, :, :3].mean(axis=0) for i in range(n)])
    return got


def test_curve_nodes_match_cycles(said):
    got = _render(CASES)
    for i, (name, _) in enumerate(CASES):
        d, c = got['DACRT'][i], got['CYCLES'][i]
        per_point = '_pp' in name
        # per point: the strip's columns, each the mean of 2 rows of a sub-pixel sampled slope
        tol = 0.03 if per_point else 2e-4
        assert np.abs(d - c).max() < tol, (name, np.abs(d - c).max(), d.mean(axis=0), c.mean(axis=0))
        assert abs(d.mean() - c.mean()) < (5e-3 if per_point else 1e-4), (name, d.mean(axis=0), c.mean(axis=0))
    assert not [s for s in said if 'Curve' in s], said


def float_from_rgb(name, extend, factor, value, through_rgb=True):
    """float_strength at `value`, the Float Curve's Value linked from a Math node (x 1) of an
    RGB node's grey (through_rgb: Blender does not fold an RGB node, so Cycles' kernel runs the
    curve, extrapolating) or of its own value (Blender folds the chain: the 0 beyond the range)."""
    mat = float_strength(name, extend, factor, False, value)
    nt = mat.node_tree
    c = next(n for n in nt.nodes if n.type == 'CURVE_FLOAT')
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY'
    m.inputs[0].default_value, m.inputs[1].default_value = value / 0.5, 0.5
    if through_rgb:
        rgb = nt.nodes.new('ShaderNodeRGB')
        rgb.outputs[0].default_value = (0.5, 0.5, 0.5, 1.0)
        nt.links.new(rgb.outputs[0], m.inputs[1])
    nt.links.new(m.outputs[0], c.inputs['Value'])
    return mat


UNFOLDED = [
    ('rgb_below', lambda n: float_from_rgb(n, 'EXTRAPOLATED', 1.0, -0.7)),
    ('rgb_above_fac', lambda n: float_from_rgb(n, 'EXTRAPOLATED', 0.6, 1.6)),
    ('rgb_below_clamped', lambda n: float_from_rgb(n, 'HORIZONTAL', 1.0, -0.7)),
    ('math_below', lambda n: float_from_rgb(n, 'EXTRAPOLATED', 1.0, -0.7, through_rgb=False)),
    ('math_above_fac', lambda n: float_from_rgb(n, 'EXTRAPOLATED', 0.6, 1.6, through_rgb=False)),
]


def test_float_curve_of_constants_blender_does_not_fold_matches_cycles(said):
    """A Float Curve of constants that Blender does not fold (an RGB node's grey on the way)
    runs in Cycles' kernel, extrapolated beyond its range; the same chain without the RGB node
    is folded, beyond its range 0 (Extrapolated). The fold's rule had been applied to every
    chain of constants (below the range a Strength of 0.7 where Cycles gives -1.076; a fuzzed
    Mix Shader factor through such a curve 44% off in blue)."""
    got = _render(UNFOLDED)
    for i, (name, _) in enumerate(UNFOLDED):
        d, c = got['DACRT'][i], got['CYCLES'][i]
        assert np.abs(d - c).max() < 2e-4, (name, d.mean(axis=0), c.mean(axis=0))
    assert not [s for s in said if 'Curve' in s], said
