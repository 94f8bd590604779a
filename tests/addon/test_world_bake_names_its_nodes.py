"""A world Strength baked from a chain of view coordinates alone (no texture) names the node
computing it in its messages: its sources had been the textures the chain read, none here, so
the report read "world Background Strength from  below 0 in places" (a blank name), in a group
or not (Generated Z through Maximum(NaN, z): below 0 on the lower half in both engines)."""
import bpy
import pytest

from . import scenes

NAN = float('nan')


def _maximum_of_z(tree):
    m, tc, sep = tree.nodes.new('ShaderNodeMath'), tree.nodes.new('ShaderNodeTexCoord'), \
        tree.nodes.new('ShaderNodeSeparateXYZ')
    m.operation = 'MAXIMUM'
    m.inputs[0].default_value = NAN
    tree.links.new(tc.outputs['Generated'], sep.inputs[0])
    tree.links.new(sep.outputs['Z'], m.inputs[1])
    return m


@pytest.mark.parametrize("grouped, name", [(False, "'Math'"), (True, "'Math' in 'G'")], ids=['top', 'group'])
def test_a_coordinate_chain_baked_into_the_world_is_named(scene, said, grouped, name):
    scene.render.resolution_x, scene.render.resolution_y = 4, 3
    scene.dacrt.samples = 1
    scenes.camera((0, 0, 3))
    scenes.world((1.0, 1.0, 1.0))
    nt = scene.world.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    if grouped:
        g = bpy.data.node_groups.new('W', 'ShaderNodeTree')
        g.interface.new_socket('Out', in_out='OUTPUT', socket_type='NodeSocketFloat')
        go = g.nodes.new('NodeGroupOutput')
        g.links.new(_maximum_of_z(g).outputs[0], go.inputs[0])
        gn = nt.nodes.new('ShaderNodeGroup')
        gn.node_tree, gn.name = g, 'G'
        src = gn.outputs[0]
    else:
        src = _maximum_of_z(nt).outputs[0]
    nt.links.new(src, bg.inputs['Strength'])
    scenes.render_rgba(scene)
    text = " | ".join(said)
    assert f"world Background Strength from {name} below 0 in places" in text, text
    assert f"world Background Strength from {name} baked into" in text, text
    assert "from  " not in text, text
