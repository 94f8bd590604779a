"""An Attribute node's Color or Vector output into an Image Texture's Vector: Cycles looks the
attribute up by name as a UV Map node of that name does, so the export reads it as one (the
map by name, a Geometry Nodes attribute through named_uvs). It had read the active render map
and said "texture coordinates from 'Attribute' read as the UV map", even where the node named
that map (exact, yet warned of) and wrongly elsewhere (block diff 0.95 on a second map, now
0.01: Closest texel edges). Its Fac output, or an unnamed Attribute (0 in Cycles), is still
read on the UV map and said."""
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


def _material(data):
    return next(m for m in data.materials if m.name == "Textured")


@pytest.mark.parametrize("name,output,mapped", [("UVMap", 'Vector', False), ("UVMap", 'Color', True),
                                                ("Second", 'Vector', False)])
def test_an_attribute_naming_a_uv_map_reads_it_by_name_unsaid(scene, exported, name, output, mapped):
    _scene(name, output, mapped)
    data = exported()
    assert not any(NOTE in t for _, t in data.messages), data.messages
    assert _material(data).uv_map == name


@pytest.mark.parametrize("name,output", [("UVMap", 'Fac'), ("", 'Vector')])
def test_an_attributes_factor_or_an_unnamed_one_is_still_said(scene, exported, name, output):
    _scene(name, output)
    data = exported()
    assert any(NOTE in t for _, t in data.messages), data.messages
    assert _material(data).uv_map == ''
