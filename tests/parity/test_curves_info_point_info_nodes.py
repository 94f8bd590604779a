"""The Curves Info node's Intercept, Length and Random and the Point Info node's Random, read
as Cycles compiles them: its standard attributes 'curve_intercept', 'curve_length',
'curve_random' and 'point_random' (nodegraph.StandardAttributeNode; computed on strands by
export/strands.py StandardAttributes, 0 on a mesh), against Cycles. And the outputs Cycles'
kernel computes, read the same way (meshes.STANDARD_INFO): Curves Info Is Strand and
Thickness, Point Info Radius, in world units on a scaled object.

Those had stood at the input's own value too: Thickness 0.407 where Cycles renders 0.0243,
Radius 0.191 where Cycles renders 0.0152, Is Strand 1 on a mesh (0.26 where Cycles is black).

They had not been evaluated: the linked input's own value stood in (a Color Ramp's Factor 0.5)
for every strand and point, said only as "value from 'Curves Info' node; its own value used":
an Intercept gradient had rendered 0.432 at the roots and 0.430 at the tips where Cycles
renders 0.128 and 0.731, a Point Info Random ramp one colour (std 0.054 where Cycles' is 0.257),
and a Curves Info ramp on a mesh its middle colour where Cycles reads 0.
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.test_curve_standard_attributes import _curves, _particles, _points, _scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _ramped(node_type, output, scale=1.0):
    """An emission material coloured by a Color Ramp (dark blue to white) of node_type's
    output times scale."""
    mat = bpy.data.materials.new(f"{node_type}{output}")
    nt = mat.node_tree
    nt.nodes.clear()
    out, em = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeEmission')
    info, ramp = nt.nodes.new(node_type), nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (0.05, 0.1, 0.4, 1.0)
    mul = nt.nodes.new('ShaderNodeMath')
    mul.operation = 'MULTIPLY'
    mul.inputs[1].default_value = scale
    nt.links.new(info.outputs[output], mul.inputs[0])
    nt.links.new(mul.outputs[0], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _sphere(material):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(0, 0, 0.6))
    bpy.context.active_object.data.materials.append(material)


def _scaled(build, scale):
    """build, then every object but the camera scaled by `scale` (world radii differ)."""
    def scaled(material):
        build(material)
        for ob in bpy.context.scene.objects:
            if ob.type != 'CAMERA':
                ob.scale = scale
    return scaled


CASES = {
    'curves_intercept': (_curves, 'ShaderNodeHairInfo', 'Intercept', 1.0),
    'curves_length': (_curves, 'ShaderNodeHairInfo', 'Length', 0.8),
    'curves_random': (_curves, 'ShaderNodeHairInfo', 'Random', 1.0),
    'particles_intercept': (_particles, 'ShaderNodeHairInfo', 'Intercept', 1.0),
    'points_random': (_points, 'ShaderNodePointInfo', 'Random', 1.0),
    'mesh_curves_random': (_sphere, 'ShaderNodeHairInfo', 'Random', 1.0),      # 0 on a mesh
    'curves_is_strand': (_curves, 'ShaderNodeHairInfo', 'Is Strand', 0.7),
    'mesh_is_strand': (_sphere, 'ShaderNodeHairInfo', 'Is Strand', 1.0),         # 0 on a mesh
    'points_is_strand': (_points, 'ShaderNodeHairInfo', 'Is Strand', 1.0),       # 0 on points
    'curves_thickness': (_curves, 'ShaderNodeHairInfo', 'Thickness', 12.0),
    'curves_thickness_scaled': (_scaled(_curves, (0.5, 1, 1.2)), 'ShaderNodeHairInfo', 'Thickness', 12.0),
    'particles_thickness': (_particles, 'ShaderNodeHairInfo', 'Thickness', 10.0),     # tapered
    'points_radius': (_points, 'ShaderNodePointInfo', 'Radius', 8.0),
    'points_radius_scaled': (_scaled(_points, (0.6, 1, 1)), 'ShaderNodePointInfo', 'Radius', 8.0),
    'curves_point_radius': (_curves, 'ShaderNodePointInfo', 'Radius', 8.0),     # 0 on curves
}


@pytest.mark.parametrize('case', list(CASES))
def test_info_node_output_reads_as_in_cycles(case, tmp_path, said):
    build, node_type, output, scale = CASES[case]
    sc = _scene()
    build(_ramped(node_type, output, scale))
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c[..., :3].mean() > 0.02
    for part in np.array_split(np.arange(d.shape[0]), 3):        # bottom to top: root to tip
        np.testing.assert_allclose(d[part, :, :3].mean(axis=(0, 1)), c[part, :, :3].mean(axis=(0, 1)),
                                   rtol=0.03, atol=0.003, err_msg=f"{case}, rows {part[0]}-{part[-1]}")
    assert not [m for m in said if "its own value used" in m], said


@pytest.mark.parametrize('case', ['curves_intercept', 'curves_length', 'curves_random', 'points_random'])
def test_ramp_of_a_per_strand_value_is_not_said_interpolated(case, said):
    """A Color Ramp of a value that is one per curve or point (Length, Random) into a Base Color
    is exact applied at the corners (all of a strand's corners hold the same value): not said,
    where the Intercept, which varies along the strand, is."""
    build, node_type, output, _ = CASES[case]
    sc = _scene()
    mat = bpy.data.materials.new(case)
    nt = mat.node_tree
    info, ramp = nt.nodes.new(node_type), nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements.new(0.5).color = (0.9, 0.1, 0.1, 1.0)        # not affine in the value
    nt.links.new(info.outputs[output], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], nt.nodes['Principled BSDF'].inputs['Base Color'])
    build(mat)
    sc.render.engine = 'DACRT'
    sc.dacrt.samples = 1
    bpy.ops.render.render()
    interpolated = [m for m in said if "applied at the mesh's corners" in m]
    assert bool(interpolated) == (output == 'Intercept'), said
