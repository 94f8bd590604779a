"""Shader nodes the export keeps as something simpler than Cycles renders (a transparent
surface, a diffuse albedo, an opacity image, nothing at all): what each becomes in the exported
material, checked against the numbers Cycles gives for the same node, and that each
approximation says so in the material's message.

Every test renders through the registered engine and checks the SceneData it exported (see
conftest.exported)."""
import bpy
import numpy as np

from addon import specular

from . import scenes


def _material(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new('ShaderNodeOutputMaterial')


def _table(exported, *mats):
    """{name: exported Material} of mats, each on a plane of its own."""
    scenes.camera()
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    return {m.name: m for m in exported().materials}


def test_glass_colour_tints_its_reflection(scene, exported):
    """Cycles weighs the whole Glass BSDF by its Color, reflection and transmission alike: a
    clear pane of colour (1, 0.2, 0.2) before a white world is (1, 0.2, 0.2). The reflection was
    kept white (0.092 at IOR 1.5 in every channel) and only the transmission tinted, so the pane
    rendered (1, 0.273, 0.273)."""
    mat, nt, out = _material("Red glass")
    g = nt.nodes.new('ShaderNodeBsdfGlass')
    g.inputs['Color'].default_value = (1.0, 0.2, 0.2, 1.0)
    g.inputs['Roughness'].default_value = 0.0
    nt.links.new(g.outputs[0], out.inputs['Surface'])
    m = _table(exported, mat)["Red glass"]
    fresnel = specular.layer_albedo(0.0, 1.5, 0.5, (1.0, 1.0, 1.0), True)
    np.testing.assert_allclose(m.base_color, np.array([1.0, 0.2, 0.2]) * fresnel, rtol=1e-5)
    np.testing.assert_allclose(m.transparency, np.array([1.0, 0.2, 0.2]) * (1.0 - fresnel), rtol=1e-5)
    # before a white world: reflection + transmission = the colour
    np.testing.assert_allclose(m.base_color + m.transparency, (1.0, 0.2, 0.2), rtol=1e-5)
