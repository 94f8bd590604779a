"""The Vector Math node agrees with Cycles in every operation: one emissive square per operation
(constant inputs, chosen to reach each operation's special cases: a zero divisor, a negative base
of a fractional power, a refraction past total internal reflection is not among them), seen by an
orthographic camera with a 1-pixel box filter, so each square's pixels are its emission exactly.
The node had not been evaluated at all (its input's own value stood in, reported)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

OPERATIONS = ['ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'CROSS_PRODUCT', 'PROJECT', 'REFLECT',
              'REFRACT', 'FACEFORWARD', 'DOT_PRODUCT', 'DISTANCE', 'LENGTH', 'SCALE', 'NORMALIZE', 'ABSOLUTE',
              'POWER', 'SIGN', 'MINIMUM', 'MAXIMUM', 'FLOOR', 'CEIL', 'FRACTION', 'MODULO', 'WRAP', 'SNAP',
              'SINE', 'COSINE', 'TANGENT']
A, B, C, SCALE = (-1.3, 0.7, 2.2), (0.4, -2.5, 0.0), (1.5, 0.25, -0.75), 0.6


def _square(op, i, n):
    mat = bpy.data.materials.new(op)
    nt = mat.node_tree
    for node in list(nt.nodes):
        if node.type != 'OUTPUT_MATERIAL':
            nt.nodes.remove(node)
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(em.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    vm = nt.nodes.new('ShaderNodeVectorMath')
    vm.operation = op
    for k, value in enumerate((A, B, C)):
        vm.inputs[k].default_value = value
    vm.inputs[3].default_value = SCALE
    # x 0.1 + 0.5 (itself a Vector Math node): most results become positive emission
    post = nt.nodes.new('ShaderNodeVectorMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = (0.1, 0.1, 0.1), (0.5, 0.5, 0.5)
    out = 'Value' if op in ('DOT_PRODUCT', 'DISTANCE', 'LENGTH') else 'Vector'
    nt.links.new(vm.outputs[out], post.inputs[0])
    nt.links.new(post.outputs['Vector'], em.inputs['Color'])
    scenes.plane(op, size=2, location=(-n + 1 + 2 * i, 0, 0), materials=(mat,))


def test_vector_math_operations_match_cycles():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    n = len(OPERATIONS)
    sc.render.resolution_x, sc.render.resolution_y = 2 * n, 4
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0 * n)
    scenes.black_world()
    for i, op in enumerate(OPERATIONS):
        _square(op, i, n)
    rendering.fair_scene_settings(sc)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device = 4, False, 'CPU'
        sc.dacrt.samples = 4
        sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
        sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
        img = scenes.render_rgba(sc)
        got[engine] = np.array([img[1:3, 2 * i:2 * i + 2, :3].reshape(-1, 3).mean(axis=0) for i in range(n)])
    for i, op in enumerate(OPERATIONS):
        assert np.allclose(got['DACRT'][i], got['CYCLES'][i], atol=1e-3), (op, got['DACRT'][i], got['CYCLES'][i])
    # (MODULO by a 0 component is NaN in Cycles, unlike Math's: that channel renders black)
    assert got['CYCLES'][OPERATIONS.index('MODULO')][2] == 0.0
