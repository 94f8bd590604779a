"""Image Textures read on coordinates other than a UV map (Texture Coordinate Generated, Object
with or without an object, Normal) and projected Flat, Box (with Blend), Sphere or Tube, on a
rotated, non-uniformly scaled cube and sphere without UV maps (CAD and kit-bash imports),
against Cycles: as a diffuse colour, an emission, a Mix Shader's factor and a Principled Base
Color and Alpha (export/procedurals._image: looked up per point at what the Vector chain
computes, as Cycles' svm_node_tex_image / svm_node_tex_image_box).

Before, the image was read on the UV map ((0, 0) without one) and every projection as Flat,
said: blocks 0.13-0.41 and means 10-45% off Cycles (cube, Generated Box: 0.40)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')

_UNREAD = ("read as the UV map", "image projection as flat")


def _scene(shape, kind='DIFFUSE'):
    """A factory-empty file: a cube or a smooth UV sphere (its UV maps removed), rotated and
    scaled 1.2 x 0.8 x 1, seen in perspective under a sun, black world, 48 x 40 pixels; its
    material's shader of `kind` (Diffuse, Emission, Principled) and an Image Texture of a
    random 5 x 6 float RGBA image (alpha 0.2-1) on Linear. (node tree, shader, image node, obj)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 40
    mat, nt, out = scenes._material("Projected")
    sh = nt.nodes.new({'DIFFUSE': 'ShaderNodeBsdfDiffuse', 'EMISSION': 'ShaderNodeEmission',
                       'PRINCIPLED': 'ShaderNodeBsdfPrincipled'}[kind])
    if kind == 'PRINCIPLED':
        sh.inputs['Roughness'].default_value = 1.0
        sh.inputs['Specular IOR Level'].default_value = 0.0
    nt.links.new(sh.outputs[0], out.inputs['Surface'])
    px = np.random.RandomState(2).rand(5, 6, 4).astype(np.float32)
    px[..., 3] = 0.2 + 0.8 * px[..., 3]
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("T", px)
    tex.interpolation = 'Linear'
    if shape == 'cube':
        bpy.ops.mesh.primitive_cube_add(size=1.6)
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=32, ring_count=16)
        bpy.ops.object.shade_smooth()
    ob = bpy.context.object
    ob.data.materials.append(mat)
    while ob.data.uv_layers:
        ob.data.uv_layers.remove(ob.data.uv_layers[0])
    ob.rotation_euler, ob.scale = (0.3, 0.5, 0.7), (1.2, 0.8, 1.0)
    scenes.camera((4.5, -4.0, 3.5), (math.radians(62), 0, math.radians(48)), kind='PERSP')
    if kind != 'EMISSION':
        scenes.light('SUN', math.pi, rotation=(0.5, 0.3, 0.9))
    scenes.black_world()
    return nt, sh, tex, ob


def _coordinates(nt, tex, coord, empty=False):
    """Link Texture Coordinate `coord` (Object of a rotated, scaled, offset Empty: empty) into
    the image's Vector."""
    tc = nt.nodes.new('ShaderNodeTexCoord')
    if empty:
        e = bpy.data.objects.new("Frame", None)
        bpy.context.scene.collection.objects.link(e)
        e.location, e.rotation_euler, e.scale = (0.2, -0.3, 0.1), (0.4, 0.1, -0.3), (0.7, 0.7, 0.7)
        tc.object = e
    nt.links.new(tc.outputs[coord], tex.inputs['Vector'])


def _blocks(img, b=8):
    h, w = img.shape[:2]
    return img[:h // b * b, :w // b * b].reshape(b, h // b, b, w // b, 3).mean(axis=(1, 3))


def _agree(tmp_path, said, samples=16, atol=0.012):
    """Render both engines, direct light only: 8 x 8 block means and the whole mean agree with
    Cycles', and nothing about the image's coordinates is said."""
    _settings(samples, 0)
    img = _rgb(tmp_path)
    d, c = img['DACRT'], img['CYCLES']
    assert c.mean() > 0.01, "the object should be visible"
    np.testing.assert_allclose(_blocks(d), _blocks(c), atol=atol)
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02, atol=5e-4)
    assert not any(u in t for t in said for u in _UNREAD), said


@pytest.mark.parametrize('shape, coord, projection, blend, empty', [
    ('cube', 'Generated', 'BOX', 0.0, False),
    ('sphere', 'Generated', 'BOX', 0.3, False),
    ('sphere', 'Object', 'FLAT', 0.0, True),
    ('sphere', 'Normal', 'SPHERE', 0.0, False),
    ('cube', 'Object', 'TUBE', 0.0, False),
])
def test_diffuse_colour_on_coordinates(tmp_path, said, shape, coord, projection, blend, empty):
    """The image's colour into a Diffuse BSDF: block means within 0.012 of Cycles' (measured
    <= 0.01 at 16 spp; before 0.22-0.40, the image read at UV (0, 0) as one texel)."""
    nt, sh, tex, _ = _scene(shape)
    tex.projection, tex.projection_blend = projection, blend
    _coordinates(nt, tex, coord, empty)
    nt.links.new(tex.outputs['Color'], sh.inputs['Color'])
    _agree(tmp_path, said)


def test_emission_generated_box(tmp_path, said):
    """Emission colour from the image on Generated, Box with Blend 0.5, on the sphere: the seen
    emission agrees with Cycles' within 0.02 a block (its colours reach 1; before: one texel's
    colour all over)."""
    nt, sh, tex, _ = _scene('sphere', 'EMISSION')
    tex.projection, tex.projection_blend = 'BOX', 0.5
    _coordinates(nt, tex, 'Generated')
    nt.links.new(tex.outputs['Color'], sh.inputs['Color'])
    _agree(tmp_path, said, atol=0.02)


def test_mix_factor_from_alpha_on_object(tmp_path, said):
    """The image's Alpha (Object coordinates, Sphere projection) as the factor of a Mix Shader
    between a red and a blue Diffuse BSDF."""
    nt, sh, tex, _ = _scene('sphere')
    tex.projection = 'SPHERE'
    _coordinates(nt, tex, 'Object')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
    sh.inputs['Color'].default_value = (0.9, 0.1, 0.05, 1.0)
    blue = nt.nodes.new('ShaderNodeBsdfDiffuse')
    blue.inputs['Color'].default_value = (0.05, 0.2, 0.9, 1.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(tex.outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(sh.outputs[0], mix.inputs[1])
    nt.links.new(blue.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    _agree(tmp_path, said)


def test_principled_base_color_and_alpha_on_generated(tmp_path, said):
    """A Principled BSDF whose Base Color and Alpha come from one image on Generated, Box with
    Blend 0.2, on the cube in front of a lit white floor (the alpha shows it through)."""
    nt, sh, tex, ob = _scene('cube', 'PRINCIPLED')
    tex.projection, tex.projection_blend = 'BOX', 0.2
    _coordinates(nt, tex, 'Generated')
    nt.links.new(tex.outputs['Color'], sh.inputs['Base Color'])
    nt.links.new(tex.outputs['Alpha'], sh.inputs['Alpha'])
    white, wnt, wout = scenes._material("White")
    d = wnt.nodes.new('ShaderNodeBsdfDiffuse')
    wnt.links.new(d.outputs[0], wout.inputs['Surface'])
    scenes.plane("Floor", size=8.0, location=(0.0, 0.0, -1.6), materials=(white,))
    _agree(tmp_path, said, samples=64, atol=0.015)   # (stochastic cut-outs: 0.011 at 64 spp)


def test_cutout_from_alpha_on_generated_box(tmp_path, said):
    """A Mix Shader of a Transparent and a Diffuse BSDF by the image's Alpha (Generated, Box
    with Blend 0.4) on the sphere over a lit white floor: the cut-out per point (its shadow too)."""
    nt, sh, tex, _ = _scene('sphere')
    tex.projection, tex.projection_blend = 'BOX', 0.4
    _coordinates(nt, tex, 'Generated')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
    clear = nt.nodes.new('ShaderNodeBsdfTransparent')
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(tex.outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(clear.outputs[0], mix.inputs[1])
    nt.links.new(sh.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    white, wnt, wout = scenes._material("White")
    d = wnt.nodes.new('ShaderNodeBsdfDiffuse')
    wnt.links.new(d.outputs[0], wout.inputs['Surface'])
    scenes.plane("Floor", size=8.0, location=(0.0, 0.0, -1.2), materials=(white,))
    _agree(tmp_path, said, samples=128, atol=0.015)  # (stochastic cut-out: 0.004 at 256 spp)


def test_window_coordinates_match_cycles(tmp_path, said):
    """An image on Texture Coordinate Window (the hit projected to the camera's frame) into a
    Diffuse BSDF is looked up per point, as Camera is: block means within 0.012 of Cycles'. It
    had stayed on the UV map, said ("Window texture coordinates read as the UV map")."""
    nt, sh, tex, _ = _scene('cube')
    _coordinates(nt, tex, 'Window')
    nt.links.new(tex.outputs['Color'], sh.inputs['Color'])
    _agree(tmp_path, said)
    assert not any("Window" in t for t in said), said


def _two_image_diffuse_plane():
    """A 2x2 UV plane seen straight down (orthographic, 48 x 48) under a sun; its material two
    Diffuse BSDFs on two different 8-bit images (Closest), not yet combined: (node tree, output,
    first BSDF, second BSDF, second image node)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    mat, nt, out = scenes._material("TwoImages")
    rs = np.random.RandomState(22)
    bsdfs, nodes = [], []
    for name, shape in (("ma", (4, 5, 4)), ("mb", (3, 3, 4))):
        px = (rs.rand(*shape) * 255).astype(np.float32) / 255
        px[..., 3] = 1.0
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image, tex.interpolation = scenes.float_image(name, px), 'Closest'
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        nt.links.new(tex.outputs['Color'], d.inputs['Color'])
        bsdfs.append(d)
        nodes.append(tex)
    scenes.plane("Plane", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    scenes.light('SUN', math.pi)
    scenes.black_world()
    return nt, out, bsdfs[0], bsdfs[1], nodes[1]


@pytest.mark.parametrize('combine', ['mix', 'add', 'checker', 'image'])
def test_two_diffuse_bsdfs_on_different_images(tmp_path, said, combine):
    """A Mix Shader (factor 0.4, a Checker, the second image's colour) or an Add Shader of two
    Diffuse BSDFs on different images: both looked up per point, 8 x 8 blocks within 0.012 of
    Cycles' (before: the second image as its mean, "two image textures mixed", blocks 0.18-0.45
    off; the Checker and image factors at their own value, 0.25-0.54)."""
    nt, out, a, b, second = _two_image_diffuse_plane()
    mix = nt.nodes.new('ShaderNodeAddShader' if combine == 'add' else 'ShaderNodeMixShader')
    first = 0 if combine == 'add' else 1
    nt.links.new(a.outputs[0], mix.inputs[first])
    nt.links.new(b.outputs[0], mix.inputs[first + 1])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    if combine == 'mix':
        mix.inputs['Fac'].default_value = 0.4
    elif combine == 'checker':
        checker = nt.nodes.new('ShaderNodeTexChecker')
        checker.inputs['Scale'].default_value = 3.0
        nt.links.new(checker.outputs['Fac'], mix.inputs['Fac'])
    elif combine == 'image':
        nt.links.new(second.outputs['Color'], mix.inputs['Fac'])
    _settings(16, 0)
    img = _rgb(tmp_path)
    d, c = img['DACRT'], img['CYCLES']
    np.testing.assert_allclose(_blocks(d), _blocks(c), atol=0.012)
    assert not any("average colour" in t or "own value" in t for t in said), said


@pytest.mark.parametrize('colorspace', ['sRGB', 'Non-Color'])
def test_8bit_file_on_generated_box(tmp_path, said, colorspace):
    """An 8-bit PNG (held as its bytes, texture.ByteTexels) on Generated, Box with Blend 0.3,
    into a Diffuse colour: the per-point lookup decodes its bytes as the UV path does."""
    nt, sh, tex, _ = _scene('cube')
    px = (np.random.RandomState(5).rand(5, 6, 4) * 255).astype(np.uint8)
    px[..., 3] = 255
    tex.image = bpy.data.images.load(scenes.write_image(tmp_path / "t.png", px))
    tex.image.colorspace_settings.name = colorspace
    tex.projection, tex.projection_blend = 'BOX', 0.3
    _coordinates(nt, tex, 'Generated')
    nt.links.new(tex.outputs['Color'], sh.inputs['Color'])
    _agree(tmp_path, said)
