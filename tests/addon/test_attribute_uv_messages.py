"""An Attribute node's output into an Image Texture's Vector: Cycles looks the attribute up by
name (a UV map's as a UV Map node of that name does). It had read the active render map and said
"texture coordinates from 'Attribute' read as the UV map", even where the node named that map
(exact, yet warned of) and wrongly elsewhere (block diff 0.95 on a second map). Now its Vector
and Color outputs, its Fac and an attribute no mesh has are computed per point as Cycles does
(tests/parity/test_attribute_uv.py): nothing is said."""
import numpy as np
import pytest

from tests.addon import scenes

NOTE = "texture coordinates from 'Attribute' read as the UV map"


def _scene(name, output='Vector', mapped=False):
    mat, nt, out = scenes._material("Textured")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("A", np.random.default_rng(32).random((4, 4, 4)).astype(np.float32))
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    at = nt.nodes.new('ShaderNodeAttribute')
    at.attribute_name = name
    if mapped:
        mp = nt.nodes.new('ShaderNodeMapping')
        mp.inputs['Scale'].default_value = (2.0, 2.0, 1.0)
        nt.links.new(at.outputs[output], mp.inputs['Vector'])
        nt.links.new(mp.outputs[0], tex.inputs['Vector'])
    else:
        nt.links.new(at.outputs[output], tex.inputs['Vector'])
    scenes.camera()
    me = scenes.plane("P", size=2.0, materials=(mat,)).data
    me.uv_layers.new(name="UVMap")
    me.uv_layers.new(name="Second")


@pytest.mark.parametrize("name,output,mapped", [("UVMap", 'Vector', False), ("UVMap", 'Color', True),
                                                ("Second", 'Vector', False), ("UVMap", 'Fac', False),
                                                ("", 'Vector', False)])
def test_an_attribute_into_an_image_is_not_said(scene, exported, name, output, mapped):
    _scene(name, output, mapped)
    data = exported()
    assert not any(NOTE in t for _, t in data.messages), data.messages
    if name:        # (an unnamed one is said as such: "has no name: it reads 0, as in Cycles")
        assert "Textured" not in " ".join(t for _, t in data.messages), data.messages
