"""A light's node tree the export cannot compute names what it could not: an IES Texture into the
Emission Strength (Cycles shapes the light by it: a uniform 1000 cd file made a hunter's lamp 70x
brighter) and a Light Path into its Color were both said as 'driven by nodes; its own value
used', without the node."""
from . import scenes


def test_light_node_tree_fallbacks_name_the_nodes(scene, said):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=10)
    lamp = scenes.light('POINT', 100.0, location=(0, 0, 2))
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    nt.links.new(nt.nodes.new('ShaderNodeTexIES').outputs[0], em.inputs['Strength'])
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], em.inputs['Color'])
    scenes.render_rgba(scene)
    # (the IES Texture is applied now; without a profile to read it is said so: test_ies_lights)
    assert any("IES Texture 'IES Texture' cannot be read" in t for t in said), said
    text = next(t for t in said if t.startswith("light 'Point': node tree approximated"))
    assert "Emission colour driven by nodes (colour from 'Light Path' node, not evaluated for a light); " \
           "its own value (1.0, 1.0, 1.0) used" in text, text
