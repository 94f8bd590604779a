"""What the export says about texture coordinates, UV maps and attributes it reads (renders
against Cycles: tests/parity/test_texcoord_edges.py):
  - a UV Map node naming an attribute of a type Cycles does not read (a string) reads (0, 0),
    as in Cycles, and says so naming the attribute (it had been silent);
"""
import numpy as np

import bpy

from . import scenes


def _text(data):
    return " | ".join(m for _, m in data.messages)


def _image_material(name, uv_map=None):
    """A Diffuse whose colour is a 4 x 4 image, through a UV Map node naming uv_map if given."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = bpy.data.images.new(name + "Image", 4, 4)
    if uv_map is not None:
        uvn = nt.nodes.new('ShaderNodeUVMap')
        uvn.uv_map = uv_map
        nt.links.new(uvn.outputs['UV'], tex.inputs['Vector'])
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat, nt, tex


def test_uv_map_node_naming_an_unread_attribute_says_so(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    mat, _, _ = _image_material("Named", 'label')
    ob = scenes.plane("Plane", materials=(mat,))
    ob.data.attributes.new('label', 'STRING', 'POINT')
    data = exported()
    assert np.all(np.asarray(data.geometry.uvs) == 0.0)
    text = _text(data)
    assert "attribute 'label'" in text and "UV Map" in text and "(0, 0), as in Cycles" in text, text
