"""What the export says where a Color Attribute or Attribute node names a layer the mesh lacks:
the node kind's own alpha (Cycles: a Color Attribute node's 0, an Attribute node's 1), for an
AOV and for a Mix Shader factor read per point. Both had said "alpha 1, as in Cycles", true of
the Attribute node alone (fuzz seed 3013; the values: tests/parity/test_missing_layer_alpha)."""
from . import scenes


def _plane(kind):
    """A plane with no attributes; its material writes AOV 'a' and mixes two emissions by the
    Alpha of a node of `kind` naming 'missing'."""
    mat, nt, out = scenes._material(f"Mat{kind}")
    node = nt.nodes.new(kind)
    if kind == 'ShaderNodeVertexColor':
        node.layer_name = 'missing'
    else:
        node.attribute_name = 'missing'
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'a'
    nt.links.new(node.outputs['Alpha'], aov.inputs['Color'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(nt.nodes.new('ShaderNodeEmission').outputs[0], mix.inputs[1])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], mix.inputs[2])
    nt.links.new(node.outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return scenes.plane(kind[10:], size=2, materials=[mat])


def _messages(scene, exported, kind):
    scenes.camera((0, 0, 5))
    a = scene.view_layers[0].aovs.add()
    a.name, a.type = 'a', 'COLOR'
    _plane(kind)
    return [m for _, m in exported().messages if "no attribute 'missing' on the mesh" in m]


def test_color_attribute_missing_layer_said_alpha_0(scene, exported):
    said = _messages(scene, exported, 'ShaderNodeVertexColor')
    assert any("an AOV reading it reads colour 0 and alpha 0, as in Cycles" in m for m in said), said
    assert any(": it reads colour 0 and alpha 0, as in Cycles" in m for m in said), said
    assert not [m for m in said if "alpha 1" in m], said


def test_attribute_missing_layer_said_alpha_1(scene, exported):
    said = _messages(scene, exported, 'ShaderNodeAttribute')
    assert any("an AOV reading it reads colour 0 and alpha 1, as in Cycles" in m for m in said), said
    assert not [m for m in said if "alpha 0" in m], said
