"""A Mix Shader whose factor an attribute node computes (Curves Info Is Strand between a
mesh's and its hair's shader, a Color Attribute mask, Object Info Random over several objects)
mixes per shading point, as Cycles runs the factor's nodes at each point
(procedurals.compile_socket with attributes, texturedmixes._procedural_mix), against Cycles.

Such a factor had stood at its own value (0.5 of each shader everywhere), said as "Mix Shader
factor not computed (value from 'Curves Info' node)": hair and mesh of red and green diffuse
mixed by Is Strand rendered (0.099, 0.099) where Cycles renders (0.049, 0.155). (Is Strand
needed its own reading too: nodegraph.CURVE_IS_STRAND.)
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.test_curve_standard_attributes import _curves, _scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _mixed(kind, source):
    """A Mix Shader of a red and a green `kind` shader by `source` (fn(node tree) -> socket)."""
    mat = bpy.data.materials.new("Mixed")
    nt = mat.node_tree
    nt.nodes.clear()
    out, mix = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeMixShader')
    a, b = nt.nodes.new(kind), nt.nodes.new(kind)
    a.inputs['Color'].default_value = (0.8, 0.1, 0.1, 1.0)
    b.inputs['Color'].default_value = (0.1, 0.8, 0.1, 1.0)
    nt.links.new(source(nt), mix.inputs['Fac'])
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def _sphere(mat, location=(0.3, 0.5, 0.4), radius=0.5):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=location)
    ob = bpy.context.active_object
    ob.data.materials.append(mat)
    return ob


def _is_strand(kind):
    mat = _mixed(kind, lambda nt: nt.nodes.new('ShaderNodeHairInfo').outputs['Is Strand'])
    _curves(mat)
    _sphere(mat)


def _color_attribute(kind):
    mat = _mixed(kind, lambda nt: nt.nodes.new('ShaderNodeVertexColor').outputs['Color'])
    ob = _sphere(mat)
    attr = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    values = np.random.default_rng(0).random((len(ob.data.vertices), 4))
    values[:, 3] = 1.0
    attr.data.foreach_set('color', values.ravel())


def _object_random(kind):
    mat = _mixed(kind, lambda nt: nt.nodes.new('ShaderNodeObjectInfo').outputs['Random'])
    for i in range(5):
        _sphere(mat, location=(-0.8 + 0.4 * i, 0.0, 0.6), radius=0.18)


CASES = {'is_strand_emission': (_is_strand, 'ShaderNodeEmission'),
         'is_strand_diffuse': (_is_strand, 'ShaderNodeBsdfDiffuse'),
         'color_attribute_diffuse': (_color_attribute, 'ShaderNodeBsdfDiffuse'),
         'object_random_diffuse': (_object_random, 'ShaderNodeBsdfDiffuse')}


@pytest.mark.parametrize('case', list(CASES))
def test_mix_shader_factor_from_an_attribute_mixes_per_point(case, tmp_path, said):
    build, kind = CASES[case]
    sc = _scene()
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 2
    build(kind)
    sun = bpy.data.lights.new("Sun", 'SUN')
    sun.energy = 3.0
    ob = bpy.data.objects.new("Sun", sun)
    sc.collection.objects.link(ob)
    ob.rotation_euler = (0.9, 0.3, 0.2)
    layer = sc.view_layers[0].name
    means = {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGB'], np.float64)
             for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = means['DACRT'], means['CYCLES']
    assert c[:2].min() > 0.01
    np.testing.assert_allclose(d, c, rtol=0.03, atol=0.001, err_msg=case)
    assert not [m for m in said if "factor not computed" in m], said
