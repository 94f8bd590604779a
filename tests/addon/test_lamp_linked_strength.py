"""A lamp whose node-tree Emission Strength is linked from a node not evaluated for a light (a
Noise Texture): the node stands at the own value of the input it is linked into and the rest of
the chain is computed on it, as a material's evaluation does. It had read the Strength socket's
own value whatever the chain: Noise x 0 lit at 1 (25.9x Cycles, which is dark), Noise x 4 at 1
too. A strength of 0 from such a stand-in had been said "skipped ... with zero strength", which
its 300 W panel and linked Strength contradicted: it is now said as read as 0 there. (The
stand-in is an Image Texture's Alpha: a point lamp's Noise of an unlinked Vector is computed
now, at Cycles' Generated (0, 0, 0) for a light: tests/parity/test_lamp_generated_textures.py.)"""
import bpy
import numpy as np

from . import scenes


def _scene(scene, strength_of, own=1.0):
    """The mean of a render of a 300 W point lamp over a floor, black world; Strength =
    strength_of(tree, an Image Texture's Alpha) (None: a constant `own`), the Strength socket's own value
    `own`. (The scene emptied first, as the `scene` fixture leaves it.)"""
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    scenes.black_world()
    lamp = scenes.light('POINT', 300.0, location=(0, 0, 2), name='Lamp')
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    em.inputs['Strength'].default_value = own
    if strength_of is not None:
        nt.links.new(strength_of(nt, nt.nodes.new('ShaderNodeTexImage').outputs['Alpha']), em.inputs['Strength'])
    scene.dacrt.samples = 4
    return scenes.render_rgba(scene)[..., :3].mean()


def _times(k):
    def chain(nt, fac):
        m = nt.nodes.new('ShaderNodeMath')
        m.operation, m.inputs[1].default_value = 'MULTIPLY', k
        nt.links.new(fac, m.inputs[0])
        return m.outputs[0]
    return chain


def test_chain_is_computed_on_the_stand_in(scene, said):
    """Image x 4 reads 0.5 x 4 = 2 (the Math input's own value 0.5), Image x 0 reads 0 and
    the lamp is dark, as in Cycles; both say the stand-in and the result."""
    unit = _scene(scene, None, 1.0)
    assert unit > 0.01
    del said[:]
    assert np.isclose(_scene(scene, _times(4.0)), 2.0 * unit, rtol=1e-5)
    text = next(t for t in said if t.startswith("light 'Lamp': node tree approximated"))
    assert "value from 'Image Texture' node; its own value used (the 'Math' node's Value input, 0.5)" in text, text
    assert "the chain computed on that: 2" in text, text
    del said[:]
    assert _scene(scene, _times(0.0)) == 0.0
    assert any("the chain computed on that: 0" in t for t in said), said


def test_zero_from_a_stand_in_is_not_zero_strength(scene, said):
    """An image's Alpha into a Strength whose own value is 0: the lamp reads 0 (the documented
    stand-in) and is skipped, said as that, not as a lamp of zero strength."""
    assert _scene(scene, lambda nt, fac: fac, own=0.0) == 0.0
    assert not [t for t in said if "zero strength" in t], said
    assert any("its own value 0 used" in t for t in said), said
    text = next(t for t in said if "node-tree strength reads 0" in t)
    assert text.startswith("skipped 1 light(s) whose node-tree strength reads 0 here"), text
    assert "Lamp (its node-tree Strength (an image) read as 0)" in text, text
    assert not [t for t in said if "as in Cycles" in t], said
