"""A Color Attribute or Attribute node naming a layer the mesh lacks, read through an AOV, an
Emission colour, a Mix Shader factor and a Diffuse BSDF's colour, against Cycles 5.0.1: every
Color, Vector and Fac reads 0, an Attribute node's Alpha 1 (svm_node_attr) and a Color
Attribute node's Alpha 0 (svm_node_vertex_color). DACRT had read both nodes' Alpha as 1 (one
key for both: an AOV of a Color Attribute's Alpha 1 where Cycles' is 0, fuzz seed 3013; its
Emission white, its Mix all the second shader, its Diffuse lit 0.955 where Cycles' is black).
Each node kind and output on its own plane, one row per reader."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

OUTPUTS = [('ca_color', 'ShaderNodeVertexColor', 'Color'), ('ca_alpha', 'ShaderNodeVertexColor', 'Alpha'),
           ('at_color', 'ShaderNodeAttribute', 'Color'), ('at_vector', 'ShaderNodeAttribute', 'Vector'),
           ('at_fac', 'ShaderNodeAttribute', 'Fac'), ('at_alpha', 'ShaderNodeAttribute', 'Alpha')]
READERS = ('aov', 'emission', 'mix', 'base_color')
W = 70


def _source(nt, kind, output, layer):
    node = nt.nodes.new(kind)
    if kind == 'ShaderNodeVertexColor':
        node.layer_name = layer
    else:
        node.attribute_name = layer
    return node.outputs[output]


def _reader(nt, out, reader, source, aov):
    if reader == 'aov':         # (the surface a grey emission: the AOV alone varies)
        e = nt.nodes.new('ShaderNodeEmission')
        e.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1)
        nt.links.new(e.outputs[0], out.inputs['Surface'])
        node = nt.nodes.new('ShaderNodeOutputAOV')
        node.aov_name = aov
        nt.links.new(source, node.inputs['Color'])
    elif reader == 'emission':
        e = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(source, e.inputs['Color'])
        nt.links.new(e.outputs[0], out.inputs['Surface'])
    elif reader == 'base_color':    # (lit by a sharp sun from above)
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(source, d.inputs['Color'])
        nt.links.new(d.outputs[0], out.inputs['Surface'])
    else:                       # red at factor 0, blue at 1
        red, blue = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new('ShaderNodeEmission')
        red.inputs['Color'].default_value, blue.inputs['Color'].default_value = (1, 0, 0, 1), (0, 0, 1, 1)
        mix = nt.nodes.new('ShaderNodeMixShader')
        nt.links.new(red.outputs[0], mix.inputs[1])
        nt.links.new(blue.outputs[0], mix.inputs[2])
        nt.links.new(source, mix.inputs['Fac'])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])


def _scene(layer):
    """Six columns (OUTPUTS) by four rows (READERS) of planes with no attribute at all, each
    material reading `layer` ('' the render colour attribute / an unnamed Attribute)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    vl = sc.view_layers[0]
    for i, (name, kind, output) in enumerate(OUTPUTS):
        for j, reader in enumerate(READERS):
            mat, nt, out = scenes._material(f"{name}_{reader}")
            _reader(nt, out, reader, _source(nt, kind, output, layer), name)
            # (the sun alone lights the Diffuse row: the emitting planes, coplanar, light
            # nothing, and sampled as lights they had made its 4 samples noisy, 0.945-0.978)
            mat.cycles.emission_sampling = 'NONE'
            scenes.plane(f"P{i}{j}", size=0.9, materials=[mat]).location = (i - 2.5, j - 1.5, 0)
        a = vl.aovs.add()
        a.name, a.type = name, 'COLOR'
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=7.0)
    scenes.black_world()
    scenes.light('SUN', 3.0)
    sc.render.resolution_x = sc.render.resolution_y = W
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    return sc


def _tiles(exr, layer_name):
    """{(output, reader): RGBA} at each plane's middle (4x4 pixels)."""
    got = {}
    for i, (name, _, _) in enumerate(OUTPUTS):
        x = int(W / 2 + (i - 2.5) * 10)
        for j, reader in enumerate(READERS):
            y = int(W / 2 + (j - 1.5) * 10)          # (the EXR's rows from the bottom)
            key = f"{layer_name}.{name}" if reader == 'aov' else f"{layer_name}.Combined"
            got[name, reader] = np.array([exr[f"{key}.{c}"][y - 2:y + 2, x - 2:x + 2].mean() for c in 'RGBA'])
    return got


@pytest.mark.parametrize('layer', ['missing', ''], ids=['named', 'render_colour'])
def test_missing_layer_reads_as_in_cycles(layer, tmp_path, said):
    sc = _scene(layer)
    exrs = scenes.render_engines(sc, tmp_path)
    c, d = (_tiles(exrs[e], sc.view_layers[0].name) for e in ('CYCLES', 'DACRT'))
    # Cycles' own, as measured: only an Attribute node's Alpha reads 1
    assert np.allclose(c['ca_alpha', 'aov'][:3], 0.0) and np.allclose(c['at_alpha', 'aov'][:3], 1.0)
    for key in c:
        np.testing.assert_allclose(d[key], c[key], atol=0.02, err_msg=str(key))
    # (an unnamed Attribute node reads 0 and is said so on its own)
    text = " | ".join(said)
    assert "alpha 0, as in Cycles" in text and ("alpha 1, as in Cycles" in text or not layer), text
