"""A Principled BSDF's Metallic computed per point (a metallic map) weighs the metal and the
dielectric layers per point as Cycles' closures do (export/metallicmaps.py). It had been read at
its own value (said): a Checker between 0 and 1 on a cube rendered 1.07x Cycles. A smooth
sphere under a white world seen by an orthographic camera (every view angle, weighted by the
projected area, as principled.py averages the layers), direct light only: its colour at
Metallic 1 and at 0 (a line through its pixels against their metallic, which Cycles renders as an
emission) against Cycles'. (The whole sphere's mean alone could not tell per point from the map read at
its mean: the albedo is affine in Metallic.)"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _map(nt, kind):
    """The Metallic map's output socket: a Checker between 0 and 1, or an image on the UV map
    (4 x 4 texels of 0 and 1, Closest)."""
    if kind == 'checker':
        t = nt.nodes.new('ShaderNodeTexChecker')
        t.inputs['Scale'].default_value = 7.0
        return t.outputs['Fac']
    t = nt.nodes.new('ShaderNodeTexImage')
    px = np.zeros((4, 4, 4), np.float32)
    px[..., :3] = (np.indices((4, 4)).sum(0) % 2)[..., None]
    px[..., 3] = 1.0
    t.image, t.interpolation = scenes.float_image("metal", px), 'Closest'
    return t.outputs['Color']


def _region_means(img, metal):
    """{'metal': RGB, 'dielectric': RGB}: a render's pixels against their metallic (the map's
    emission render, `metal`, over the pixel's coverage), a line fitted by least squares weighed by
    coverage, read at 1 and at 0. (The albedo is affine in the metallic at each view angle, and
    the cells fall at every view angle alike, so the line holds each side's mean over every view
    angle as principled.py averages it; means over whole cells alone would leave out the rim,
    where the cells are thin and the reflection strongest.)"""
    img = img.reshape(-1, 4).astype(np.float64)
    m = metal.reshape(-1, 4).astype(np.float64)
    covered = m[:, 3] > 0.01
    alpha = m[covered, 3]
    share = m[covered, 0] / alpha
    assert (share > 0.99).sum() > 60 and (share < 0.01).sum() > 60, share
    design = np.stack([np.ones_like(share), share], axis=1) * np.sqrt(alpha)[:, None]
    target = img[covered, :3] / alpha[:, None] * np.sqrt(alpha)[:, None]
    (a, b), *_ = np.linalg.lstsq(design, target, rcond=None)
    return {'dielectric': a, 'metal': a + b}


def _sphere_means(kind, base_texture, said):
    """{engine: {region: mean RGB}} (_region_means, and 'sphere': the whole sphere's mean) of a
    sphere whose Principled (base (0.6, 0.3, 0.2) or a Checker of it and (0.2, 0.5, 0.7);
    roughness 0.4, the default specular layer) has its Metallic from `kind`'s map; said keeps
    DACRT's reports."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    mat, nt, out = scenes._material("Metal map")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.6, 0.3, 0.2, 1.0)
    p.inputs['Roughness'].default_value = 0.4
    if base_texture:
        b = nt.nodes.new('ShaderNodeTexChecker')
        b.inputs['Scale'].default_value = 3.0
        b.inputs['Color1'].default_value, b.inputs['Color2'].default_value = (0.6, 0.3, 0.2, 1), (0.2, 0.5, 0.7, 1)
        nt.links.new(b.outputs['Color'], p.inputs['Base Color'])
    metallic = _map(nt, kind)
    nt.links.new(metallic, p.inputs['Metallic'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=48, ring_count=24)     # (with a UV map)
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.05)
    scenes.world((1.0, 1.0, 1.0))
    rendering.matched(sc, 32)
    sc.render.film_transparent = True
    images = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        images[engine] = scenes.render_rgba(sc)
    # the map itself, where each pixel's metallic is 0 or 1 (Cycles, the emission of its value)
    glow = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(metallic, glow.inputs['Color'])
    nt.links.new(glow.outputs[0], out.inputs['Surface'])
    sc.render.engine = 'CYCLES'
    metal = scenes.render_rgba(sc)
    return {engine: {**_region_means(img, metal), 'sphere': _sphere_mean(img)} for engine, img in images.items()}


def _sphere_mean(img):
    """The whole sphere's mean RGB, premultiplied: the rim's pixels weigh by their coverage, so
    every view angle counts."""
    img = img.reshape(-1, 4).astype(np.float64)
    return img[:, :3].sum(axis=0) / img[:, 3].sum()


@pytest.mark.parametrize("kind,base_texture", [('checker', False), ('image', False), ('checker', True)])
def test_a_metallic_map_weighs_the_metal_per_point_as_cycles(kind, base_texture, said):
    means = _sphere_means(kind, base_texture, said)
    # (measured: within 0.9914-1.0072 of Cycles; the map read at its mean, 0.907-1.101, each
    # case failing by 2.2% or more on both sides)
    for region in ('metal', 'dielectric'):
        ratio = means['DACRT'][region] / means['CYCLES'][region]
        np.testing.assert_allclose(ratio, 1.0, atol=0.015, err_msg=f"{region}: {means}")
    # (and the whole sphere's mean, a tighter bound on the mean the sides weigh together)
    ratio = means['DACRT']['sphere'] / means['CYCLES']['sphere']
    np.testing.assert_allclose(ratio, 1.0, atol=0.01, err_msg=f"sphere: {means}")
    assert not [t for t in said if "Metallic driven by nodes" in t], said
    assert [t for t in said if "Metallic from" in t and "per point" in t], said
