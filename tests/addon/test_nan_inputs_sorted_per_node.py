"""A material's NaN inputs are sorted by the node reading them, not by its type: whether the node
evaluation computes a Mix depends on its data type and factor mode (nodeeval.node_inputs), and
the material's scan had asked it per node type, so a non-uniform Mix of colours' NaN A was said
'read as 0' alone and 'computed through the node' beside any float Mix of the tree, an unlinked
one included, for the same image. The world's and light's scan (nanmessages.nan_found) asks it
per node; the material's now reads the same scan."""
import bpy
import numpy as np
import pytest

from . import scenes

NAN = float('nan')


def _render(scene, float_mix_beside):
    mat, nt, _, out = scenes.small_view(scene)
    diffuse = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(diffuse.outputs[0], out.inputs['Surface'])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.name, mix.data_type, mix.factor_mode = 'M', 'RGBA', 'NON_UNIFORM'
    socket = {s.identifier: s for s in (*mix.inputs, *mix.outputs)}
    socket['A_Color'].default_value = (NAN, 0.5, 0.5, 1.0)
    socket['B_Color'].default_value = (0.5, 0.5, 0.5, 1.0)
    socket['Factor_Vector'].default_value = (0.25, 0.25, 0.25)
    nt.links.new(socket['Result_Color'], diffuse.inputs['Color'])
    if float_mix_beside:
        nt.nodes.new('ShaderNodeMix').data_type = 'FLOAT'       # unlinked: read by nothing
    scenes.plane("Plane", size=10, materials=(mat,))
    return scenes.render_rgba(scene)


@pytest.mark.parametrize("float_mix_beside", [False, True], ids=['alone', 'beside-a-float-mix'])
def test_a_nodes_nan_is_said_as_for_the_node_not_its_type(scene, said, float_mix_beside):
    img = _render(scene, float_mix_beside)
    text = " | ".join(t for t in said if "'A' of 'M'" in t)
    assert "NaN read as 0 (as Cycles clamps it) for 'A' of 'M'" in text, said
    assert "computed through" not in text, text
    assert np.isfinite(img).all()
