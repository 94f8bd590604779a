"""A NaN typed into a shader's colour or vector input (a script's or driver's) is named, at the
top level and inside groups: the NaN scan had read float inputs alone, so a Principled's Base
Color or a Glossy's Color of (NaN, 0.5, 0.5) rendered with no word of it. Cycles 5.0.1 reads the
NaN channel as 0 (measured, 16 spp mean under a white world: Principled (0.038, 0.517, 0.517)
against DACRT's (0.060, 0.529, 0.529), its specular layer as diffuse; Glossy (0, 0.474, 0.474)
against (0, 0.469, 0.469); Diffuse (0, 0.5, 0.5) in both), as the message says."""
import bpy
import numpy as np
import pytest

from . import scenes

NAN = float('nan')


def _render(scene, shader, name, value, grouped=False):
    mat, nt, _, out = scenes.small_view(scene)
    tree = nt
    if grouped:
        tree = bpy.data.node_groups.new('Shading', 'ShaderNodeTree')
        tree.interface.new_socket('Out', in_out='OUTPUT', socket_type='NodeSocketShader')
        go = tree.nodes.new('NodeGroupOutput')
        gn = nt.nodes.new('ShaderNodeGroup')
        gn.node_tree, gn.name = tree, 'G'
        nt.links.new(gn.outputs[0], out.inputs['Surface'])
    node = tree.nodes.new(shader)
    node.name = 'S'
    tree.links.new(node.outputs[0], go.inputs[0] if grouped else out.inputs['Surface'])
    sock = node.inputs[name]
    sock.default_value = value[:len(sock.default_value)]
    scenes.plane("Plane", size=10, materials=(mat,))
    return scenes.render_rgba(scene)


@pytest.mark.parametrize("shader, name, grouped, words", [
    ('ShaderNodeBsdfPrincipled', 'Base Color', False, "'Base Color' of 'S'"),
    ('ShaderNodeBsdfAnisotropic', 'Color', False, "'Color' of 'S'"),
    ('ShaderNodeBsdfPrincipled', 'Base Color', True, "'Base Color' of 'S' in 'G'"),
    ('ShaderNodeBsdfDiffuse', 'Color', True, "'Color' of 'S' in 'G'"),
], ids=['principled', 'glossy', 'principled-in-group', 'diffuse-in-group'])
def test_a_nan_colour_typed_into_a_shader_is_named(scene, said, shader, name, grouped, words):
    img = _render(scene, shader, name, (NAN, 0.5, 0.5, 1.0), grouped)
    text = " | ".join(said)
    assert f"NaN read as 0 (as Cycles clamps it) for {words}" in text, text
    assert np.isfinite(img).all() and img[..., 1].mean() > 0.3


def test_a_nan_alpha_of_a_shader_colour_is_not_named(scene, said):
    # (control: Cycles reads no shader colour's alpha)
    _render(scene, 'ShaderNodeBsdfPrincipled', 'Base Color', (0.5, 0.5, 0.5, NAN))
    assert "NaN" not in " | ".join(said)
