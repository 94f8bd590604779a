"""Shader AOVs as Cycles writes them (svm/aov.h): what feeds an AOV Output node evaluated with
the machinery of material colours (per object for Object Info, per point for Texture
Coordinate and mesh attributes), a message naming the AOV where an input is not evaluated, and
a COLOR AOV's alpha counting the nodes that write it (each adds (r, g, b, 1)). Values against
Cycles' renders of the same scenes (quoted) or closed forms; DACRT renders only, 32x24."""
import math

import bpy
import numpy as np

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
