"""A rough diffuse (Cycles' improved Oren-Nayar with OpenPBR's energy-preserving multiple
scattering) as the view-dependent BSDF Cycles renders, not its albedo averaged over views
(addon/roughdiffuse.py, native/cpp/orennayar.h): a plane seen by an orthographic camera at
several view angles, lit by a sharp sun (with the sun behind the viewer and facing it), by a
point lamp and by a uniform world, at roughness 0.5 and 1, colours 0.8 and 0.3, a textured
colour and a Mix Shader weight. Each case's image mean within 2 % of Cycles per channel.
Before: the averaged albedo, 0.33-7.7x Cycles under the sun (0.60x behind and 2.09x facing at
45 degrees, roughness 1)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 6


def _material(kind, roughness, colour):
    """'plain': a Diffuse BSDF of the colour; 'texture': its colour a Closest image of two
    texels (colour and 0.3); 'mix': a Mix Shader 0.7 of it and a Transparent BSDF;
    'principled': a Principled BSDF of that Diffuse Roughness without a specular layer."""
    if kind == 'principled':
        mat = scenes.principled("Rough", colour, specular=0.0)
        bsdf = next(n for n in mat.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
        bsdf.inputs['Diffuse Roughness'].default_value = roughness
        return mat
    mat, nt, out = scenes._material("Rough")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (*colour, 1.0)
    d.inputs['Roughness'].default_value = roughness
    node = d
    if kind == 'texture':
        px = np.ones((1, 2, 4), np.float32)
        px[0, 0, :3], px[0, 1, :3] = colour, (0.3, 0.3, 0.3)
        tex = nt.nodes.new('ShaderNodeTexImage')
        tex.image = scenes.float_image("Texels", px)
        tex.interpolation = 'Closest'
        nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    elif kind == 'mix':
        mix = nt.nodes.new('ShaderNodeMixShader')
        mix.inputs['Fac'].default_value = 0.3
        nt.links.new(d.outputs[0], mix.inputs[1])
        nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0], mix.inputs[2])
        node = mix
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def build(view, light, roughness, colour, kind='plain', samples=4):
    """The plane (UV-mapped, 40 x 40) seen from `view` degrees above it (from -Y), lit by
    light: ('sun', elevation, +1 behind the viewer / -1 facing it), ('point', z), ('area', z)
    or ('world',)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    e = math.radians(view)
    scenes.camera((0, -10 * math.cos(e), 10 * math.sin(e)), (math.pi / 2 - e, 0, 0), kind='ORTHO', ortho_scale=0.5)
    plane = scenes.plane("Plane", size=40.0, materials=(_material(kind, roughness, colour),))
    plane.data.uv_layers.new(name="UVMap")
    if light[0] == 'sun':
        s = math.radians(light[1])
        scenes.light('SUN', 2.0, rotation=(light[2] * (math.pi / 2 - s), 0, 0), angle=0.0)
        scenes.black_world()
    elif light[0] == 'point':
        scenes.light('POINT', 300.0, location=(0, 0.5, light[1]), shadow_soft_size=0.0)
        scenes.black_world()
    elif light[0] == 'area':
        scenes.light('AREA', 300.0, location=(0, 1.0, light[1]), rotation=(-0.5, 0, 0), size=1.0)
        scenes.black_world()
    else:
        scenes.world((1.0, 1.0, 1.0), 1.0)
    sc.render.resolution_x = sc.render.resolution_y = RES
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    return sc


def ratio(tmp_path, *args, **kw):
    """DACRT's image mean over Cycles' per channel (3,), and Cycles' mean."""
    build(*args, **kw)
    means = {}
    for engine in ('DACRT', 'CYCLES'):
        bpy.context.scene.render.engine = engine
        r = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr"))
        means[engine] = np.array([r[c].mean() for c in 'RGB'], np.float64)
    return means['DACRT'] / means['CYCLES'], means['CYCLES']


SUN = [(view, (sun, side), rough, col)
       for view, sun, side in ((90, 45, 1), (45, 45, 1), (45, 45, -1), (20, 30, 1), (20, 30, -1), (45, 70, -1))
       for rough, col in ((1.0, 0.8), (0.5, 0.3))] + \
      [(45, (20, 1), 1.0, 0.3), (45, (20, -1), 0.5, 0.8)]


@pytest.mark.parametrize('view, sun, rough, col', SUN)
def test_rough_diffuse_under_a_sun_matches_cycles(view, sun, rough, col, tmp_path):
    r, level = ratio(tmp_path, view, ('sun', *sun), rough, (col, col, col))
    assert level.min() > 0.02
    assert np.abs(r - 1.0).max() < 0.02, r


@pytest.mark.parametrize('kind', ['texture', 'mix', 'principled'])
def test_rough_diffuse_textured_and_mixed_under_a_sun(kind, tmp_path):
    """A texture's colour per texel (its nonlinear multiple scattering from each texel's colour),
    a Mix Shader's weight (the colour is the closure's over the weight) and a Principled BSDF's
    rough base with no layer over it."""
    r, _ = ratio(tmp_path, 30, ('sun', 35, -1), 1.0, (0.9, 0.6, 0.2), kind)
    assert np.abs(r - 1.0).max() < 0.02, r


@pytest.mark.parametrize('lamp', ['point', 'area'])
def test_rough_diffuse_under_a_lamp(lamp, tmp_path):
    """A point lamp, and an area lamp (its samples drawn by lanes)."""
    r, _ = ratio(tmp_path, 35, (lamp, 1.5), 1.0, (0.8, 0.5, 0.3), samples=64 if lamp == 'area' else 16)
    assert np.abs(r - 1.0).max() < 0.02, r


def test_rough_diffuse_under_a_world(tmp_path):
    """Under a uniform world the light comes by the bounce (BSDF rays), so the bounce takes the
    factor: seen from 20 degrees (the averaged albedo was 1.6-3 % dark there)."""
    r, _ = ratio(tmp_path, 20, ('world',), 1.0, (0.8, 0.5, 0.3), samples=256)
    assert np.abs(r - 1.0).max() < 0.02, r


def test_what_is_said(said, tmp_path):
    """Rendered as Cycles' BSDF, a rough Diffuse is not reported; mixed with a Lambertian one
    (two colours, one BSDF factor each) it keeps its averaged albedo and says so."""
    build(45, ('sun', 45, 1), 1.0, (0.8, 0.8, 0.8))
    bpy.context.scene.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "plain.exr")
    assert not any("Oren-Nayar" in t for t in said), said
    mat, nt, mix, a, b = scenes.mix_shader_material("Mixed", 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfDiffuse')
    a.inputs['Roughness'].default_value = 1.0
    bpy.data.objects["Plane"].data.materials[0] = mat
    scenes.render_exr(tmp_path / "mixed.exr")
    text = next(t for t in said if "Oren-Nayar" in t)
    assert "mixed with another reflection" in text and "averaged over view directions" in text, text
    # a Principled's rough base under its specular layer: averaged, said
    said.clear()
    layered = scenes.principled("Layered", (0.8, 0.8, 0.8), specular=0.5)
    next(n for n in layered.node_tree.nodes if n.type == 'BSDF_PRINCIPLED').inputs['Diffuse Roughness'] \
        .default_value = 1.0
    bpy.data.objects["Plane"].data.materials[0] = layered
    scenes.render_exr(tmp_path / "layered.exr")
    text = next(t for t in said if "Oren-Nayar" in t)
    assert "under the specular" in text and "averaged over view directions" in text, text
