"""Cycles' standard attributes of curves and points read by an Attribute node on strands
(export/strands.py StandardAttributes): 'curve_intercept' (a key's length along its curve's key
chords over the curve's), 'curve_length' and 'curve_random' (hash_uint2_to_float of the curve's
index) on Curves objects and hair particles, 'point_random' on point clouds, against Cycles.

They had read 0 with the message "no attribute 'curve_intercept' on the mesh: it reads colour 0
and alpha 1, as in Cycles", where Cycles renders the root-to-tip gradient: strands of emission
'curve_intercept' had rendered black, 0.000 where Cycles' mean is 0.233.
"""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    sc.render.film_transparent = True
    scenes.camera(location=(0, -4, 0.6), rotation=(math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=2.0)
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    sc.cycles_curves.shape = 'THICK'
    return sc


def _reading(name, scale=1.0):
    """An emission material whose colour is the Attribute node `name`'s Color times scale."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out, em = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeEmission')
    attr = nt.nodes.new('ShaderNodeAttribute')
    attr.attribute_name = name
    mul = nt.nodes.new('ShaderNodeVectorMath')
    mul.operation = 'SCALE'
    mul.inputs['Scale'].default_value = scale
    nt.links.new(attr.outputs['Color'], mul.inputs[0])
    nt.links.new(mul.outputs[0], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _curves(material):
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 6)
    curves = []
    for _ in range(30):      # upright wavy strands, of different heights (so their lengths differ)
        x0, y0, ph, h = rng.uniform(-0.8, 0.8), rng.uniform(-0.3, 0.3), rng.uniform(0, 6.28), rng.uniform(0.6, 1.2)
        curves.append(np.stack([x0 + 0.15 * np.sin(4 * t + ph), y0 + 0.1 * np.cos(3 * t + ph), h * t], 1))
    scenes.hair_curves("Strands", curves, radius=0.03, material=material)


def _particles(material):
    em = scenes.plane("Emitter", size=1.5, location=(0, 0, 0.05), materials=[material])
    em.show_instancer_for_render = False
    em.modifiers.new("Hair", 'PARTICLE_SYSTEM')
    s = em.particle_systems[0].settings
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 100, 0.8, 0.04
    s.brownian_factor = 0.1      # wavy, so the chords' lengths matter


def _points(material):
    rng = np.random.default_rng(1)
    pts = rng.uniform(-0.8, 0.8, (40, 3)) * (1, 0.2, 0.5) + (0, 0, 0.6)
    scenes.point_cloud("Dots", pts, radius=0.08, material=material)


CASES = {
    'curves_intercept': (_curves, 'curve_intercept', 1.0),
    'curves_length': (_curves, 'curve_length', 0.5),
    'curves_random': (_curves, 'curve_random', 1.0),
    'particles_intercept': (_particles, 'curve_intercept', 1.0),
    'points_random': (_points, 'point_random', 1.0),
}


@pytest.mark.parametrize('case', list(CASES))
def test_strand_standard_attribute_reads_as_in_cycles(case, tmp_path, said):
    build, name, scale = CASES[case]
    sc = _scene()
    build(_reading(name, scale))
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c[..., :3].mean() > 0.02, "Cycles must read the attribute"
    # thirds of the frame from bottom to top (root to tip): the gradient, not only its mean
    for part in np.array_split(np.arange(d.shape[0]), 3):
        np.testing.assert_allclose(d[part, :, :3].mean(), c[part, :, :3].mean(), rtol=0.03, atol=0.003,
                                   err_msg=f"{name}, rows {part[0]}-{part[-1]}")
    assert not [m for m in said if name in m], f"no message about '{name}': {said}"


def test_color_attribute_node_naming_curve_intercept_reads_nothing_as_in_cycles(tmp_path):
    """A Color Attribute node naming 'curve_intercept' reads no attribute in Cycles (a standard
    name), not the intercept the Attribute node reads: black strands in both."""
    sc = _scene()
    mat = bpy.data.materials.new("ColorAttr")
    nt = mat.node_tree
    nt.nodes.clear()
    out, em = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeEmission')
    col = nt.nodes.new('ShaderNodeVertexColor')
    col.layer_name = 'curve_intercept'
    nt.links.new(col.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    _curves(mat)
    layer = sc.view_layers[0].name
    means = {e: np.mean([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'])
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    assert means['CYCLES'] < 1e-4 and means['DACRT'] < 1e-4, means
