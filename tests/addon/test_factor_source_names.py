"""A Mix Shader factor not weighed per point is said naming what computes it by kind
(texturedmixes.factor_source): from the textures the compile met (procedurals.Sources, kind and
name each), not from their names joined into one string and split back by a pattern. That
split broke an image whose name holds ', ' and a capital ('a, B'): "textures ('Checker
Texture', 'B'', image 'a)"."""
import bpy
import numpy as np
import pytest

from addon.export import procedurals
from addon.export.texturedmixes import factor_source
from tests.addon import scenes


@pytest.mark.parametrize('pairs, shown', [
    ([('image', 'tex.png')], "image 'tex.png'"),
    ([('image', None)], "Image Texture"),
    ([('procedural', 'Checker Texture')], "procedural texture 'Checker Texture'"),
    ([('procedural', 'Checker Texture'), ('procedural', 'Noise Texture')],
     "procedural textures 'Checker Texture', 'Noise Texture'"),
    ([('image', 'One'), ('image', 'Two')], "images 'One', 'Two'"),
    ([('procedural', 'Checker Texture'), ('image', 'One')], "textures ('Checker Texture', image 'One')"),
    ([('procedural', 'Checker Texture'), ('image', None)], "textures ('Checker Texture', Image Texture)"),
    ([('procedural', 'Checker Texture'), ('image', 'a, B')], "textures ('Checker Texture', image 'a, B')"),
    ([('image', 'a, B'), ('image', 'C')], "images 'a, B', 'C'"),
])
def test_factor_source_words_each_source_by_its_kind(pairs, shown):
    sources = procedurals.Sources(pairs + pairs)        # (each once, in the order met)
    assert factor_source(sources) == shown
    assert str(sources) == ', '.join(procedurals.source_name(*p) for p in pairs)


def test_an_image_name_with_a_comma_is_said_whole(scene, said):
    """Mix(Transparent, Transparent) by Checker x an image named 'a, B': the transparency is one
    colour per material, so the factor stands at its own value, said naming both sources."""
    mat, nt, out = scenes._material("M")
    mix, mul = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeMath')
    mul.operation = 'MULTIPLY'
    img = nt.nodes.new('ShaderNodeTexImage')
    img.image = scenes.float_image("a, B", np.full((4, 4, 4), 0.5, np.float32))
    nt.links.new(nt.nodes.new('ShaderNodeTexChecker').outputs['Fac'], mul.inputs[0])
    nt.links.new(img.outputs['Color'], mul.inputs[1])
    nt.links.new(mul.outputs[0], mix.inputs['Fac'])
    clear = [nt.nodes.new('ShaderNodeBsdfTransparent') for _ in range(2)]
    clear[1].inputs['Color'].default_value = (0.2, 0.2, 0.9, 1)
    nt.links.new(clear[0].outputs[0], mix.inputs[1])
    nt.links.new(clear[1].outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.plane("P", materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    scene.render.resolution_x = scene.render.resolution_y = 8
    scene.dacrt.samples = 1
    bpy.ops.render.render()
    text = next(t for t in said if "'M'" in t)
    assert "Mix Shader factor from textures ('Checker Texture', image 'a, B') not evaluated per point" in text, text
