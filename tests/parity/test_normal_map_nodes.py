"""A tangent-space normal map read through colour nodes, against Cycles: a DirectX-style map
(green channel pointing the other way) flipped back by Separate Color -> 1 - G -> Combine Color,
the common fix, or through RGB Curves. The left texel tilts the normal 45 degrees toward the
bitangent (+v), the right toward -v, under a sun from +y, so the halves differ by the tilt.
Such normal maps had been ignored (reported): both halves rendered as an untilted plane."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _flip_green(nt, tex):
    sep, comb = nt.nodes.new('ShaderNodeSeparateColor'), nt.nodes.new('ShaderNodeCombineColor')
    inv = nt.nodes.new('ShaderNodeMath')
    inv.operation = 'SUBTRACT'
    inv.inputs[0].default_value = 1.0
    nt.links.new(tex.outputs['Color'], sep.inputs['Color'])
    nt.links.new(sep.outputs['Red'], comb.inputs['Red'])
    nt.links.new(sep.outputs['Green'], inv.inputs[1])
    nt.links.new(inv.outputs[0], comb.inputs['Green'])
    nt.links.new(sep.outputs['Blue'], comb.inputs['Blue'])
    return comb.outputs['Color']


def _curves_flip_green(nt, tex):
    c = nt.nodes.new('ShaderNodeRGBCurve')
    g = c.mapping.curves[1]
    g.points[0].location, g.points[1].location = (0.0, 1.0), (1.0, 0.0)
    c.mapping.update()
    nt.links.new(tex.outputs['Color'], c.inputs['Color'])
    return c.outputs['Color']


@pytest.mark.parametrize('flip', [_flip_green, _curves_flip_green], ids=['separate_math_combine', 'rgb_curves'])
def test_directx_normal_map_flipped_by_nodes_matches_cycles(tmp_path, flip):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.2)
    # DirectX green: the left texel's +v tilt is stored as green 38 (OpenGL: 217)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "dx.png",
                                                  np.array([[[128, 38, 217], [128, 217, 217]]], np.uint8)))
    img.colorspace_settings.name = 'Non-Color'
    mat, nt, out = scenes._material("DX")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation, tex.extension = img, 'Closest', 'EXTEND'
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(flip(nt, tex), nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_plane_add(size=4.0)               # UVs: v along +y (the bitangent)
    bpy.context.active_object.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(-35.0), 0.0, 0.0)     # from +y, 35 degrees off vertical
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1) for e, exr in exrs.items()}
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    halves = [(slice(4, 28), slice(4, 28)), (slice(4, 28), slice(36, 60))]
    for r, k in halves:
        np.testing.assert_allclose(nrm['DACRT'][r, k].mean((0, 1)), nrm['CYCLES'][r, k].mean((0, 1)), atol=2e-3)
    dm = [img['DACRT'][r, k].mean() for r, k in halves]
    cm = [img['CYCLES'][r, k].mean() for r, k in halves]
    np.testing.assert_allclose(dm, cm, rtol=0.005)
    assert max(cm) > 1.3 * min(cm), "the halves must differ by their normals' tilt"
