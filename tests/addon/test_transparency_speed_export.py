"""The export side of a transparent step's cost (Transparency._through): materials that cut
out by one image's alpha get one opacity array, so the integrator looks it up once for all of
their hits (SurfaceValues._transparency groups lookups by texture); 20 leaf materials on one
image had paid 20 lookups a step."""
import math

import bpy
import numpy as np

from . import scenes


def _alpha_image(alphas):
    img = bpy.data.images.new("Alpha", len(alphas), 1, float_buffer=True, alpha=True)
    img.pixels.foreach_set([c for a in alphas for c in (0.5, 0.5, 0.5, a)])
    img.pack()
    return img


def _card(name, image, transparent_first=True):
    """Mix Shader (factor: the image's alpha) of a Transparent BSDF and a Diffuse."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    mix = nt.nodes.new('ShaderNodeMixShader')
    clear, dif = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    t = nt.nodes.new('ShaderNodeTexImage')
    t.image = image
    nt.links.new(t.outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(clear.outputs[0], mix.inputs[1 if transparent_first else 2])
    nt.links.new(dif.outputs[0], mix.inputs[2 if transparent_first else 1])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def test_materials_cut_out_by_one_image_share_its_opacity_array(scene, exported):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    image = _alpha_image([0.0, 0.25, 1.0])
    other = _alpha_image([1.0, 0.5, 0.0])
    leaf = scenes.principled("Leaf", (0.2, 0.6, 0.1))
    tex = leaf.node_tree.nodes.new('ShaderNodeTexImage')
    tex.image = image
    leaf.node_tree.links.new(tex.outputs['Alpha'], leaf.node_tree.nodes['Principled BSDF'].inputs['Alpha'])
    built = [_card("A", image), _card("B", image), leaf, _card("Inverted", image, transparent_first=False),
             _card("Other", other)]
    for i, mat in enumerate(built):
        ob = scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
        ob.data.uv_layers.new(name="UVMap")
    table = {m.name: m for m in exported().materials}
    a = table["A"].opacity
    assert table["B"].opacity is a and table["Leaf"].opacity is a        # one array for one image's alpha
    assert np.allclose(a[0, :, 0], [0.0, 0.25, 1.0])
    assert table["Inverted"].opacity is not a and np.allclose(table["Inverted"].opacity[0, :, 0], [1.0, 0.75, 0.0])
    assert table["Other"].opacity is not a and np.allclose(table["Other"].opacity[0, :, 0], [1.0, 0.5, 0.0])
