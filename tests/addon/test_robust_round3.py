"""What the export says of bad node set-ups and values it renders as Cycles does (hunt "robust",
round 3): each is named, with what it renders as."""
import bpy
import numpy as np

from . import scenes


def _diffuse(name, color=(0.3, 0.45, 0.7)):
    mat = scenes.diffuse(name, color)
    nt = mat.node_tree
    return mat, nt, next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')


def _small(scene):
    scenes.world((1, 1, 1))
    scenes.camera((0, 0, 3), kind='ORTHO', ortho_scale=2.0)
    scene.dacrt.samples, scene.dacrt.max_bounces = 2, 0


def test_group_without_group_output_is_named(scene, said):
    """A group used in a material with no Group Output inside: its output reads 0, said with
    the group and output named (it had read the input's own value, silently)."""
    _small(scene)
    mat, nt, d = _diffuse("M")
    ng = bpy.data.node_groups.new("NoOut", 'ShaderNodeTree')
    ng.interface.new_socket("Tint", in_out='OUTPUT', socket_type='NodeSocketColor')
    g = nt.nodes.new('ShaderNodeGroup')
    g.node_tree = ng
    nt.links.new(g.outputs[0], d.inputs['Color'])
    scenes.plane("P", materials=(mat,))
    bpy.ops.render.render()
    hits = [t for t in said if "'NoOut' output 'Tint'" in t]
    assert hits and "read 0, as in Cycles" in hits[0], said
    said.clear()
    ng.nodes.new('NodeGroupOutput')         # with one: nothing said
    bpy.ops.render.render()
    assert not any("NoOut" in t for t in said), said


def test_nan_in_one_channel_of_a_colour_attribute_is_said_per_channel(scene, exported):
    """NaN in R at one corner: the triangles around it black in R alone (as Cycles), and said
    so (it had said they render black, every channel)."""
    _small(scene)
    mat, nt, d = _diffuse("M")
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = 'Col'
    nt.links.new(a.outputs['Color'], d.inputs['Color'])
    ob = scenes.plane("P", materials=(mat,))
    col = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'CORNER')
    c = np.tile(np.array([0.8, 0.5, 0.2, 1.0], np.float32), (len(col.data), 1))
    c[0, 0] = np.nan
    col.data.foreach_set('color', c.ravel())
    data = exported()
    colors = np.asarray(data.geometry.colors)
    assert np.all(colors[..., 0] == 0.0) and np.allclose(colors[..., 1:], (0.5, 0.2)), colors
    text = " | ".join(m for _, m in data.messages)
    assert "render black in their R channel (the others shaded), as in Cycles" in text, text


def test_nan_attribute_read_by_nodes_is_named(scene, said):
    """A corner colour attribute NaN at one corner into an Emission's Color (read per point by
    the nodes): said, naming the attribute (it had been read as 0 at the corner, silently)."""
    _small(scene)
    mat = scenes.emission("E", (1, 1, 1), 2.0)
    nt = mat.node_tree
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = 'Glow'
    nt.links.new(a.outputs['Color'], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Color'])
    ob = scenes.plane("P", materials=(mat,))
    col = ob.data.color_attributes.new('Glow', 'FLOAT_COLOR', 'CORNER')
    c = np.tile(np.array([0.8, 0.5, 0.2, 1.0], np.float32), (len(col.data), 1))
    c[0, 0] = np.nan
    col.data.foreach_set('color', c.ravel())
    bpy.ops.render.render()
    assert any("'P': attribute 'Glow' NaN or infinite at some corner" in t and "as in Cycles" in t
               for t in said), said


def _mix_cycle(nt):
    a, b = nt.nodes.new('ShaderNodeMix'), nt.nodes.new('ShaderNodeMix')
    a.data_type = b.data_type = 'RGBA'
    nt.links.new(a.outputs[2], b.inputs[6])
    nt.links.new(b.outputs[2], a.inputs[6])
    return b.outputs[2]


def test_link_cycle_is_named_in_a_material_a_group_and_the_world(scene, said):
    """A link cycle: in the material's tree, said as rendered black as in Cycles; in a node group
    it holds, the group named and that Cycles crashes there; in the world's tree, said for the
    world. A link between unavailable sockets closes no cycle (Blender's rule): nothing said."""
    _small(scene)
    mat, nt, d = _diffuse("Looped")
    nt.links.new(_mix_cycle(nt), d.inputs['Color'])
    scenes.plane("P", materials=(mat,))
    bpy.ops.render.render()
    assert any("'Looped' (node link cycle (" in t and "rendered black, as in Cycles" in t for t in said), said
    said.clear()
    ng = bpy.data.node_groups.new("Loop", 'ShaderNodeTree')
    ng.interface.new_socket("Color", in_out='OUTPUT', socket_type='NodeSocketColor')
    ng.links.new(_mix_cycle(ng), ng.nodes.new('NodeGroupOutput').inputs[0])
    mat2, nt2, d2 = _diffuse("Grouped")
    g = nt2.nodes.new('ShaderNodeGroup')
    g.node_tree = ng
    nt2.links.new(g.outputs[0], d2.inputs['Color'])
    bpy.data.objects["P"].data.materials[0] = mat2
    bpy.ops.render.render()
    assert any("node link cycle in node group 'Loop'" in t and "crashes" in t for t in said), said
    said.clear()
    wt = scene.world.node_tree
    wt.links.new(_mix_cycle(wt), next(n for n in wt.nodes if n.type == 'BACKGROUND').inputs['Color'])
    bpy.data.objects["P"].data.materials[0] = scenes.diffuse("Plain", (0.5, 0.5, 0.5))
    bpy.ops.render.render()
    assert any(t.startswith("world approximated: node link cycle") for t in said), said


def test_unavailable_socket_link_is_no_cycle(scene, said):
    """A link left from an output a Mix no longer shows (switched to Float) is invalid but closes
    no cycle: both engines ignore it; nothing said of a cycle."""
    _small(scene)
    mat, nt, d = _diffuse("M")
    a = nt.nodes.new('ShaderNodeMix')
    a.data_type = 'RGBA'
    nt.links.new(a.outputs[2], d.inputs['Color'])
    a.data_type = 'FLOAT'
    scenes.plane("P", materials=(mat,))
    bpy.ops.render.render()
    assert not any("cycle" in t for t in said), said


def test_inf_typed_strength_is_named_and_read_as_0(scene, exported):
    """'inf' typed into a World Background Strength or an Emission Strength: Blender stores
    float32's largest (3.4e38), finite, which the renderer's float32 products overflow on (every
    pixel ~1e37, 3.4e38 on the emitter, unnamed): read as 0 and named with the socket, by the
    rule that skips a lamp of such a strength (lights.base.fits_float32). 1e20 is kept."""
    _small(scene)
    bg = next(n for n in scene.world.node_tree.nodes if n.type == 'BACKGROUND')
    bg.inputs['Strength'].default_value = float('inf')
    mat = scenes.emission("Hot", (1, 1, 1), float('inf'))
    scenes.plane("P", materials=(mat,))
    data = exported()
    text = " | ".join(m for _, m in data.messages)
    assert "world Background colour x strength" in text and "(Strength 3.4e+38" in text, text
    assert "Emission colour x strength 3.4e+38 (Strength 3.4e+38" in text, text
    assert not np.asarray(data.world).any()
    hot = next(m for m in data.materials if m.name == 'Hot')
    assert not np.asarray(hot.emission).any()
    bg.inputs['Strength'].default_value = 1e20
    mat.node_tree.nodes['Emission'].inputs['Strength'].default_value = 1e20
    data = exported()
    assert not any("beyond the float32" in m for _, m in data.messages), data.messages
    assert np.asarray(next(m for m in data.materials if m.name == 'Hot').emission).min() > 1e19


def test_zero_area_light_message_gives_the_world_size(scene, said):
    """An area light of Size 1 whose object is scaled to 0 along X: skipped as in Cycles, the
    message giving the scale and the world size it makes (it had said 'size 1 x 1', hiding
    which side is 0 and why)."""
    _small(scene)
    scenes.plane("P", materials=(scenes.diffuse("D", (0.5, 0.5, 0.5)),))
    ob = scenes.light('AREA', 100.0, location=(0, 0, 2), size=1.0)
    ob.scale = (0.0, 2.0, 1.0)
    bpy.ops.render.render()
    assert any("has zero area (size 1 x 1 m, world scale (0, 2, 1) -> 0 x 2 m)" in t for t in said), said


def test_cycle_in_a_muted_group_is_no_cycle(scene, said):
    """A muted Group node passes its input through (Cycles reads nothing of its tree, and renders
    the material as without it: measured 0.5147 both): a cycle inside it says nothing."""
    _small(scene)
    ng = bpy.data.node_groups.new("Loop", 'ShaderNodeTree')
    ng.interface.new_socket("Color", in_out='OUTPUT', socket_type='NodeSocketColor')
    ng.links.new(_mix_cycle(ng), ng.nodes.new('NodeGroupOutput').inputs[0])
    mat, nt, d = _diffuse("M")
    g = nt.nodes.new('ShaderNodeGroup')
    g.node_tree = ng
    g.mute = True
    nt.links.new(g.outputs[0], d.inputs['Color'])
    scenes.plane("P", materials=(mat,))
    bpy.ops.render.render()
    assert not any("cycle" in t for t in said), said
