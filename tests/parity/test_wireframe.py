"""The Wireframe node (Size in world units) agrees with Cycles: 1 within Size / 2 of an edge of
the triangle hit (svm_wireframe), read per point. Four tilted 3x3 grids side by side, seen by an
orthographic camera (1-pixel box filter, 128 spp): the node into an Emission's Color, into a Mix
Shader's factor between two Emissions, into an Emission's Strength with its Size from a Math node,
and into a Diffuse BSDF's Color (through a Color Ramp) under a white world (no bounces). 4x4-pixel
blocks within 0.02 of Cycles' (lines cover pixels partly: each block a mean of 2048 samples; measured
0.004-0.007). The node had stood at the reading input's own value, said: blocks 0.28-0.85 off."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

KINDS = ('color', 'mix', 'strength', 'diffuse')
N = len(KINDS)


def _material(kind):
    mat, nt, _ = scenes._material(kind)     # (its output node: 'Material Output')
    out = nt.nodes['Material Output'].inputs['Surface']
    wire = nt.nodes.new('ShaderNodeWireframe')
    wire.use_pixel_size = False
    wire.inputs['Size'].default_value = 0.12
    if kind == 'color':
        em = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(wire.outputs[0], em.inputs['Color'])
        nt.links.new(em.outputs[0], out)
    elif kind == 'mix':
        a, b = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new('ShaderNodeEmission')
        a.inputs['Color'].default_value, b.inputs['Color'].default_value = (0.2, 0.5, 0.1, 1), (1, 0.3, 0.8, 1)
        mix = nt.nodes.new('ShaderNodeMixShader')
        nt.links.new(wire.outputs[0], mix.inputs['Fac'])
        nt.links.new(a.outputs[0], mix.inputs[1])
        nt.links.new(b.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out)
    elif kind == 'strength':
        size = nt.nodes.new('ShaderNodeMath')
        size.operation = 'MULTIPLY'
        size.inputs[0].default_value, size.inputs[1].default_value = 0.1, 2.0
        nt.links.new(size.outputs[0], wire.inputs['Size'])
        em = nt.nodes.new('ShaderNodeEmission')
        em.inputs['Color'].default_value = (0.9, 0.6, 0.2, 1)
        nt.links.new(wire.outputs[0], em.inputs['Strength'])
        nt.links.new(em.outputs[0], out)
    else:
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].color = (0.1, 0.2, 0.6, 1)
        ramp.color_ramp.elements[1].color = (0.9, 0.8, 0.3, 1)
        nt.links.new(wire.outputs[0], ramp.inputs[0])
        nt.links.new(ramp.outputs[0], d.inputs['Color'])
        nt.links.new(d.outputs[0], out)
    return mat


def test_wireframe_matches_cycles():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32 * N, 32
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0 * N)
    scenes.world((1.0, 1.0, 1.0), 1.0)
    for i, kind in enumerate(KINDS):
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=3, y_subdivisions=3, size=1.9,
                                        location=(-N + 1 + 2 * i, 0, 0), rotation=(0.3, -0.2, 0.4 + i))
        ob = bpy.context.active_object
        ob.data.materials.append(_material(kind))
    rendering.matched(sc, 128)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        img = scenes.render_rgba(sc)[..., :3]
        got[engine] = img.reshape(8, 4, 8 * N, 4, 3).mean(axis=(1, 3))
    diff = np.abs(got['DACRT'] - got['CYCLES'])
    for i, kind in enumerate(KINDS):
        part = diff[:, 8 * i:8 * i + 8]
        assert part.max() < 0.02, (kind, part.max(), got['DACRT'][:, 8 * i:8 * i + 8].mean(axis=(0, 1)),
                                    got['CYCLES'][:, 8 * i:8 * i + 8].mean(axis=(0, 1)))
    # the lines are there: each square's blocks differ by more than the tolerance in Cycles
    for i in range(N):
        assert np.ptp(got['CYCLES'][1:7, 8 * i + 1:8 * i + 7].max(axis=-1)) > 0.15, KINDS[i]
