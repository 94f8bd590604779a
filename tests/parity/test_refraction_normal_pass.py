"""A Refraction BSDF's Normal input bends the Normal pass as Cycles' refraction closure's
normal (maybe_ensure_valid_specular_reflection of the bent normal, svm/closure.h), while its
light still passes unbent (said): the Combined image is the same with the map as without it.
An ico sphere seen from the side under a World-space Normal Map of a constant colour or a
Noise's Bump. Before, the map was dropped for the pass too: 0.65 mean per-pixel difference from
Cycles' Normal pass (0.45 under the Bump), 0.011 now (0.033), as a Diffuse BSDF's."""

import os

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .normalpass import normal_pass_diff, normal_pass_scene, world_normal_map

pytestmark = pytest.mark.usefixtures('parity_addon')


def _refraction(mapped):
    """A Refraction BSDF material; mapped: 'map' (a World Normal Map), 'bump' (a Noise's Bump) or ''."""
    mat = bpy.data.materials.new('Refraction')
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    bsdf = nt.nodes.new('ShaderNodeBsdfRefraction')
    bsdf.inputs['Color'].default_value = (0.6, 0.5, 0.4, 1.0)
    if mapped == 'map':
        nt.links.new(world_normal_map(nt).outputs['Normal'], bsdf.inputs['Normal'])
    elif mapped == 'bump':
        bump = nt.nodes.new('ShaderNodeBump')
        bump.inputs['Distance'].default_value = 4.0
        noise = nt.nodes.new('ShaderNodeTexNoise')
        noise.inputs['Scale'].default_value = 2.0
        nt.links.new(noise.outputs['Fac'], bump.inputs['Height'])
        nt.links.new(bump.outputs['Normal'], bsdf.inputs['Normal'])
    nt.links.new(bsdf.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('mapped', ['map', 'bump'])
def test_refraction_normal_map_bends_the_normal_pass_as_cycles(tmp_path, mapped):
    sc = normal_pass_scene()
    diff = normal_pass_diff(tmp_path, sc, _refraction(mapped))
    # (a Diffuse BSDF's under the same map: 0.008 and 0.3%; under the same Bump: 0.036 and 3%)
    bound = 0.02 if mapped == 'map' else 0.05
    assert diff.mean() < bound and (diff > 0.1).mean() < 0.04, (diff.mean(), (diff > 0.1).mean())


@pytest.mark.parametrize('mapped', ['map', 'bump'])
def test_refraction_normal_map_leaves_the_image_unbent(tmp_path, mapped):
    images = []
    for kind in ('', mapped):
        sc = normal_pass_scene()
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=1.5, location=(0, 0, 1))
        bpy.context.object.data.materials.append(_refraction(kind))
        scenes.plane('Floor', size=40, location=(0, 0, -1), materials=[scenes.diffuse('D', (0.5, 0.5, 0.5))])
        scenes.world((0.3, 0.3, 0.3), 1.0)
        sc.render.engine = 'DACRT'
        sc.dacrt.samples = 16
        ch = scenes.read_exr(scenes.render_exr(os.path.join(tmp_path, f'{kind or "unbent"}.exr'), sc))
        images.append(np.stack([ch[c] for c in 'RGB'], -1))
    assert images[0].mean() > 0.05
    assert np.array_equal(images[0], images[1])
