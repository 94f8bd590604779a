"""A NaN or an 'inf' typed (float32's largest) inside a node group, or typed into a Group node's
input that a node inside reads, is named as at the tree's top level: the NaN scan and the
float32-overflow table had looked only at the material tree's top level, so a group's bad value
rendered with no word of it (measured: a NaN Roughness of a Diffuse in a group, a NaN into a Math
in a group, a Combine Color of 3.4e38 in a group: DACRT's and Cycles' images as at the top
level, the report silent)."""
import numpy as np
import pytest

from . import scenes

NAN, INF = float('nan'), float('inf')


def _group(name, inputs=(), output='NodeSocketColor'):
    """A new shader node group with Float inputs named `inputs` and one output; (group, its Group
    Input node, its Group Output node)."""
    import bpy
    g = bpy.data.node_groups.new(name, 'ShaderNodeTree')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    for n in inputs:
        g.interface.new_socket(n, in_out='INPUT', socket_type='NodeSocketFloat')
    g.interface.new_socket('Out', in_out='OUTPUT', socket_type=output)
    return g, gi, go


def _group_node(nt, group, name):
    n = nt.nodes.new('ShaderNodeGroup')
    n.node_tree, n.name = group, name
    return n


def _render(scene, build):
    """A 4x3, 1-sample view of a plane under a grey world whose Diffuse material's tree
    `build(tree, diffuse, output)` completes; the render's report texts are `said`."""
    mat, nt, d, out = scenes.small_view(scene, background=(0.5, 0.5, 0.5))
    build(nt, d, out)
    scenes.plane("Plane", size=10, materials=(mat,))
    scenes.render_rgba(scene)


def _diffuse_in_group(nt, d, out):
    g, _, go = _group('Shading', output='NodeSocketShader')
    inner = g.nodes.new('ShaderNodeBsdfDiffuse')
    inner.inputs['Roughness'].default_value = NAN
    g.links.new(inner.outputs[0], go.inputs[0])
    nt.links.new(_group_node(nt, g, 'G').outputs[0], out.inputs['Surface'])


def _math_in_group(nt, d, out, fed=False):
    """Maximum(a Checker's Fac, NaN) in a group into the Diffuse colour (the Checker keeps it from
    being folded): the NaN typed in the group, or into the Group node's input X."""
    g, gi, go = _group('Shade', inputs=('X',) if fed else ())
    tex, m = g.nodes.new('ShaderNodeTexChecker'), g.nodes.new('ShaderNodeMath')
    m.operation, m.name = 'MAXIMUM', 'Max'
    g.links.new(tex.outputs['Fac'], m.inputs[0])
    if fed:
        g.links.new(gi.outputs[0], m.inputs[1])
    else:
        m.inputs[1].default_value = NAN
    g.links.new(m.outputs[0], go.inputs[0])
    n = _group_node(nt, g, 'G')
    if fed:
        n.inputs['X'].default_value = NAN
    nt.links.new(n.outputs[0], d.inputs['Color'])


def _nested_roughness(nt, d, out):
    """A Group node 'Inner' inside a group 'G', its input X (NaN, typed in G) the Roughness of a
    Diffuse inside Inner."""
    ig, igi, igo = _group('Inner', inputs=('X',), output='NodeSocketShader')
    inner = ig.nodes.new('ShaderNodeBsdfDiffuse')
    ig.links.new(igi.outputs[0], inner.inputs['Roughness'])
    ig.links.new(inner.outputs[0], igo.inputs[0])
    og, _, ogo = _group('Outer', output='NodeSocketShader')
    n = _group_node(og, ig, 'Inner')
    n.inputs['X'].default_value = NAN
    og.links.new(n.outputs[0], ogo.inputs[0])
    nt.links.new(_group_node(nt, og, 'G').outputs[0], out.inputs['Surface'])


def _huge_colour_in_group(nt, d, out):
    g, _, go = _group('Colour')
    c = g.nodes.new('ShaderNodeCombineColor')
    c.inputs['Red'].default_value = INF         # Blender stores float32's largest
    g.links.new(c.outputs[0], go.inputs[0])
    nt.links.new(_group_node(nt, g, 'G').outputs[0], d.inputs['Color'])


@pytest.mark.parametrize("build, words", [
    (_diffuse_in_group, "NaN read as 0 (as Cycles clamps it) for 'Roughness' of 'Diffuse BSDF' in 'G'"),
    (_math_in_group, "NaN computed through the node as Cycles computes it for 'Value' of 'Max' in 'G'"),
    (lambda *a: _math_in_group(*a, fed=True), "NaN computed through the node as Cycles computes it for 'X' of 'G'"),
    (_nested_roughness, "NaN read as 0 (as Cycles clamps it) for 'X' of 'Inner' in 'G'"),
    (_huge_colour_in_group, "'Red' of 'Combine Color' in 'G' at float32's largest (an 'inf' typed: Blender "
                            "stores 3.4e38), where Cycles renders inf or NaN pixels"),
], ids=['shader-input', 'math', 'group-input', 'nested-group-input', 'inf-typed'])
def test_a_bad_value_in_a_group_is_named_where_it_is_typed(scene, said, build, words):
    _render(scene, build)
    text = " | ".join(said)
    assert words in text, text


def test_a_nan_in_a_group_node_nothing_reads_is_not_named(scene, said):
    """(control) A NaN in a Math node inside a group whose output takes a Value node's instead:
    Cycles compiles no such node, so nothing reads the NaN and nothing is said."""
    def build(nt, d, out):
        g, _, go = _group('Shade')
        m, v = g.nodes.new('ShaderNodeMath'), g.nodes.new('ShaderNodeValue')
        m.inputs[1].default_value = NAN
        v.outputs[0].default_value = 0.3
        g.links.new(v.outputs[0], go.inputs[0])
        nt.links.new(_group_node(nt, g, 'G').outputs[0], d.inputs['Color'])
    _render(scene, build)
    assert "NaN" not in " | ".join(said)


def _world_strength_from(scene, build):
    """A 4x3, 1-sample render of the world alone, its Background Strength fed by build(tree) (a
    socket), or set by build when it returns None."""
    scene.render.resolution_x, scene.render.resolution_y = 4, 3
    scene.dacrt.samples = 1
    scenes.camera((0, 0, 3))
    scenes.world((1.0, 1.0, 1.0))
    nt = scene.world.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    src = build(nt, bg)
    if src is not None:
        nt.links.new(src, bg.inputs['Strength'])
    return scenes.render_rgba(scene)


def _world_maximum(nt, bg):
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MAXIMUM'
    m.inputs[0].default_value, m.inputs[1].default_value = NAN, 0.3
    return m.outputs[0]


def _world_group(nt, bg):
    g, _, go = _group('W', output='NodeSocketFloat')
    m, tc, sep = g.nodes.new('ShaderNodeMath'), g.nodes.new('ShaderNodeTexCoord'), g.nodes.new('ShaderNodeSeparateXYZ')
    m.operation = 'MAXIMUM'
    m.inputs[0].default_value = NAN
    g.links.new(tc.outputs['Generated'], sep.inputs[0])
    g.links.new(sep.outputs['Z'], m.inputs[1])
    g.links.new(m.outputs[0], go.inputs[0])
    return _group_node(nt, g, 'G').outputs[0]


def _world_nan_strength(nt, bg):
    bg.inputs['Strength'].default_value = NAN


@pytest.mark.parametrize("build, words, not_words", [
    # Maximum(NaN, 0.3) renders black in both engines: computed with the NaN, not read as 0
    # (which would give 0.3)
    (_world_maximum, "NaN computed through the node as Cycles computes it for 'Value' of 'Math'",
     "NaN read as 0 for 'Value' of 'Math'"),
    (_world_group, "NaN computed through the node as Cycles computes it for 'Value' of 'Math' in 'G'", None),
    # (control: a Background's own NaN Strength is read as 0, a black world, as in Cycles)
    (_world_nan_strength, "NaN read as 0 for 'Strength' of 'Background'", "computed through"),
], ids=['math', 'group', 'strength'])
def test_a_world_nan_is_said_as_the_node_reading_it_takes_it(scene, said, build, words, not_words):
    img = _world_strength_from(scene, build)
    text = " | ".join(said)
    assert words in text, text
    assert not_words is None or not_words not in text, text
    if build is _world_maximum:
        assert np.allclose(img[..., :3], 0.0)
