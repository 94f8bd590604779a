"""Shader node edge cases against Cycles (hunt 60, "shaders"), each rendered by both engines in
the test: a grid seen from straight above by an orthographic camera (a 1-pixel box filter), its
material's colour from the nodes under test, as an emission (the pixels are the nodes' value)
or as a diffuse colour under a sun straight down (direct light only: almost no noise)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 32


def _scene(wire, shader='emission', setup=None):
    """A 2x2 grid (8x8 quads) filling the view, its material's Emission Color (or Diffuse Color
    under a sun, shader='diffuse') fed by wire(tree) -> socket; setup(object) before."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = RES
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=8, y_subdivisions=8, size=2.0)
    ob = bpy.context.object
    mat, nt, out = scenes._material("M")
    if shader == 'emission':
        sh = nt.nodes.new('ShaderNodeEmission')
        target = sh.inputs['Color']
    else:
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        target = sh.inputs['Color']
        scenes.light('SUN', 3.0, angle=0.0)
    nt.links.new(sh.outputs[0], out.inputs['Surface'])
    nt.links.new(wire(nt), target)
    ob.data.materials.append(mat)
    if setup is not None:
        setup(ob)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    return sc


def _both(sc, tmp_path):
    """{engine: RGB (RES, RES, 3)}."""
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        got[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
    return got['CYCLES'], got['DACRT']


def _alternating(name, values, kind='FLOAT', domain='POINT'):
    """setup(object): a point attribute `name` cycling through values."""
    def setup(ob):
        me = ob.data
        a = me.attributes.new(name, kind, domain)
        n = len(a.data)
        v = np.asarray(values, np.float32)[np.arange(n) % len(values)]
        if kind == 'FLOAT':
            a.data.foreach_set('value', v.ravel())
        else:
            a.data.foreach_set('color', v.ravel())
    return setup


def _attribute(name, output):
    def wire(nt):
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = name
        return a.outputs[output]
    return wire


@pytest.mark.parametrize('case', ['fac', 'color'])
def test_negative_attribute_values_clamped_after_interpolation(case, tmp_path):
    """A point attribute with negative values (a float -1 / 1.5; a colour with negative
    channels) into a Diffuse Color: Cycles interpolates the attribute and clamps the closure
    weight per point, so a -1 corner darkens its triangles. It had been clamped per corner
    first: 1.67x (float) and 1.16x (colour) Cycles' mean; now within 1%."""
    if case == 'fac':
        setup = _alternating('f', [-1.0, 1.5])
    else:
        setup = _alternating('f', [(-0.5, 0.3, 1.8, 1.0), (1.2, 0.2, -0.4, 1.0)], 'FLOAT_COLOR')
    sc = _scene(_attribute('f', 'Fac' if case == 'fac' else 'Color'), 'diffuse', setup)
    c, d = _both(sc, tmp_path)
    mc, md = c.mean(axis=(0, 1)), d.mean(axis=(0, 1))
    assert mc.mean() > 0.05
    assert np.abs(md - mc).max() < 0.01 * mc.max(), (mc, md)

