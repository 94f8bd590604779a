"""Node groups in materials, worlds and lights: read as Cycles reads them (it flattens groups
before compiling a shader), so a material built from groups exports exactly what the same
nodes ungrouped export, with nothing reported as approximated."""
import math

import bpy
import numpy as np

from addon import colornodes, nodeeval, nodegraph, specular
from tests.bench import fairmaterials

from . import scenes


def setup(scene):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))


def _group(name, inputs=(), outputs=(('Shader', 'NodeSocketShader'),)):
    """An empty shader node group with the given (name, socket type) interface; returns the
    group and its Group Input and Group Output nodes."""
    g = bpy.data.node_groups.new(name, 'ShaderNodeTree')
    for n, t in inputs:
        g.interface.new_socket(n, in_out='INPUT', socket_type=t)
    for n, t in outputs:
        g.interface.new_socket(n, in_out='OUTPUT', socket_type=t)
    return g, g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')


def _principled_group():
    """Group 'Paint': a Principled BSDF whose Base Color is the group's 'Tint' input (through a
    reroute) and whose emission is an inner Value node x an inner RGB node."""
    g, gi, go = _group("Paint", inputs=(('Tint', 'NodeSocketColor'),))
    p = g.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Specular IOR Level'].default_value = 0.0
    r = g.nodes.new('NodeReroute')
    g.links.new(gi.outputs['Tint'], r.inputs[0])
    g.links.new(r.outputs[0], p.inputs['Base Color'])
    val, rgb = g.nodes.new('ShaderNodeValue'), g.nodes.new('ShaderNodeRGB')
    val.outputs[0].default_value = 3.0
    rgb.outputs[0].default_value = (1.0, 0.5, 0.25, 1.0)
    g.links.new(val.outputs[0], p.inputs['Emission Strength'])
    g.links.new(rgb.outputs[0], p.inputs['Emission Color'])
    g.links.new(p.outputs[0], go.inputs['Shader'])
    return g


def _output_from_group(tree, output_type, group):
    """Replace the tree by an output node of output_type fed by a Group node of `group`'s
    'Shader' output; returns the Group node."""
    tree.nodes.clear()
    out = tree.nodes.new(output_type)
    node = tree.nodes.new('ShaderNodeGroup')
    node.node_tree = group
    tree.links.new(node.outputs['Shader'], out.inputs['Surface'])
    return node


def _material_using(group, name, tint=None, tint_node=None):
    mat, nt, out = scenes._material(name)
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = group
    if tint is not None:
        node.inputs['Tint'].default_value = (*tint, 1.0)
    if tint_node is not None:
        nt.links.new(tint_node(nt).outputs[0], node.inputs['Tint'])
    nt.links.new(node.outputs['Shader'], out.inputs['Surface'])
    return mat, node


def _rgb(color):
    def make(nt):
        n = nt.nodes.new('ShaderNodeRGB')
        n.outputs[0].default_value = (*color, 1.0)
        return n
    return make


def _materials(exported, *mats):
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    data = exported()
    return {m.name: m for m in data.materials}, data


def test_group_inputs_and_inner_nodes_are_followed(scene, exported):
    """The group's input comes from the Group node's own value or from an RGB node outside;
    the inner Value and RGB nodes feed the emission; a reroute sits in between."""
    setup(scene)
    g = _principled_group()
    own, _ = _material_using(g, "Own", tint=(0.2, 0.4, 0.6))
    linked, _ = _material_using(g, "Linked", tint=(0.9, 0.9, 0.9), tint_node=_rgb((0.1, 0.7, 0.3)))
    table, data = _materials(exported, own, linked)
    assert np.allclose(table["Own"].base_color, (0.2, 0.4, 0.6), atol=1e-6)
    assert np.allclose(table["Linked"].base_color, (0.1, 0.7, 0.3), atol=1e-6)
    for m in table.values():
        if m.name in ("Own", "Linked"):
            assert np.allclose(m.emission, (3.0, 1.5, 0.75), atol=1e-6)
            assert not m.approximated, m.approximated
    assert not any("approximated" in t for _, t in data.messages)


def test_nested_groups(scene, exported):
    """A group inside a group: the outer material's RGB node reaches the Principled two levels
    down, through both Group Input nodes."""
    setup(scene)
    inner = _principled_group()
    outer, gi, go = _group("Wrapper", inputs=(('Colour', 'NodeSocketColor'),))
    node = outer.nodes.new('ShaderNodeGroup')
    node.node_tree = inner
    outer.links.new(gi.outputs['Colour'], node.inputs['Tint'])
    outer.links.new(node.outputs['Shader'], go.inputs['Shader'])
    mat, nt, out = scenes._material("Nested")
    top = nt.nodes.new('ShaderNodeGroup')
    top.node_tree = outer
    nt.links.new(_rgb((0.3, 0.2, 0.1))(nt).outputs[0], top.inputs['Colour'])
    nt.links.new(top.outputs['Shader'], out.inputs['Surface'])
    table, _ = _materials(exported, mat)
    assert np.allclose(table["Nested"].base_color, (0.3, 0.2, 0.1), atol=1e-6)
    assert np.allclose(table["Nested"].emission, (3.0, 1.5, 0.75), atol=1e-6)
    assert not table["Nested"].approximated


def test_group_shaders_mixed_and_unreadable_parts_reported(scene, exported):
    """A Mix Shader inside a group with its factor from the group input; a Glossy BSDF inside a
    group is approximated as diffuse (and says so); a group whose shader output is not linked
    inside renders black, as in Cycles."""
    setup(scene)
    g, gi, go = _group("Blend", inputs=(('Fac', 'NodeSocketFloat'),))
    a, b = g.nodes.new('ShaderNodeBsdfDiffuse'), g.nodes.new('ShaderNodeBsdfGlossy')
    a.inputs['Color'].default_value = (1, 0, 0, 1)
    b.inputs['Color'].default_value = (0, 0, 1, 1)
    mix = g.nodes.new('ShaderNodeMixShader')
    g.links.new(gi.outputs['Fac'], mix.inputs['Fac'])
    g.links.new(a.outputs[0], mix.inputs[1])
    g.links.new(b.outputs[0], mix.inputs[2])
    g.links.new(mix.outputs[0], go.inputs['Shader'])
    mat, nt, out = scenes._material("Blend")
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = g
    node.inputs['Fac'].default_value = 0.25
    nt.links.new(node.outputs['Shader'], out.inputs['Surface'])
    empty, _, _ = _group("Empty")
    black, nt2, out2 = scenes._material("Black")
    en = nt2.nodes.new('ShaderNodeGroup')
    en.node_tree = empty
    nt2.links.new(en.outputs['Shader'], out2.inputs['Surface'])
    table, _ = _materials(exported, mat, black)
    assert np.allclose(table["Blend"].base_color, (0.75, 0, 0.25), atol=1e-6)
    assert "Glossy BSDF as diffuse" in table["Blend"].approximated
    assert np.allclose(table["Black"].base_color, 0) and np.allclose(table["Black"].emission, 0)
    assert not table["Black"].approximated


def test_group_sockets_convert_values_as_cycles(scene, exported):
    """Cycles converts a value at each group socket of another type: a vector through a Float
    socket is its average, also when the socket's own value is used; a vector through a Color
    socket read as a float is a colour's luminance (it was passed through as a colour: the
    vector (0.8, 0.3, 0.1) drew that colour, Cycles a grey 0.4)."""
    setup(scene)
    vec = (0.8, 0.3, 0.1)
    # a float input wired straight to a colour output
    grey, gi, go = _group("Grey", inputs=(('Amount', 'NodeSocketFloat'),), outputs=(('Colour', 'NodeSocketColor'),))
    grey.links.new(gi.outputs['Amount'], go.inputs['Colour'])
    # a vector or colour input into a Math node, its float out as the colour
    def summed(name, socket_type):
        g, gi, go = _group(name, inputs=(('In', socket_type),), outputs=(('Out', 'NodeSocketFloat'),))
        add = g.nodes.new('ShaderNodeMath')
        add.inputs[1].default_value = 0.0
        g.links.new(gi.outputs['In'], add.inputs[0])
        g.links.new(add.outputs[0], go.inputs['Out'])
        return g
    vsum, csum = summed("VectorSum", 'NodeSocketVector'), summed("ColourSum", 'NodeSocketColor')

    def material(name, group, feed=None, own=None):
        mat, nt, out = scenes._material(name)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        node = nt.nodes.new('ShaderNodeGroup')
        node.node_tree = group
        if feed is not None:
            xyz = nt.nodes.new('ShaderNodeCombineXYZ')
            for i, x in enumerate(feed):
                xyz.inputs[i].default_value = x
            nt.links.new(xyz.outputs[0], node.inputs[0])
        if own is not None:
            node.inputs[0].default_value = own
        nt.links.new(node.outputs[0], d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        return mat

    mats = [material("VecThroughFloat", grey, feed=vec), material("VecOwnToFloat", vsum, own=vec),
            material("VecThroughColour", csum, feed=vec), material("VecToVector", vsum, feed=vec)]
    table, _ = _materials(exported, *mats)
    average, luminance = np.mean(vec), float(colornodes.gray(np.array(vec))[0])
    assert abs(average - luminance) > 0.005
    for name, want in (("VecThroughFloat", average), ("VecOwnToFloat", average), ("VecThroughColour", luminance),
                       ("VecToVector", average)):
        assert np.allclose(table[name].base_color, want, atol=1e-6), (name, table[name].base_color, want)
        assert not table[name].approximated, table[name].approximated


def test_image_texture_inside_a_group(scene, exported):
    """An Image Texture inside a group, on the UV map, is the material's texture."""
    setup(scene)
    px = np.ones((2, 2, 4), np.float32)
    px[0, 0, :3] = (0.25, 0.5, 0.75)
    img = scenes.float_image("Checker", px)
    g, gi, go = _group("Textured")
    tex, d = g.nodes.new('ShaderNodeTexImage'), g.nodes.new('ShaderNodeBsdfDiffuse')
    tex.image = img
    g.links.new(tex.outputs['Color'], d.inputs['Color'])
    g.links.new(d.outputs[0], go.inputs['Shader'])
    mat, nt, out = scenes._material("Tex")
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = g
    nt.links.new(node.outputs['Shader'], out.inputs['Surface'])
    ob = scenes.plane("P", materials=(mat,))
    ob.data.uv_layers.new(name="UVMap")
    data = exported()
    m = data.materials[data.geometry.material[0]]
    assert m.name == "Tex" and m.texture is not None and not m.approximated
    assert np.allclose(m.texture[..., :3], px[..., :3])


def test_world_and_light_groups(scene, exported):
    """A world whose Background sits in a group, its strength from the group input; a light
    whose Emission node sits in a group."""
    setup(scene)
    scenes.world((0, 0, 0), 1.0)
    g, gi, go = _group("Sky", inputs=(('Strength', 'NodeSocketFloat'),))
    bg = g.nodes.new('ShaderNodeBackground')
    bg.inputs['Color'].default_value = (0.5, 0.25, 1.0, 1.0)
    g.links.new(gi.outputs['Strength'], bg.inputs['Strength'])
    g.links.new(bg.outputs[0], go.inputs['Shader'])
    _output_from_group(scene.world.node_tree, 'ShaderNodeOutputWorld', g).inputs['Strength'].default_value = 2.0
    lamp = scenes.light('POINT', 100.0, location=(0, 0, 3), name="Lamp")
    lamp.data.use_nodes = True
    lg, _, lgo = _group("LampShader")
    em = lg.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (1.0, 0.5, 0.5, 1.0)
    em.inputs['Strength'].default_value = 0.5
    lg.links.new(em.outputs[0], lgo.inputs['Shader'])
    _output_from_group(lamp.data.node_tree, 'ShaderNodeOutputLight', lg)
    scenes.plane("Floor")
    data = exported()
    assert np.allclose(data.world, (1.0, 0.5, 2.0))
    lamp.data.use_nodes = False
    plain = exported().lights[0].strength
    assert np.allclose(data.lights[0].strength / plain, (0.5, 0.25, 0.25), rtol=1e-6)
    assert not any("node tree" in t for _, t in data.messages)


def test_source_carrier_and_unwrap(scene):
    """source() names the socket whose own value stands in for an unreadable node: the Group
    node's input when the chain leaves the group through its Group Input."""
    g, gi, go = _group("Carrier", inputs=(('Tint', 'NodeSocketColor'),))
    d = g.nodes.new('ShaderNodeBsdfDiffuse')
    g.links.new(gi.outputs['Tint'], d.inputs['Color'])
    g.links.new(d.outputs[0], go.inputs['Shader'])
    mat, node = _material_using(g, "M", tint=(0.3, 0.3, 0.3))
    noise = mat.node_tree.nodes.new('ShaderNodeTexNoise')
    mat.node_tree.links.new(noise.outputs['Color'], node.inputs['Tint'])
    out = nodegraph.output_node(mat.node_tree)
    inner = nodegraph.linked_node(out.inputs['Surface'])
    assert nodegraph.unwrap(inner) == d and inner.groups == (node,)
    link, carrier = nodegraph.source(inner.inputs['Color'])
    assert nodegraph.unwrap(link.from_node) == noise
    assert nodegraph.unwrap(carrier) == node.inputs['Tint'] and carrier.groups == ()
    color, exact = nodeeval.constant_color(inner.inputs['Color'])
    assert np.allclose(color, 0.3) and not exact


def test_fair_editor_edits_inside_groups(scene, exported):
    """The benchmark's fair-material editor follows groups as the export does: it zeroes a
    grouped Principled's metallic in the group's tree and unlinks a Noise Texture of Geometry
    Tangent (which the export reads as its own value) at the Group node's input, so nothing
    is left approximated."""
    setup(scene)
    g, gi, go = _group("Metal", inputs=(('Tint', 'NodeSocketColor'),))
    p = g.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Metallic'].default_value = 1.0
    p.inputs['Specular IOR Level'].default_value = 0.0
    g.links.new(gi.outputs['Tint'], p.inputs['Base Color'])
    g.links.new(p.outputs[0], go.inputs['Shader'])
    mat, node = _material_using(g, "Metal", tint=(0.4, 0.5, 0.6))
    noise = mat.node_tree.nodes.new('ShaderNodeTexNoise')
    geometry = mat.node_tree.nodes.new('ShaderNodeNewGeometry')      # (Tangent: not read per point)
    mat.node_tree.links.new(geometry.outputs['Tangent'], noise.inputs['Vector'])
    mat.node_tree.links.new(noise.outputs['Color'], node.inputs['Tint'])
    assert fairmaterials.remaining_approximations([mat])
    changes = fairmaterials.make_diffuse([mat])
    assert changes["Metal"]
    assert fairmaterials.remaining_approximations([mat]) == {}
    assert p.inputs['Metallic'].default_value == 0.0 and not node.inputs['Tint'].is_linked
    table, _ = _materials(exported, mat)
    # the metal's albedo (what the export renders for it) folded into the base colour
    want = specular.metal_albedo(0.5, (0.4, 0.5, 0.6), (1, 1, 1))
    assert np.allclose(table["Metal"].base_color, want, atol=1e-6) and want[0] < 0.39


def test_used_outputs_follow_links_back_through_groups_and_mutes(scene):
    """used_outputs: what reaches the active output, as source() follows links (groups,
    reroutes, muted nodes); an output linked only to a node nothing uses is not among them."""
    g, gi, go = _group("Lookup", outputs=(('Color', 'NodeSocketColor'), ('Alpha', 'NodeSocketFloat')))
    inner = g.nodes.new('ShaderNodeTexImage')
    g.links.new(inner.outputs['Color'], go.inputs['Color'])
    g.links.new(inner.outputs['Alpha'], go.inputs['Alpha'])
    mat, nt, out = scenes._material("Used outputs")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    group = nt.nodes.new('ShaderNodeGroup')
    group.node_tree = g
    nt.links.new(group.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    tex = nt.nodes.new('ShaderNodeTexImage')
    leftover = nt.nodes.new('ShaderNodeMath')           # feeds nothing
    nt.links.new(tex.outputs['Alpha'], leftover.inputs[0])
    muted = nt.nodes.new('ShaderNodeInvert')             # muted: Color passes through to Roughness
    muted.mute = True
    nt.links.new(tex.outputs['Color'], muted.inputs['Color'])
    nt.links.new(muted.outputs['Color'], d.inputs['Roughness'])
    used = nodegraph.used_outputs(nt)
    inner_key = lambda s: nodegraph.output_key(nodegraph.GraphNode(inner, (group,)), s)  # noqa: E731
    assert inner_key('Color') in used and inner_key('Alpha') not in used
    assert nodegraph.output_key(tex, 'Color') in used
    assert nodegraph.output_key(tex, 'Alpha') not in used and nodegraph.output_key(leftover, 'Value') not in used
    nt.links.new(group.outputs['Alpha'], d.inputs['Roughness'])     # now the group's Alpha is used
    assert inner_key('Alpha') in nodegraph.used_outputs(nt)


def test_a_colour_passes_group_sockets_and_muted_nodes_unconverted(scene, exported):
    """A colour crosses a group's Float or Vector socket, or a muted Math node, as it is, and is
    converted only where it is read, as Cycles 5.0 renders it (measured: red through a Float
    socket stays red, where DACRT had drawn its luminance grey 0.21; through a Vector socket
    into a Math node it is the luminance 0.2126, where DACRT had taken the average 0.333);
    a vector is converted at the sockets (test_group_sockets_convert_values_as_cycles)."""
    setup(scene)
    red = (1.0, 0.0, 0.0)

    def through(name, socket_type, then_math=False, muted=False):
        mat, nt, out = scenes._material(name)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        rgb = nt.nodes.new('ShaderNodeRGB')
        rgb.outputs[0].default_value = (*red, 1.0)
        if muted:
            node = nt.nodes.new('ShaderNodeMath')
            node.operation, node.mute = 'SQRT', True
        else:
            g, gi, go = _group(name + "Group", inputs=(('In', socket_type),), outputs=(('Out', socket_type),))
            g.links.new(gi.outputs['In'], go.inputs['Out'])
            node = nt.nodes.new('ShaderNodeGroup')
            node.node_tree = g
        nt.links.new(rgb.outputs[0], node.inputs[0])
        result = node.outputs[0]
        if then_math:
            result = scenes.read_as_float(nt, result)
        nt.links.new(result, d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
        return mat

    mats = [through("FloatSocket", 'NodeSocketFloat'), through("Muted", None, muted=True),
            through("VectorSocketMath", 'NodeSocketVector', then_math=True)]
    table, _ = _materials(exported, *mats)
    luminance = float(colornodes.gray(np.array(red))[0])
    for name, want in (("FloatSocket", red), ("Muted", red), ("VectorSocketMath", (luminance,) * 3)):
        assert np.allclose(table[name].base_color, want, atol=1e-6), (name, table[name].base_color, want)
        assert not table[name].approximated, table[name].approximated
