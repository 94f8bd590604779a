"""Shader AOVs as Cycles writes them (svm/aov.h): what feeds an AOV Output node evaluated with
the machinery of material colours (per object for Object Info, per point for Texture
Coordinate and mesh attributes), a message naming the AOV where an input is not evaluated, and
a COLOR AOV's alpha counting the nodes that write it (each adds (r, g, b, 1)). Values against
Cycles' renders of the same scenes (quoted) or closed forms; DACRT renders only, 32x24."""
import math

import bpy
import numpy as np
import pytest

from addon.export.objectinfo import object_random
from . import scenes


def _front_camera(sc):
    cam = bpy.data.objects.new('Cam', bpy.data.cameras.new('Cam'))
    sc.collection.objects.link(cam)
    cam.location, cam.rotation_euler = (0, -5, 0), (math.radians(90), 0, 0)
    sc.camera = cam


def _add_aov(sc, name, kind):
    a = sc.view_layers[0].aovs.add()
    a.name, a.type = name, kind


def _aov_node(tree, name, color=None, value=None):
    node = tree.nodes.new('ShaderNodeOutputAOV')
    node.aov_name = name
    if color is not None:
        node.inputs['Color'].default_value = (*color, 1.0)
    if value is not None:
        node.inputs['Value'].default_value = value
    return node


def _render(sc, tmp_path, samples=4):
    """{channel: (H, W)} of the multilayer result (row 0 at the bottom)."""
    sc.dacrt.samples = samples
    return scenes.read_exr(scenes.render_exr(tmp_path / "aov.exr", sc, multilayer=True))


def _rgba(exr, name, at):
    return np.array([exr[f"ViewLayer.{name}.{c}"][at] for c in 'RGBA'])


CENTRE, CORNER = (12, 16), (0, 0)


# --- a COLOR AOV's alpha counts its nodes --------------------------------------------------------

def test_two_nodes_of_one_color_aov_write_alpha_two(scene, tmp_path):
    """Two AOV Output nodes named 'tint' in one material, colours (0.1, 0, 0) and (0, 0.2, 0):
    Cycles writes (0.1, 0.2, 0, 2.0) there (each node adds alpha 1; DACRT had written 1.0)."""
    _front_camera(scene)
    mat = scenes.diffuse('Grey', (0.5, 0.5, 0.5))
    _aov_node(mat.node_tree, 'tint', color=(0.1, 0.0, 0.0))
    _aov_node(mat.node_tree, 'tint', color=(0.0, 0.2, 0.0))
    scenes.cube('Box', size=2, materials=[mat])
    scenes.world((0.5, 0.5, 0.5))
    _add_aov(scene, 'tint', 'COLOR')
    exr = _render(scene, tmp_path)
    np.testing.assert_allclose(_rgba(exr, 'tint', CENTRE), (0.1, 0.2, 0.0, 2.0), atol=1e-6)
    np.testing.assert_allclose(_rgba(exr, 'tint', CORNER), 0.0, atol=1e-6)     # the world writes none


def test_group_used_twice_and_world_nodes_each_add_alpha(scene, tmp_path):
    """A group holding one AOV Output node (0.1, 0, 0), used twice in a material, and two world
    AOV Output nodes (0, 0, 0.3) and (0, 0.1, 0): Cycles writes (0.2, 0, 0, 2.0) on the cube and
    (0, 0.1, 0.3, 2.0) on the sky (DACRT had written alpha 1.0 on both)."""
    _front_camera(scene)
    mat = scenes.diffuse('Grey', (0.5, 0.5, 0.5))
    group = bpy.data.node_groups.new('G', 'ShaderNodeTree')
    _aov_node(group, 'tint', color=(0.1, 0.0, 0.0))
    for _ in range(2):
        mat.node_tree.nodes.new('ShaderNodeGroup').node_tree = group
    scenes.cube('Box', size=2, materials=[mat])
    scenes.world((0.5, 0.5, 0.5))
    for color in ((0.0, 0.0, 0.3), (0.0, 0.1, 0.0)):
        _aov_node(scene.world.node_tree, 'tint', color=color)
    _add_aov(scene, 'tint', 'COLOR')
    exr = _render(scene, tmp_path)
    np.testing.assert_allclose(_rgba(exr, 'tint', CENTRE), (0.2, 0.0, 0.0, 2.0), atol=1e-6)
    np.testing.assert_allclose(_rgba(exr, 'tint', CORNER), (0.0, 0.1, 0.3, 2.0), atol=1e-6)


def test_aov_counts_exported(scene, exported):
    """Material.aov_counts and SceneData.world_aov_counts: how many nodes write each AOV."""
    _front_camera(scene)
    mat = scenes.diffuse('Grey', (0.5, 0.5, 0.5))
    for _ in range(3):
        _aov_node(mat.node_tree, 'tint', color=(0.1, 0.0, 0.0))
    _aov_node(mat.node_tree, 'mask', value=0.5)
    scenes.plane('P', materials=[mat])
    scenes.world((0.5, 0.5, 0.5))
    _aov_node(scene.world.node_tree, 'tint', color=(0.0, 0.1, 0.0))
    _add_aov(scene, 'tint', 'COLOR')
    _add_aov(scene, 'mask', 'VALUE')
    s = exported()
    m = next(m for m in s.materials if m.name == 'Grey')
    assert m.aov_counts == {'tint': 3, 'mask': 1}
    np.testing.assert_allclose(m.aovs['tint'][0], (0.3, 0.0, 0.0), atol=1e-6)
    assert s.world_aov_counts == {'tint': 1}


# --- inputs evaluated per object and per point ----------------------------------------------------

def _grey_with(scene, name='Grey'):
    _front_camera(scene)
    scenes.world((0.5, 0.5, 0.5))
    return scenes.diffuse(name, (0.5, 0.5, 0.5))


def test_object_info_random_per_object(scene, tmp_path, said):
    """A VALUE AOV fed by Object Info > Random on a material of constant colour, on two cubes
    (one through a Math Multiply by 2): each cube's value is Blender's hash of its name, as
    Cycles writes it (its render of 'Box' at the centre: 0.1934; DACRT had written 0.0000, with
    a warning that never named the AOV)."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    info = nt.nodes.new('ShaderNodeObjectInfo')
    nt.links.new(info.outputs['Random'], _aov_node(nt, 'rand').inputs['Value'])
    math = nt.nodes.new('ShaderNodeMath')
    math.operation, math.inputs[1].default_value = 'MULTIPLY', 2.0
    nt.links.new(info.outputs['Random'], math.inputs[0])
    nt.links.new(math.outputs[0], _aov_node(nt, 'twice').inputs['Value'])
    scenes.cube('Box', size=0.8, location=(-0.7, 0, 0), materials=[mat])
    scenes.cube('Crate', size=0.8, location=(0.7, 0, 0), materials=[mat])
    _add_aov(scene, 'rand', 'VALUE')
    _add_aov(scene, 'twice', 'VALUE')
    exr = _render(scene, tmp_path)
    rand, twice = exr['ViewLayer.rand.X'], exr['ViewLayer.twice.X']
    left, right = (12, 11), (12, 21)          # the cubes' centres (row 0 at the bottom)
    box, crate = object_random('Box', 0, False), object_random('Crate', 0, False)
    assert abs(box - 0.1934) < 1e-4 and abs(box - crate) > 0.05
    assert rand[left] == pytest.approx(box, abs=1e-5) and rand[right] == pytest.approx(crate, abs=1e-5)
    assert twice[left] == pytest.approx(2 * box, abs=1e-5) and twice[right] == pytest.approx(2 * crate, abs=1e-5)
    assert rand[CORNER] == 0.0
    assert not any('Object Info' in t for t in said), said


def test_object_info_location_and_color(scene, tmp_path):
    """A COLOR AOV fed by Object Info > Location, another by Object Info > Color: the object's
    location and viewport colour (DACRT had written 0 for both)."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    info = nt.nodes.new('ShaderNodeObjectInfo')
    nt.links.new(info.outputs['Location'], _aov_node(nt, 'loc').inputs['Color'])
    nt.links.new(info.outputs['Color'], _aov_node(nt, 'col').inputs['Color'])
    ob = scenes.cube('Box', size=1.0, location=(0.1, 0.2, 0.05), materials=[mat])
    ob.color = (0.3, 0.6, 0.9, 1.0)
    _add_aov(scene, 'loc', 'COLOR')
    _add_aov(scene, 'col', 'COLOR')
    exr = _render(scene, tmp_path)
    np.testing.assert_allclose(_rgba(exr, 'loc', CENTRE), (0.1, 0.2, 0.05, 1.0), atol=1e-5)
    np.testing.assert_allclose(_rgba(exr, 'col', CENTRE), (0.3, 0.6, 0.9, 1.0), atol=1e-5)


def test_texture_coordinates_and_geometry_position_per_point(scene, tmp_path):
    """COLOR AOVs fed straight by Texture Coordinate > Generated and Object and by Geometry >
    Position, on a cube of size 2 at (0, 0, 0.3) seen face on (its face y = -1): per point,
    Generated (x + 1) / 2, 0, (z' + 1) / 2, Object (x, -1, z'), Position (x, -1, z' + 0.3)
    with z' the object-space height; a VALUE AOV of Generated is their average (Cycles
    converts a vector so). DACRT had written 0 for each."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    tc = nt.nodes.new('ShaderNodeTexCoord')
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    nt.links.new(tc.outputs['Generated'], _aov_node(nt, 'gen').inputs['Color'])
    nt.links.new(tc.outputs['Object'], _aov_node(nt, 'obj').inputs['Color'])
    nt.links.new(geo.outputs['Position'], _aov_node(nt, 'pos').inputs['Color'])
    nt.links.new(tc.outputs['Generated'], _aov_node(nt, 'genv').inputs['Value'])
    scenes.cube('Box', size=2.0, location=(0, 0, 0.3), materials=[mat])
    for name in ('gen', 'obj', 'pos'):
        _add_aov(scene, name, 'COLOR')
    _add_aov(scene, 'genv', 'VALUE')
    exr = _render(scene, tmp_path, samples=16)
    obj = np.stack([exr[f'ViewLayer.obj.{c}'] for c in 'RGB'], axis=-1)
    gen = np.stack([exr[f'ViewLayer.gen.{c}'] for c in 'RGB'], axis=-1)
    pos = np.stack([exr[f'ViewLayer.pos.{c}'] for c in 'RGB'], axis=-1)
    face = np.s_[7:22, 8:24]                 # pixels well inside the front face
    assert np.allclose(obj[face][..., 1], -1.0, atol=1e-5)
    # the view spans x and z across the face: a gradient, not a constant
    assert np.ptp(obj[face][..., 0]) > 0.5 and np.ptp(obj[face][..., 2]) > 0.3
    np.testing.assert_allclose(gen[face], (obj[face] + 1.0) / 2.0, atol=1e-5)
    np.testing.assert_allclose(pos[face], obj[face] + (0.0, 0.0, 0.3), atol=1e-5)
    np.testing.assert_allclose(exr['ViewLayer.genv.X'][face], gen[face].mean(axis=-1), atol=1e-5)
    # the centre pixel looks at the face's middle, 0.3 below it in object space
    np.testing.assert_allclose(obj[CENTRE], (0.0, -1.0, -0.3), atol=0.1)


def test_color_attribute_per_corner(scene, tmp_path):
    """A COLOR AOV fed by a Color Attribute node, and a VALUE AOV by its Fac through a Math
    Multiply by 3, on a plane whose corners carry a colour attribute: the attribute as Cycles
    interpolates it (a constant attribute gives the constant; DACRT had written 0)."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    attr = nt.nodes.new('ShaderNodeVertexColor')
    attr.layer_name = 'paint'
    nt.links.new(attr.outputs['Color'], _aov_node(nt, 'paint').inputs['Color'])
    math = nt.nodes.new('ShaderNodeMath')
    math.operation, math.inputs[1].default_value = 'MULTIPLY', 3.0
    nt.links.new(attr.outputs['Alpha'], math.inputs[0])
    nt.links.new(math.outputs[0], _aov_node(nt, 'alpha3').inputs['Value'])
    ob = scenes.plane('Card', size=2.0, materials=[mat])
    ob.rotation_euler = (math_pi_2(), 0, 0)
    layer = ob.data.color_attributes.new('paint', 'FLOAT_COLOR', 'POINT')
    for d in layer.data:
        d.color = (0.2, 0.4, 0.6, 0.25)
    _add_aov(scene, 'paint', 'COLOR')
    _add_aov(scene, 'alpha3', 'VALUE')
    exr = _render(scene, tmp_path)
    np.testing.assert_allclose(_rgba(exr, 'paint', CENTRE), (0.2, 0.4, 0.6, 1.0), atol=1e-5)
    assert exr['ViewLayer.alpha3.X'][CENTRE] == pytest.approx(0.75, abs=1e-5)


def math_pi_2():
    return math.pi / 2


def test_light_path_camera_outputs(scene, tmp_path):
    """Light Path outputs as the camera rays that write AOVs read them: Is Camera Ray 1 (Cycles:
    its COLOR AOV equals the alpha coverage, 0.8115 on average in its render of a floor, cube
    and ball), Is Diffuse Ray and Ray Depth 0 (DACRT had written 0 for Is Camera Ray)."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    lp = nt.nodes.new('ShaderNodeLightPath')
    nt.links.new(lp.outputs['Is Camera Ray'], _aov_node(nt, 'cam').inputs['Color'])
    nt.links.new(lp.outputs['Is Diffuse Ray'], _aov_node(nt, 'diff', value=0.5).inputs['Value'])
    nt.links.new(lp.outputs['Ray Depth'], _aov_node(nt, 'depth', value=0.5).inputs['Value'])
    scenes.cube('Box', size=2.0, materials=[mat])
    for name, kind in (('cam', 'COLOR'), ('diff', 'VALUE'), ('depth', 'VALUE')):
        _add_aov(scene, name, kind)
    exr = _render(scene, tmp_path)
    np.testing.assert_allclose(_rgba(exr, 'cam', CENTRE), 1.0, atol=1e-6)
    assert exr['ViewLayer.diff.X'][CENTRE] == 0.0 and exr['ViewLayer.depth.X'][CENTRE] == 0.0


@pytest.mark.parametrize('node, output, value', [('ShaderNodeLightPath', 'Ray Length', 0.0),
                                                 ('ShaderNodeNewGeometry', 'Backfacing', 0.0)])
def test_unevaluated_input_is_named_with_its_aov(scene, tmp_path, said, node, output, value):
    """An AOV input the export does not evaluate per point (Light Path Ray Length, Geometry
    Backfacing) writes its own value, and the warning names the AOV, the node and output, and
    what is written, under the material's name (it had said only "value from 'Light Path'
    node; its own value used")."""
    mat = _grey_with(scene)
    nt = mat.node_tree
    src = nt.nodes.new(node)
    nt.links.new(src.outputs[output], _aov_node(nt, 'v').inputs['Value'])
    scenes.cube('Box', size=2.0, materials=[mat])
    _add_aov(scene, 'v', 'VALUE')
    exr = _render(scene, tmp_path)
    assert exr['ViewLayer.v.X'][CENTRE] == value
    text = next(t for t in said if 'approximated' in t)
    assert f"'Grey' (AOV 'v' value: '{src.bl_label}' {output} not evaluated for it; its input's own value 0 " \
           "is written)" in text, text
