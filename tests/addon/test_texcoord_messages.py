"""What the export says about texture coordinates, UV maps and attributes it reads (renders
against Cycles: tests/parity/test_texcoord_edges.py):
  - a UV Map node naming an attribute of a type Cycles does not read (a string) reads (0, 0),
    as in Cycles, and says so naming the attribute (it had been silent);
  - "textures on several UV maps" is said only where two different maps are read: not for an
    image on a UV Map node naming the active render map times a Checker on Generated or Object
    coordinates (the image's own UV need had counted as Texture Coordinate UV's), nor beside an
    image reading the active render map unnamed (the same map); still for a Checker on Texture
    Coordinate UV beside an image on another map, and for a named map beside the unnamed one on
    a mesh whose active render map is another;
  - an Attribute node naming a standard attribute of Cycles' that the export does not compute
    ('N', 'tangent') says it is not read here (it had said
    "no attribute 'N' on the mesh: its colour reads 0, as in Cycles", where Cycles reads it);
    one Cycles reads 0 for on a mesh ('density') says so, as in Cycles, as does a Color
    Attribute node naming a standard name (Cycles reads none, not even the colour attribute);
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


def _mix_multiply(nt, a, b):
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
    mix.inputs['Factor'].default_value = 1.0
    nt.links.new(a, mix.inputs['A'])
    nt.links.new(b, mix.inputs['B'])
    return mix.outputs['Result']


def _several_material(name, second, uv_map='UVMap'):
    """An image on a UV Map node naming uv_map, times a Checker on Texture Coordinate `second`
    ('Generated', 'Object', 'UV') or (second 'image') a second image with its Vector unlinked."""
    mat, nt, tex = _image_material(name, uv_map)
    d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
    if second == 'image':
        other = nt.nodes.new('ShaderNodeTexImage')
        other.image = bpy.data.images.new(name + "Other", 4, 4)
        b = other.outputs['Color']
    else:
        ck = nt.nodes.new('ShaderNodeTexChecker')
        nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs[second], ck.inputs['Vector'])
        b = ck.outputs['Color']
    nt.links.new(_mix_multiply(nt, tex.outputs['Color'], b), d.inputs['Color'])
    return mat


def _uv_plane(name, x, material, layers=('UVMap',), active=None):
    """A plane with UV maps `layers` (the first the active render one, or `active`)."""
    ob = scenes.plane(name, location=(x, 0, 0), materials=(material,))
    for layer in layers:
        ob.data.uv_layers.new(name=layer)
    if active is not None:
        ob.data.uv_layers[active].active_render = True
    return ob


def _said_several(data):
    return [m.name for m in data.materials if "several UV maps" in m.approximated] + \
        (["(messages)"] if "several UV maps" in _text(data) else [])


def test_one_uv_map_read_two_ways_is_not_said_several(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    for i, second in enumerate(('Generated', 'Object', 'image')):
        _uv_plane(f"P{i}", 3 * i, _several_material(f"M{i}", second))
    data = exported()
    assert not _said_several(data), _text(data)


def test_two_uv_maps_read_are_said_several(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    _uv_plane("Coords", 0, _several_material("OnDetail", 'UV', 'Detail'), ('UVMap', 'Detail'))
    _uv_plane("OtherActive", 3, _several_material("Unnamed", 'image'), ('UVMap', 'Other'), active='Other')
    _uv_plane("SameActive", 6, _several_material("Same", 'image'), ('Other', 'UVMap'), active='UVMap')
    data = exported()
    table = {m.name: m.approximated for m in data.materials}
    assert "textures on several UV maps ('Detail', the active render map)" in table["OnDetail"], table
    assert "textures on several UV maps ('UVMap', the active render map)" in table["Unnamed"], table
    assert "several" not in table["Same"], table


def _attribute_material(name, attribute, output='Color'):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = 'GEOMETRY', attribute
    nt.links.new(a.outputs[output], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def test_standard_attributes_not_read_here_are_said_so(scene, exported):
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    names = ('N', 'tangent')
    # ('random_per_island' and 'pointiness' are read: export/islands.py, export/pointiness.py)
    for i, name in enumerate(names + ('random_per_island', 'pointiness')):
        scenes.plane(f"P{i}", location=(3 * i, 0, 0), materials=(_attribute_material(f"M{i}", name),))
    scenes.plane("Fac", location=(0, 3, 0), materials=(_attribute_material("F", 'N', 'Fac'),))
    scenes.plane("Density", location=(3, 3, 0), materials=(_attribute_material("D", 'density'),))
    mat, nt, out = scenes._material("VC")
    d, vc = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeVertexColor')
    vc.layer_name = 'generated'
    nt.links.new(vc.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("VC", location=(6, 3, 0), materials=(mat,)).data.color_attributes.new('generated', 'FLOAT_COLOR',
                                                                                        'POINT')
    text = _text(exported())
    assert "a Color Attribute node naming 'generated', the name of a Cycles standard attribute, reads no " \
        "attribute" in text and "its colour reads 0, as in Cycles" in text, text
    for name in names:
        assert f"Cycles' standard attribute '{name}' is not read here; its colour reads 0" in text, text
    assert "'random_per_island' is not read here" not in text and "'pointiness' is not read here" not in text, text
    assert "Cycles' standard attribute 'N' is not read here; it reads colour 0 and alpha 1" in text, text
    assert "'density' is the name of a Cycles standard attribute" in text and "reads 0, as in Cycles" in text, text
    assert "no attribute 'N'" not in text and "standard attribute 'N' is not read here; its colour reads 0, as in " \
        "Cycles" not in text, text
