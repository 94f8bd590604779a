"""Colour and float nodes compute in float32, as Cycles' SVM does: a value exactly on a step's
edge lands on Cycles' side. Each square is a plane under a uniform white world, no bounces, so
its pixels are the Diffuse colour the chain computes; both engines render it and the test
compares them (medians), and the closed forms. They had computed in float64: Value 0.7 x 10 -> Floor ->
/ 10 gave 0.6 (0.699999988 x 10 = 6.99999988 in float64, 7 in float32; Cycles 0.7), a Stepped
Map Range of 0 gave 1.5 (Cycles 1.3), a Snap of 0.7 by 0.1 gave 0.6 (Cycles 0.7)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _math(nt, op, a, b=None):
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = op
    nt.links.new(a, m.inputs[0])
    if b is not None:
        m.inputs[1].default_value = b
    return m.outputs[0]


def _value(nt, v):
    n = nt.nodes.new('ShaderNodeValue')
    n.outputs[0].default_value = v
    return n.outputs[0]


def _posterize(nt, src):
    return _math(nt, 'DIVIDE', _math(nt, 'FLOOR', _math(nt, 'MULTIPLY', src, 10.0)), 10.0)


def _stepped(nt, src):
    mr = nt.nodes.new('ShaderNodeMapRange')
    mr.interpolation_type, mr.clamp = 'STEPPED', False
    for k, v in zip(range(1, 6), (0.2, 0.7, 0.9, 0.1, 4.0)):
        mr.inputs[k].default_value = v
    nt.links.new(src, mr.inputs[0])
    return mr.outputs[0]


def _vector_floor(nt, src):
    """Combine XYZ (v, v, v) x 10 -> Vector Math Floor -> x 0.1 (Vector Math) as a colour."""
    c = nt.nodes.new('ShaderNodeCombineXYZ')
    for k in range(3):
        nt.links.new(src, c.inputs[k])
    out = c.outputs[0]
    for op, b in (('MULTIPLY', 10.0), ('FLOOR', None), ('DIVIDE', 10.0)):
        vm = nt.nodes.new('ShaderNodeVectorMath')
        vm.operation = op
        if b is not None:
            vm.inputs[1].default_value = (b, b, b)
        nt.links.new(out, vm.inputs[0])
        out = vm.outputs[0]
    return out


def _checker_fac(nt, scale=2.0):
    ch = nt.nodes.new('ShaderNodeTexChecker')
    ch.inputs['Scale'].default_value = scale
    return ch.outputs['Fac']


# name -> (the chain, Cycles' value as float32 computes it); the procedural ones: a Checker's
# Fac x 0.7 gives 0.7 on its white squares, 0 on the others
CHAINS = {
    'floor': (lambda nt: _posterize(nt, _value(nt, 0.7)), 0.7),
    'stepped map range': (lambda nt: _stepped(nt, _value(nt, 0.0)), 1.3),
    'snap': (lambda nt: _math(nt, 'SNAP', _value(nt, 0.7), 0.1), 0.7),
    'vector floor': (lambda nt: _vector_floor(nt, _value(nt, 0.7)), 0.7),
    'procedural floor': (lambda nt: _posterize(nt, _math(nt, 'MULTIPLY', _checker_fac(nt), 0.7)), None),
}


def _square(name, chain, i, n):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    for node in list(nt.nodes):
        if node.type != 'OUTPUT_MATERIAL':
            nt.nodes.remove(node)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    nt.links.new(chain(nt), d.inputs['Color'])
    scenes.plane(name, size=2, location=(-n + 1 + 2 * i, 0, 0), materials=(mat,))


def test_step_edges_land_where_cycles_puts_them():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    n = len(CHAINS)
    sc.render.resolution_x, sc.render.resolution_y = 8 * n, 8
    sc.view_settings.view_transform = 'Standard'
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0 * n)
    scenes.world((1, 1, 1))
    for i, (name, (chain, _)) in enumerate(CHAINS.items()):
        _square(name, chain, i, n)
    rendering.fair_scene_settings(sc)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device = 8, False, 'CPU'
        sc.cycles.use_adaptive_sampling = False
        sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
        sc.dacrt.samples = 8
        sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
        sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
        got[engine] = scenes.render_rgba(sc)[..., :3]
    for i, (name, (_, value)) in enumerate(CHAINS.items()):
        c, d = (got[e][2:6, 8 * i + 2:8 * i + 6] for e in ('CYCLES', 'DACRT'))     # (inside)
        # (medians: a few of Cycles' samples of the white world come back black, 0.6125 = 7/8 x 0.7)
        if value is not None:
            assert abs(np.median(c) - value) < 1e-3, (name, np.median(c))      # (Cycles: the closed form)
            assert abs(np.median(d) - value) < 1e-3, (name, np.median(d), np.median(c))
        else:       # the Checker's squares (2 x 2 pixels each): 0.7 or 0, where Cycles has them
            white = c[..., 0] > 0.3
            assert 0 < white.sum() < white.size and np.all((d[..., 0] > 0.3) == white)
            assert abs(np.median(c[white]) - 0.7) < 1e-3 and abs(np.median(d[white]) - 0.7) < 1e-3, \
                (np.median(d[white]), np.median(c[white]))
