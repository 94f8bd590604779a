"""Export speed, round 3: walks of a material's node graph the export did although their answer
could not change the result, now skipped. Each test checks the property (how often the heavy
step runs) and that the result is what the old way gave; no timing here (the numbers: the
commits)."""
import bpy
import numpy as np

from addon.export import procedurals
from addon.procedural import ProceduralTexels
from tests.addon import scenes


def _image(name, value):
    img = bpy.data.images.new(name, 4, 4, alpha=False, float_buffer=True)
    img.pixels.foreach_set(np.tile(np.array(value + (1.0,), np.float32), 16))
    return img


def _chain_material(name, noise=True, images=2):
    """Diffuse colour = Noise Color (or a constant) x Image 1 x Image 2 (Mix Multiply)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    if noise:
        last = nt.nodes.new('ShaderNodeTexNoise').outputs['Color']
    else:
        rgb = nt.nodes.new('ShaderNodeRGB')
        rgb.outputs[0].default_value = (0.7, 0.6, 0.5, 1.0)
        last = rgb.outputs[0]
    for k in range(images):
        t = nt.nodes.new('ShaderNodeTexImage')
        t.image = _image(f'{name}_img{k}', (0.9 - 0.2 * k, 0.5, 0.3 + 0.2 * k))
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
        mix.inputs['Factor'].default_value = 1.0
        nt.links.new(last, mix.inputs['A'])
        nt.links.new(t.outputs['Color'], mix.inputs['B'])
        last = mix.outputs['Result']
    nt.links.new(last, d.inputs['Color'])
    return mat


def _counted(monkeypatch):
    calls = []
    real = procedurals._images_reached

    def images_reached(socket):
        calls.append(socket)
        return real(socket)
    monkeypatch.setattr(procedurals, '_images_reached', images_reached)
    return calls


def _texture(data, name):
    return next(m for m in data.materials if m.name == name).texture


def test_a_procedural_chain_does_not_count_the_images_feeding_it(scene, exported, monkeypatch):
    """compile_socket counted the images of a chain (a walk of every link feeding the socket)
    only to decide whether a chain with no procedural texture is compiled: with a Noise in it,
    the count is not taken (1000 such materials spent 0.6 s in it), and the chain compiles
    as before: a per-point texture reading the noise and both images."""
    scenes.camera()
    scenes.cube("Cube", materials=(_chain_material("NoiseImages"),))
    calls = _counted(monkeypatch)
    tex = _texture(exported(), "NoiseImages")
    assert isinstance(tex, ProceduralTexels)
    assert 'Noise Texture' in tex.name
    assert calls == []


def test_a_chain_of_images_alone_still_counts_them(scene, exported, monkeypatch):
    """With no procedural texture, the count decides (two images: compiled per point), as before."""
    scenes.camera()
    scenes.cube("Cube", materials=(_chain_material("Images", noise=False),))
    calls = _counted(monkeypatch)
    tex = _texture(exported(), "Images")
    assert calls, "the image count of an image-only chain is still taken"
    assert isinstance(tex, ProceduralTexels)
