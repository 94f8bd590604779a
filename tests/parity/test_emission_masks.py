"""Emission masks against Cycles: a Mix Shader between a Diffuse and an Emission (a glow on a
sign, lava cracks) or between two Emissions whose factor a texture computes (an image on UV or
on Generated coordinates, its Alpha, a Checker). The factor weighs each side's emission at the
shading point as Cycles' Mix Shader does (export/texturedmixes._procedural_mix), composed with a
side's own per-point emission; the emitter lights the floor per point too.

Before, such a factor stood at the node's own value 0.5 (said): every variant rendered the same
image, the emitter's red 0.97 where Cycles' is 0.72 (image on UV, 1.36x), 32 of 48 blocks off."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .rendering import matched

pytestmark = pytest.mark.usefixtures('parity_addon')


def _mask_image(tmp_path):
    """A 4 x 4 8-bit RGBA image of unrelated colour and alpha per texel (a mask)."""
    rng = np.random.default_rng(3)
    px = rng.integers(0, 256, (4, 4, 4)).astype(np.uint8)
    px[..., 3] = rng.permutation(np.repeat([0, 60, 200, 255], 4)).reshape(4, 4)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "mask.png", px))
    img.alpha_mode = 'STRAIGHT'
    return img


def _factor(nt, kind, tmp_path):
    """The output a factor of `kind` reads."""
    if kind == 'checker':
        tc, t = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexChecker')
        t.inputs['Scale'].default_value = 3.0
        nt.links.new(tc.outputs['Generated'], t.inputs['Vector'])
        return t.outputs['Fac']
    t = nt.nodes.new('ShaderNodeTexImage')
    t.image, t.interpolation = _mask_image(tmp_path), 'Closest'
    if kind == 'image_generated':
        tc = nt.nodes.new('ShaderNodeTexCoord')
        nt.links.new(tc.outputs['Generated'], t.inputs['Vector'])
    return t.outputs['Alpha' if kind == 'image_alpha' else 'Color']


def _emission(nt, color, strength=3.0):
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Color'].default_value = color
    e.inputs['Strength'].default_value = strength
    return e


def _mask_material(kind, tmp_path):
    mat, nt, out = scenes._material("Mask")
    mix = nt.nodes.new('ShaderNodeMixShader')
    fac = 'checker' if kind in ('emission_pair', 'textured_emission') else kind
    fac = 'image_uv' if kind == 'textured_emission' else fac
    nt.links.new(_factor(nt, fac, tmp_path), mix.inputs['Fac'])
    if kind == 'emission_pair':           # Mix(Emission, Emission): two glows
        first = _emission(nt, (0.1, 0.3, 1.0, 1.0), 2.0)
    else:
        first = nt.nodes.new('ShaderNodeBsdfDiffuse')
        first.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1.0)
    second = _emission(nt, (1.0, 0.6, 0.2, 1.0))
    if kind == 'textured_emission':       # the emission's own colour per point (a Checker)
        tc, ch = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexChecker')
        ch.inputs['Scale'].default_value = 5.0
        ch.inputs['Color1'].default_value, ch.inputs['Color2'].default_value = (1, 0.2, 0, 1), (0, 0.5, 1, 1)
        nt.links.new(tc.outputs['Generated'], ch.inputs['Vector'])
        nt.links.new(ch.outputs['Color'], second.inputs['Color'])
    nt.links.new(first.outputs[0], mix.inputs[1])
    nt.links.new(second.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def _blocks(img, k=8):
    h, w, c = img.shape
    return img[:h // k * k, :w // k * k].reshape(h // k, k, w // k, k, c).mean((1, 3))


@pytest.mark.parametrize('kind', ['image_uv', 'image_generated', 'image_alpha', 'checker', 'emission_pair',
                                  'textured_emission'])
def test_emission_mask_matches_cycles(kind, tmp_path, said):
    """An upright mask plane over a grey floor under a sun: 8 px block means of the whole image
    (the mask seen by the camera, the floor it lights) within 3% (+0.01) of Cycles', the image
    mean within 1%, and nothing said about the Mix Shader factor."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera(location=(0, -7, 4), rotation=(np.radians(60), 0, 0))
    scenes.plane("Floor", size=8.0, materials=(scenes.diffuse("Floor", (0.8, 0.8, 0.8)),))
    sign = scenes.plane("Sign", size=3.0, location=(0, 1.5, 1.6), materials=(_mask_material(kind, tmp_path),))
    sign.rotation_euler = (np.radians(90), 0, 0)            # upright, facing the camera (-y)
    sign.data.uv_layers.new(name="UVMap")
    scenes.light('SUN', 2.0, rotation=(0.6, 0.3, 0.0))
    scenes.black_world()
    matched(sc, 128, bounces=1)
    sc.cycles.diffuse_bounces = 1
    sc.cycles.glossy_bounces = 0
    layer = sc.view_layers[0].name
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1)
           for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = img['DACRT'], img['CYCLES']
    np.testing.assert_allclose(_blocks(d), _blocks(c), rtol=0.03, atol=0.01)
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.01)
    assert not any("Mix Shader factor" in t for t in said), said
    # the mask shows: the sign's blocks are not one flat half-glow
    sign_blocks = _blocks(c)[2:5, 2:6, 0]
    assert sign_blocks.max() > 1.3 * sign_blocks.min(), sign_blocks


def _said_for(tmp_path, said, first, second, kind):
    """DACRT's reports for a Mix Shader of node types first and second by a factor of `kind`
    on a tiny plane (no Cycles render: the message is the subject)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, out = scenes._material("M")
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(_factor(nt, kind, tmp_path), mix.inputs['Fac'])
    a, b = nt.nodes.new(first), nt.nodes.new(second)
    a.inputs['Color'].default_value, b.inputs['Color'].default_value = (0.9, 0.2, 0.2, 1), (0.2, 0.2, 0.9, 1)
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.plane("P", materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 8
    sc.render.engine, sc.dacrt.samples = 'DACRT', 1
    bpy.ops.render.render()
    return next(t for t in said if "'M'" in t)


@pytest.mark.parametrize('first, second, kind, what', [
    ('ShaderNodeBsdfTransparent', 'ShaderNodeBsdfTransparent', 'checker', "a transparent part is one colour"),
    ('ShaderNodeBsdfTransparent', 'ShaderNodeBsdfTransparent', 'image_uv', "a transparent part is one colour"),
    ('ShaderNodeBsdfTransparent', 'ShaderNodeBsdfTransparent', 'image_generated', "a transparent part is one colour")])
def test_a_factor_not_weighed_per_point_says_what_stands_at_a_constant(first, second, kind, what, tmp_path, said):
    """Where the surface holds one value per material (a Transparent's colour beside another
    transparent side; a Translucent BSDF's is weighed per point: test_translucent_masks.py),
    the factor stands at its own value for both shaders: said once, naming the factor's source
    (an image as an image) and why. It had said "procedural textures ('image 'mask.png'')" and
    then the factor again ("not computed (an image)"), without saying what was read at a
    constant."""
    text = _said_for(tmp_path, said, first, second, kind)
    source = "procedural texture 'Checker Texture'" if kind == 'checker' else "image 'mask.png'"
    assert f"Mix Shader factor from {source} not evaluated per point ({what}" in text, text
    assert "its own value 0.5 weighs both shaders" in text, text
    assert text.count("Mix Shader factor") == 1 and "procedural textures" not in text, text
