"""Fresnel and Layer Weight (Fresnel, Facing) per shading point against Cycles: a Mix Shader's
factor, a Mix colour's factor and an emission's strength they feed vary with the angle between
the ray and the normal at each hit (svm_node_fresnel, svm_node_layer_weight), at camera and
bounce vertices, in light samples of the emitters they shape, and through the cut-out of a
Transparent side (export/procedurals.py compiles them; the integrator's hits carry their rays'
directions, viewside.Facing).

They had stood at their averages over view directions everywhere, said: the image mean came
close on a convex object seen whole (the average is the mean over its projected area), but the
picture did not (a sphere's red centre and white rim came out pink throughout: 79% of 4x4
blocks within Cycles' noise), and a bowl seen from inside (back faces: the IOR inverted,
total internal reflection at grazing views) came out 0.67x Cycles in green; a Fresnel rim glow
seen from inside 0.38x in blue; a Fresnel cut-out 0.86x in red, 1.15x in blue.
A smooth sphere over a grey floor under an area light or a sky-blue world, 4 seeds of 32
samples a side; per-channel means within 1% and Welch tests per pixel and per 4x4 block.
"""
import math

import bpy
import bmesh
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

SEEDS, SAMPLES, SIZE = 4, 32, 48


def _factor(nt, kind, value):
    """The view-dependent output kind ('fresnel', 'facing', 'layer fresnel') at IOR or Blend value."""
    if kind == 'fresnel':
        n = nt.nodes.new('ShaderNodeFresnel')
        n.inputs['IOR'].default_value = value
        return n, n.outputs['Fac']
    n = nt.nodes.new('ShaderNodeLayerWeight')
    n.inputs['Blend'].default_value = value
    return n, n.outputs['Facing' if kind == 'facing' else 'Fresnel']


def _material(kind, value, use):
    """A material whose `use` of the factor is: 'diffuses' a Mix Shader of a red and a white
    Diffuse; 'glow' of a red Diffuse and a blue Emission; 'strength' a 50% Mix Shader of a red
    Diffuse and an Emission of strength 8 x the factor; 'colour' a Diffuse whose colour a Mix
    node mixes; 'cutout' a Mix Shader of a white Transparent and a red Diffuse."""
    if use == 'colour':
        mat, nt, out = scenes._material("Viewed")
        diffuse = nt.nodes.new('ShaderNodeBsdfDiffuse')
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type = 'RGBA'
        mix.inputs['A'].default_value = (0.8, 0.05, 0.05, 1.0)
        mix.inputs['B'].default_value = (0.9, 0.9, 0.9, 1.0)
        nt.links.new(mix.outputs['Result'], diffuse.inputs['Color'])
        nt.links.new(diffuse.outputs[0], out.inputs['Surface'])
        node, socket = _factor(nt, kind, value)
        nt.links.new(socket, mix.inputs['Factor'])
        return mat, node
    second = {'diffuses': 'ShaderNodeBsdfDiffuse', 'cutout': 'ShaderNodeBsdfDiffuse'}.get(use, 'ShaderNodeEmission')
    first = 'ShaderNodeBsdfTransparent' if use == 'cutout' else 'ShaderNodeBsdfDiffuse'
    mat, nt, mix, a, b = scenes.mix_shader_material("Viewed", first, second)
    a.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1.0) if use == 'cutout' else (0.8, 0.05, 0.05, 1.0)
    b.inputs['Color'].default_value = {'diffuses': (0.9, 0.9, 0.9, 1.0), 'cutout': (0.9, 0.2, 0.1, 1.0)}.get(
        use, (0.2, 0.6, 1.0, 1.0))
    node, socket = _factor(nt, kind, value)
    if use == 'strength':
        times = nt.nodes.new('ShaderNodeMath')
        times.operation = 'MULTIPLY'
        times.inputs[1].default_value = 8.0
        nt.links.new(socket, times.inputs[0])
        nt.links.new(times.outputs[0], b.inputs['Strength'])
        mix.inputs['Fac'].default_value = 0.5
    else:
        if use == 'glow':
            b.inputs['Strength'].default_value = 3.0
        nt.links.new(socket, mix.inputs['Fac'])
    return mat, node


def _scene(kind, value, use='diffuses', light='area', smooth=True, bowl=False, normal=None):
    """The sphere (bowl: its half towards the camera removed, so the camera sees its inside, back
    faces) of the material over a grey floor; normal: a Geometry output into the node's Normal."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = SIZE
    scenes.camera(location=(0, -5, 0.5), rotation=(math.radians(84), 0, 0))
    mat, node = _material(kind, value, use)
    if normal is not None:
        geometry = mat.node_tree.nodes.new('ShaderNodeNewGeometry')
        mat.node_tree.links.new(geometry.outputs[normal], node.inputs['Normal'])
    sphere = scenes.uv_sphere(radius=1.0, segments=32, rings=16, smooth=smooth, materials=[mat])
    if bowl:
        bm = bmesh.new()
        bm.from_mesh(sphere.data)
        bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.y < -0.2], context='VERTS')
        bm.to_mesh(sphere.data)
        bm.free()
    scenes.plane("Floor", size=10, location=(0, 0, -1), materials=[scenes.diffuse("Grey", (0.5, 0.5, 0.5))])
    if light == 'area':
        scenes.black_world()
        bpy.ops.object.light_add(type='AREA', location=(2, -2, 3), rotation=(math.radians(40), math.radians(30), 0))
        lamp = bpy.context.active_object.data
        lamp.energy, lamp.size = 300.0, 2.0
    else:
        scenes.world((0.8, 0.9, 1.0), 1.0)
    sc.cycles.samples = sc.dacrt.samples = SAMPLES
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 3
    sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = 0
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc



CASES = {
    'facing 0.3, area light': dict(kind='facing', value=0.3),
    'facing 0.9, world': dict(kind='facing', value=0.9, light='world'),
    'layer fresnel 0.1, area light': dict(kind='layer fresnel', value=0.1),
    'layer fresnel 0.5, world, flat': dict(kind='layer fresnel', value=0.5, light='world', smooth=False),
    'fresnel 1.1, area light': dict(kind='fresnel', value=1.1),
    'fresnel 3, area light, flat': dict(kind='fresnel', value=3.0, smooth=False),
    'facing 0.5 of the true normal': dict(kind='facing', value=0.5, normal='True Normal'),
    'rim glow, facing 0.3': dict(kind='facing', value=0.3, use='glow'),
    'rim glow strength, facing 0.3': dict(kind='facing', value=0.3, use='strength'),
    'mix colour, fresnel 1.45, world': dict(kind='fresnel', value=1.45, use='colour', light='world'),
    'bowl inside, fresnel 1.45': dict(kind='fresnel', value=1.45, bowl=True),
    'bowl inside, layer fresnel 0.3, world': dict(kind='layer fresnel', value=0.3, light='world', bowl=True),
    'bowl inside, rim glow, fresnel 1.45': dict(kind='fresnel', value=1.45, use='glow', bowl=True),
    'cut-out, fresnel 1.45': dict(kind='fresnel', value=1.45, use='cutout'),
}


@pytest.mark.parametrize('case', list(CASES))
def test_view_dependent_factors_match_cycles_per_pixel(case, said):
    sc = _scene(**CASES[case])
    cycles, _ = rendering.assert_agrees(sc, SEEDS)
    assert cycles.mean() > 0.02
    text = ' '.join(said)
    assert "view-dependent" not in text and "own value" not in text, text
