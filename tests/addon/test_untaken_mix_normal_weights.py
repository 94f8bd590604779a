"""A Mix Shader whose per-point factor the export does not take (a Checker between a Glossy
BSDF and a Holdout: the Holdout's weight is one per material) weighs its sides' Normal-pass
parts (principled.normal_parts: the closures Cycles gives their own normal) by the factor's own
value, as the same Mix of a constant factor does. Each try at a per-point mix read the sides
and left their entries behind, so the fallback's were added to them: the Glossy counted 3x
(1 + 0.5 of its Color for 0.5), the Normal pass leaning to its raised normal where the diffuse share had
been taken from it."""
import bpy
import numpy as np

from . import scenes


def _mix(name, checker):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.5
    glossy = nt.nodes.new('ShaderNodeBsdfGlossy')
    glossy.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    nt.links.new(glossy.outputs[0], mix.inputs[1])
    nt.links.new(nt.nodes.new('ShaderNodeHoldout').outputs[0], mix.inputs[2])
    if checker:
        nt.links.new(nt.nodes.new('ShaderNodeTexChecker').outputs['Fac'], mix.inputs['Fac'])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def test_untaken_per_point_mix_weighs_normal_parts_as_a_constant_factor(scene, exported):
    mats = [_mix("Constant", False), _mix("Checker", True)]
    scenes.camera()
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    table = {m.name: m for m in exported().materials}
    constant, checker = table["Constant"], table["Checker"]
    assert "Checker" in checker.approximated                # (the factor's own value, said)
    assert np.isclose(constant.normal_parts[0], 0.4)        # the Glossy: Color 0.8 x weight 0.5
    for a, b in zip(constant.normal_parts, checker.normal_parts):
        assert np.allclose(a, b), (constant.normal_parts, checker.normal_parts)
