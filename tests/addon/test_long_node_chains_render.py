"""A material whose colour comes through a very long node chain (800 Math nodes after a Checker)
renders, saying what it does not read: the walk asking whether a procedural texture feeds an
input recursed once per node and passed Python's recursion limit, and the render failed
("maximum recursion depth exceeded")."""
import numpy as np

from . import scenes


def test_an_800_node_chain_from_a_texture_renders_and_is_said(scene, said):
    mat, nt, d, _ = scenes.small_view(scene)
    prev = nt.nodes.new('ShaderNodeTexChecker').outputs['Fac']
    for _ in range(800):
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = 'MULTIPLY_ADD'
        nt.links.new(prev, m.inputs[0])
        prev = m.outputs[0]
    nt.links.new(prev, d.inputs['Color'])
    scenes.plane("Plane", size=10, materials=(mat,))
    img = scenes.render_rgba(scene)
    assert np.isfinite(img).all() and img[..., :3].mean() > 0.1
    assert "procedural texture not evaluated per point" in " | ".join(said)
