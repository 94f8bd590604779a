"""Rough diffuse (Diffuse BSDF Roughness, Principled Diffuse Roughness) in the Diffuse passes,
as Cycles writes them: Diffuse Color and Denoising Albedo hold the Oren-Nayar closure's colour
(its weight, film/data_passes.h), not the roughness-mapped albedo DACRT shades with, and
Diffuse Direct / Indirect are divided by that colour, so Color x (Direct + Indirect) is still
the diffuse light. A constant colour (Diffuse BSDF), an image's (Principled) and a Mix Shader
of a rough and a Lambertian Diffuse. Before, the colour was the albedo (0.966 x 0.9 on a white
wall at roughness 1) and Direct / Indirect 2-3 % high."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_light_passes import _blocks, light_and_passes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image_principled(name, roughness):
    """A Principled BSDF, no specular layer, diffuse roughness `roughness`, its Base Color a
    2 x 2 float image of two colours (Closest)."""
    px = np.zeros((2, 2, 4), np.float32)
    px[..., 3] = 1.0
    px[0, 0, :3] = px[1, 1, :3] = (0.9, 0.7, 0.2)
    px[0, 1, :3] = px[1, 0, :3] = (0.3, 0.5, 0.8)
    mat = scenes.principled(name, (1.0, 1.0, 1.0))
    nt = mat.node_tree
    bsdf = next(n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED')
    bsdf.inputs['Diffuse Roughness'].default_value = roughness
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image(name + 'Image', px)
    tex.interpolation = 'Closest'
    nt.links.new(tex.outputs['Color'], bsdf.inputs['Base Color'])
    return mat


def _mixed(name):
    """Mix Shader 0.5 of a Diffuse of roughness 1 and a Lambertian one."""
    mat, nt, mix, a, b = scenes.mix_shader_material(name, 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfDiffuse')
    a.inputs['Color'].default_value = (0.3, 0.8, 0.5, 1.0)
    a.inputs['Roughness'].default_value = 1.0
    b.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    return mat


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 30
    scenes.camera(location=(0, -6, 2.0), rotation=(math.radians(90), 0, 0), kind='PERSP')
    scenes.plane(size=4, location=(0, 0, 0), materials=[scenes.diffuse("Floor", (0.9, 0.6, 0.3), roughness=1.0)])
    back = scenes.plane(size=4, location=(0, 2, 2), materials=[_image_principled("Back", 0.7)])
    back.rotation_euler = (math.radians(90), 0, 0)
    wall = scenes.plane(size=4, location=(-2, 0, 2), materials=[_mixed("Wall")])
    wall.rotation_euler = (0, math.radians(90), 0)
    light_and_passes(sc, 128)
    sc.view_layers[0].cycles.denoising_store_passes = True
    return sc


def test_rough_diffuse_passes_match_cycles(tmp_path):
    """Diffuse Color and Denoising Albedo per 10 x 10 block within 1 % of the level (they are
    the closure colours, noise only at edges). Diffuse Direct + Indirect on the back wall, seen
    head-on (where the view-averaged Oren-Nayar albedo is close to Cycles' response) within
    2.5 % of Cycles' per channel; and DACRT's Combined is still Color x (Direct + Indirect) (+ Environment at the edges)."""
    sc = _scene()
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name

    def get(o, p):
        return np.stack([o[f"{name}.{p}.{ch}"] for ch in 'RGB'], -1).astype(np.float64)
    for p in ('Diffuse Color', 'Denoising Albedo'):
        c, d = get(out['CYCLES'], p), get(out['DACRT'], p)
        level = float(c.mean(axis=(0, 1)).max())
        assert level > 0.3
        assert np.abs(_blocks(d) - _blocks(c)).max() < 0.01 * level, \
            (p, np.abs(_blocks(d) - _blocks(c)).max() / level)
    c_light, d_light = (get(out[e], 'Diffuse Direct') + get(out[e], 'Diffuse Indirect') for e in ('CYCLES', 'DACRT'))
    wall = (slice(10, 20), slice(10, 30))           # the image-textured back wall
    # the light passes differ from Cycles' as Combined does (the view-averaged Oren-Nayar
    # albedo), no more: divided by the same colour
    light = d_light[wall].mean(axis=(0, 1)) / c_light[wall].mean(axis=(0, 1))
    shade = get(out['DACRT'], 'Combined')[wall].mean(axis=(0, 1)) / get(out['CYCLES'], 'Combined')[wall].mean(axis=(0, 1))
    assert np.allclose(light, shade, rtol=0.01), (light, shade)
    colour = get(out['DACRT'], 'Diffuse Color')
    lit = (colour > 0.2).all(axis=-1)
    assert lit.mean() > 0.6
    combined = get(out['DACRT'], 'Combined')
    env = get(out['DACRT'], 'Environment')
    assert np.allclose((colour * d_light + env)[lit], combined[lit], rtol=1e-3, atol=1e-4)
