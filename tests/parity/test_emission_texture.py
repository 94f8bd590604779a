"""Emission from an image (a screen, a sign, a glTF emissive map) against Cycles: the emitter
seen by the camera shows the image, and what it lights follows the image's colours, in light
samples (the sample's point on the emitter reads the image) and in BSDF rays that meet it.

Before, such an emitter glowed with the image's average everywhere: the floor under a red half
and a blue half came out the same purple on both sides."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image(tmp_path):
    """A 2 x 1 8-bit sRGB image on disk: red on the left, blue on the right."""
    return bpy.data.images.load(scenes.write_image(tmp_path / "screen.png",
                                                   np.array([[[230, 40, 20], [20, 60, 240]]], np.uint8)))


@pytest.mark.parametrize('shader', ['EMISSION', 'PRINCIPLED'])
def test_image_emission_matches_cycles(shader, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera(location=(0, -7, 4), rotation=(np.radians(60), 0, 0))
    scenes.plane("Floor", size=8.0, materials=(scenes.diffuse("Floor", (0.8, 0.8, 0.8)),))
    mat, nt, out = scenes._material("Screen")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation, tex.extension = _image(tmp_path), 'Closest', 'EXTEND'
    if shader == 'EMISSION':
        node = nt.nodes.new('ShaderNodeEmission')
        node.inputs['Strength'].default_value = 3.0
        nt.links.new(tex.outputs['Color'], node.inputs['Color'])
    else:                                  # as a glTF import makes it: black base, emissive map
        node = nt.nodes.new('ShaderNodeBsdfPrincipled')
        node.inputs['Base Color'].default_value = (0, 0, 0, 1)
        node.inputs['Specular IOR Level'].default_value = 0.0
        node.inputs['Emission Strength'].default_value = 3.0
        nt.links.new(tex.outputs['Color'], node.inputs['Emission Color'])
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    screen = scenes.plane("Screen", size=3.0, location=(0, 1.5, 1.6), materials=(mat,))
    screen.rotation_euler = (np.radians(90), 0, 0)            # upright, facing the camera (-y)
    screen.data.uv_layers.new(name="UVMap")
    sc.cycles.samples = sc.dacrt.samples = 256
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.glossy_bounces = 0
    layer = sc.view_layers[0].name
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1)
           for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = img['DACRT'], img['CYCLES']
    rows = slice(0, 14)                     # the floor in front of the screen (row 0: bottom)
    for cols in (slice(4, 28), slice(36, 60)):                 # left (red) and right (blue) halves
        np.testing.assert_allclose(d[rows, cols].mean((0, 1)), c[rows, cols].mean((0, 1)), rtol=0.03)
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.01)
    left, right = c[rows, 4:28].mean((0, 1)), c[rows, 36:60].mean((0, 1))
    assert left[0] > 1.2 * right[0] and right[2] > 1.2 * left[2], "the floor must show the image's halves"


# (the chart's texels, the pixel columns of its first two, 32 pixels across)
_CHARTS = {'white-padded': ([[0, 255, 0], [255, 0, 0], [255, 255, 255], [255, 255, 255]], (slice(1, 7), slice(9, 15))),
           'negative-mean': ([[0, 255, 0], [90, 0, 90]], (slice(2, 14), slice(18, 30)))}


@pytest.mark.parametrize('chart', list(_CHARTS))
def test_wide_gamut_emission_keeps_its_negative_channels(tmp_path, chart):
    """An 8-bit Display P3 image as emission, seen straight on: its pure green and red texels
    lie outside Rec.709's gamut, so some of their channels are negative, and Cycles keeps them
    (emission is no closure weight). DACRT had set them to 0 per texel without a word: P3 green
    (0, 1.042, 0) where Cycles has (-0.225, 1.042, -0.079); under AgX its PNG red 113 of 255,
    Cycles' 14. Where a channel's average over the image is negative (P3 green beside a dark
    purple), that channel of every texel had been dropped: the purple's red 0, Cycles' 0.125."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 8
    texels, columns = _CHARTS[chart]
    chart = np.array([texels], np.uint8)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "chart.png", chart))
    img.colorspace_settings.name = 'Display P3'
    mat, nt, out = scenes._material("Chart")
    tex, em = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeEmission')
    tex.image, tex.interpolation = img, 'Closest'
    nt.links.new(tex.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    plane = scenes.plane("Chart", size=2.0, materials=(mat,))
    plane.scale = (2.0, 1.0, 1.0)
    plane.data.uv_layers.new(name="UVMap")
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    layer = sc.view_layers[0].name
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1)
           for e, exr in scenes.render_engines(sc, tmp_path).items()}
    for cols in columns:
        c, d = img['CYCLES'][2:6, cols].mean((0, 1)), img['DACRT'][2:6, cols].mean((0, 1))
        assert c.min() < -0.001, c                      # out of gamut: some channel negative
        np.testing.assert_allclose(d, c, atol=2e-3)
