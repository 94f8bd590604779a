"""Normal Map nodes that are not a tangent-space map of an image, against Cycles 5.0: a colour
from a procedural chain (a Noise texture, Object coordinates through Combine Color) in tangent
space, and any colour in object, world, Blender object and Blender world space (a direction;
Blender's spaces negate y and z), of strength 1 and 0.5, on an object rotated and scaled
unevenly (object space turns by the normal matrix), seen from the front and from behind (a
plane's back face negates the direction). The shading normals (the Normal pass) must match per
pixel, and the lit image. Such maps had been ignored (said): the object rendered unbent."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _noise(nt):
    n = nt.nodes.new('ShaderNodeTexNoise')
    n.inputs['Scale'].default_value = 1.5
    n.inputs['Detail'].default_value = 0.0
    return n.outputs['Color']


def _object_colour(nt):
    """(x, y, z) of Object coordinates mapped into 0..1 by a Mapping node and Combine Color:
    a direction that turns across the object."""
    tc, sep = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeSeparateXYZ')
    comb = nt.nodes.new('ShaderNodeCombineColor')
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.inputs['Scale'].default_value = (0.35, 0.35, 0.35)
    mp.inputs['Location'].default_value = (0.5, 0.5, 0.8)
    nt.links.new(tc.outputs['Object'], mp.inputs['Vector'])
    nt.links.new(mp.outputs['Vector'], sep.inputs['Vector'])
    for a, b in zip('XYZ', ('Red', 'Green', 'Blue')):
        nt.links.new(sep.outputs[a], comb.inputs[b])
    return comb.outputs['Color']


def _constant(nt):
    return None


def _fresnel_mix(nt):
    """Two colours mixed by a Fresnel: the view at each hit (its unbent normal) picks the direction."""
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    mix.inputs['A'].default_value = (0.5, 0.5, 1.0, 1.0)
    mix.inputs['B'].default_value = (0.95, 0.25, 0.6, 1.0)
    nt.links.new(nt.nodes.new('ShaderNodeFresnel').outputs['Fac'], mix.inputs['Factor'])
    return mix.outputs['Result']


def _geometry_normal(nt):
    """The shading normal as a colour (turned to the side the ray meets, as Cycles turns it)."""
    return nt.nodes.new('ShaderNodeNewGeometry').outputs['Normal']


CASES = [
    ('TANGENT', _noise, 1.0), ('TANGENT', _object_colour, 0.5),
    ('OBJECT', _object_colour, 1.0), ('OBJECT', _noise, 0.5), ('OBJECT', _constant, 1.0),
    ('WORLD', _object_colour, 1.0), ('WORLD', _constant, 0.5),
    ('BLENDER_OBJECT', _object_colour, 1.0), ('BLENDER_WORLD', _noise, 1.0),
    ('TANGENT', _fresnel_mix, 1.0), ('WORLD', _fresnel_mix, 0.8), ('WORLD', _geometry_normal, 0.7),
]


def _driven_strength(nt, socket):
    """Strength = 0.9 x Object x + 0.7 per point: from below 0 (clamped) to about 1.8."""
    tc, sep = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeSeparateXYZ')
    ma = nt.nodes.new('ShaderNodeMath')
    ma.operation = 'MULTIPLY_ADD'
    ma.inputs[1].default_value, ma.inputs[2].default_value = 0.9, 0.7
    nt.links.new(tc.outputs['Object'], sep.inputs['Vector'])
    nt.links.new(sep.outputs['X'], ma.inputs[0])
    nt.links.new(ma.outputs[0], socket)


DRIVEN = [('TANGENT', _noise), ('WORLD', _object_colour), ('OBJECT', _constant)]


@pytest.mark.parametrize('space,colour', DRIVEN, ids=[f"{s.lower()}-{c.__name__[1:]}" for s, c in DRIVEN])
def test_normal_map_strength_driven_by_nodes_matches_cycles(tmp_path, space, colour):
    """A Strength from a node chain, per point (it had been read at its own value, said)."""
    _render_and_compare(tmp_path, space, colour, _driven_strength)


@pytest.mark.parametrize('space,colour,strength', CASES,
                         ids=[f"{s.lower()}-{c.__name__[1:]}-{k}" for s, c, k in CASES])
def test_normal_map_space_and_colour_chain_matches_cycles(tmp_path, space, colour, strength):
    _render_and_compare(tmp_path, space, colour, strength)


def _render_and_compare(tmp_path, space, colour, strength):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 24
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=5.0)
    mat, nt, out = scenes._material("NM")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nmap.space = space
    if callable(strength):
        strength(nt, nmap.inputs['Strength'])
    else:
        nmap.inputs['Strength'].default_value = strength
    nmap.inputs['Color'].default_value = (0.75, 0.35, 0.7, 1.0)
    fed = colour(nt)
    if fed is not None:
        nt.links.new(fed, nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    # left: a sphere rotated and scaled unevenly; right: a plane turned to show its back
    # (Blender's primitives: they carry the UV map tangent space reads)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(-1.2, 0, 0), rotation=(0.4, 0.3, 0.9),
                                         scale=(1.0, 0.6, 0.9))
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(mat)
    bpy.ops.mesh.primitive_plane_add(size=1.8, location=(1.3, 0, 0), rotation=(math.pi - 0.3, 0.2, 0.5))
    bpy.context.active_object.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(30.0), math.radians(-20.0), 0.0)
    scenes.world((0.05, 0.05, 0.05))
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.render.film_transparent = True             # (alpha marks the objects' pixels)
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1) for e, exr in exrs.items()}
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    alpha = exrs['CYCLES'][f"{layer}.Combined.A"]
    inside = alpha > 0.999                       # (pixels wholly on an object: no edge mixing)
    assert 150 < inside.sum() < 0.8 * inside.size
    diff = np.abs(nrm['DACRT'] - nrm['CYCLES'])[inside]
    assert float(np.median(diff)) < 0.01 and float(np.percentile(diff, 95)) < 0.05, \
        (float(np.median(diff)), float(np.percentile(diff, 95)), float(diff.max()))
    dm, cm = img['DACRT'][inside].mean(axis=0), img['CYCLES'][inside].mean(axis=0)
    print(space, colour.__name__, getattr(strength, '__name__', strength), 'normals median/p95/max', float(np.median(diff)),
          float(np.percentile(diff, 95)), float(diff.max()), 'means', dm, cm)
    np.testing.assert_allclose(dm, cm, rtol=0.02, atol=2e-3)


def _curves_flip_green(nt, socket):
    c = nt.nodes.new('ShaderNodeRGBCurve')
    g = c.mapping.curves[1]
    g.points[0].location, g.points[1].location = (0.0, 1.0), (1.0, 0.0)
    c.mapping.update()
    nt.links.new(socket, c.inputs['Color'])
    return c.outputs['Color']


@pytest.mark.parametrize('space,through', [('OBJECT', False), ('BLENDER_WORLD', True)],
                         ids=['object-image', 'blender_world-image_through_curves'])
def test_object_and_world_space_image_normal_maps_match_cycles(tmp_path, space, through):
    """A baked object- or world-space normal map: an image of directions on the UV map (directly,
    or through RGB Curves), on a sphere rotated and scaled unevenly. It had been ignored."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 32
    scenes.camera(location=(0, 0, 6), kind='ORTHO', ortho_scale=2.6)
    rng = np.random.default_rng(5)
    d = rng.normal(size=(4, 4, 3)) + np.array([0.0, 0.0, 1.5])
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "os.png", np.round(
        (0.5 * d + 0.5) * 255).astype(np.uint8)))
    img.colorspace_settings.name = 'Non-Color'
    mat, nt, out = scenes._material("OS")
    bsdf = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = img, 'Linear'
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nmap.space = space
    nt.links.new(_curves_flip_green(nt, tex.outputs['Color']) if through else tex.outputs['Color'],
                 nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], bsdf.inputs['Normal'])
    nt.links.new(bsdf.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, rotation=(0.4, 0.3, 0.9), scale=(1.0, 0.6, 0.9))
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(30.0), math.radians(-20.0), 0.0)
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.render.film_transparent = True
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    inside = exrs['CYCLES'][f"{layer}.Combined.A"] > 0.999
    assert 150 < inside.sum() < 0.8 * inside.size
    diff = np.abs(nrm['DACRT'] - nrm['CYCLES'])[inside]
    print(space, through, float(np.median(diff)), float(np.percentile(diff, 95)), float(diff.max()))
    assert float(np.median(diff)) < 0.01 and float(np.percentile(diff, 95)) < 0.05, \
        (float(np.median(diff)), float(np.percentile(diff, 95)), float(diff.max()))
