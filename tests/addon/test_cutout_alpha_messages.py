"""A cut-out whose alpha nodes compute from one image (export/cutouts.py _evaluated_alpha) is
evaluated per texel, then blended; Cycles blends, then runs the nodes. That is exact when the
chain is affine in what it reads (a grey Non-Color opacity map's colour, read as its luminance;
an image's Alpha x 0.7; a Mix Shader factor from a mask image) and the colour it reads is
blended as linear texels: nothing is said then. It had been reported "alpha from nodes on image
... evaluated per texel before the blend (... cut-out edges one texel soft)" for every such
asset, though the render equals Cycles' (leaf cards over a red ground: (0.4732, 0.1896,
0.0594) Cycles, (0.4733, 0.1896, 0.0594) DACRT, 8-px blocks within 0.0029). Where the chain
is no affine map (a Greater Than or a Constant Color Ramp on the alpha) or the mask is an 8-bit
sRGB image's colour (blended encoded, then decoded), it is still said."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

NOTE = "evaluated per texel before the blend"


def _images(tmp_path):
    """(an RGBA leaf whose alpha is a soft disc, its alpha as a grey RGB mask file)."""
    yy, xx = (np.mgrid[0:16, 0:16] + 0.5) / 16
    alpha = np.clip((0.45 - np.hypot(xx - 0.5, yy - 0.5)) / 0.1, 0, 1)
    leaf = np.stack([0.3 + 0.5 * xx, 0.6 + 0 * xx, 0.2 + 0 * xx, alpha], -1)
    leaf_path = scenes.write_image(tmp_path / "leaf.png", (leaf * 255).round().astype(np.uint8))
    mask_path = scenes.write_image(tmp_path / "mask.png", (np.stack([alpha] * 3, -1) * 255).round().astype(np.uint8))
    return leaf_path, mask_path


def _principled(name):
    mat, nt, out = scenes._material(name)
    b = nt.nodes.new('ShaderNodeBsdfPrincipled')
    nt.links.new(b.outputs[0], out.inputs['Surface'])
    return mat, nt, b, out


def _image_node(nt, path, colorspace='sRGB'):
    t = nt.nodes.new('ShaderNodeTexImage')
    t.image = bpy.data.images.load(str(path), check_existing=True)
    t.image.colorspace_settings.name = colorspace
    return t


def _opacity_map(tmp_path):
    mat, nt, b, _ = _principled("OpacityMap")
    nt.links.new(_image_node(nt, _images(tmp_path)[1], 'Non-Color').outputs['Color'], b.inputs['Alpha'])
    return mat


def _alpha_times(tmp_path):
    mat, nt, b, _ = _principled("AlphaTimes")
    t = _image_node(nt, _images(tmp_path)[0])
    m = nt.nodes.new('ShaderNodeMath')
    m.operation, m.inputs[1].default_value = 'MULTIPLY', 0.7
    nt.links.new(t.outputs['Color'], b.inputs['Base Color'])
    nt.links.new(t.outputs['Alpha'], m.inputs[0])
    nt.links.new(m.outputs[0], b.inputs['Alpha'])
    return mat


def _mix_by_mask(tmp_path):
    """Mix Shader (Transparent, Principled) whose factor is a Non-Color mask's colour."""
    mat, nt, b, out = _principled("MixByMask")
    mix = nt.nodes.new('ShaderNodeMixShader')
    clear = nt.nodes.new('ShaderNodeBsdfTransparent')
    nt.links.new(_image_node(nt, _images(tmp_path)[1], 'Non-Color').outputs['Color'], mix.inputs['Fac'])
    nt.links.new(clear.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def _greater_than(tmp_path):
    mat, nt, b, _ = _principled("GreaterThan")
    t = _image_node(nt, _images(tmp_path)[0])
    m = nt.nodes.new('ShaderNodeMath')
    m.operation, m.inputs[1].default_value = 'GREATER_THAN', 0.5
    nt.links.new(t.outputs['Alpha'], m.inputs[0])
    nt.links.new(m.outputs[0], b.inputs['Alpha'])
    return mat


def _constant_ramp(tmp_path):
    mat, nt, b, _ = _principled("ConstantRamp")
    t = _image_node(nt, _images(tmp_path)[0])
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.interpolation = 'CONSTANT'
    ramp.color_ramp.elements[1].position = 0.5
    nt.links.new(t.outputs['Alpha'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], b.inputs['Alpha'])
    return mat


def _srgb_mask(tmp_path):
    """The grey mask's colour into Alpha, the image left sRGB: Cycles blends its bytes encoded."""
    mat, nt, b, _ = _principled("SrgbMask")
    nt.links.new(_image_node(nt, _images(tmp_path)[1], 'sRGB').outputs['Color'], b.inputs['Alpha'])
    return mat


def _said(exported, mat):
    scenes.camera()
    scenes.plane("Card", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    return [t for _, t in exported().messages if NOTE in t]


@pytest.mark.parametrize('make', [_opacity_map, _alpha_times, _mix_by_mask], ids=lambda f: f.__name__.strip('_'))
def test_affine_alpha_chain_is_not_reported(scene, exported, tmp_path, make):
    assert _said(exported, make(tmp_path)) == []


@pytest.mark.parametrize('make', [_greater_than, _constant_ramp, _srgb_mask], ids=lambda f: f.__name__.strip('_'))
def test_alpha_chain_that_does_not_commute_with_the_blend_is_reported(scene, exported, tmp_path, make):
    assert len(_said(exported, make(tmp_path))) == 1


def test_closest_lookup_is_not_reported(scene, exported, tmp_path):
    """'Closest' blends nothing: a Greater Than on its alpha is exact."""
    mat = _greater_than(tmp_path)
    next(n for n in mat.node_tree.nodes if n.type == 'TEX_IMAGE').interpolation = 'Closest'
    assert _said(exported, mat) == []
