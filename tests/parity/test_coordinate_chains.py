"""Colour chains made of texture coordinates and colour/float nodes alone (no texture node: a
Separate XYZ of Generated into a Color Ramp, an Object coordinate through Math), evaluated per
shading point as procedural textures are (export/procedurals.compile_socket), against Cycles:
as a diffuse colour, an emission strength, a Mix Shader's factor and a Principled Alpha.

Before, such a chain was read at the coordinate's own value, (0, 0, 0) everywhere: a Generated
X ramp on a floor rendered 0.035x Cycles' mean, with "its own value used" said."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(name):
    """A factory-empty file and a new material (its node tree, its output)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    return scenes._material(name)


def _plane(mat, size=4.0):
    """A size x size plane of material mat seen straight down by an orthographic camera that
    frames it, 48 x 48 pixels, with a UV map over it (0..1, u along x); a black world."""
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.plane("Plane", size=size, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=size)
    scenes.black_world()
    return sc


def _columns(img, n=4, trim=2):
    """Mean colour of n vertical bands across x (left to right), trimmed at their edges."""
    w = img.shape[1] // n
    return np.array([img[:, i * w + trim:(i + 1) * w - trim].mean((0, 1)) for i in range(n)])


def _bands_agree(tmp_path, said, samples, rtol, atol):
    """Render with both engines (no bounces) and check DACRT's bands against Cycles' and that
    no node was read at its own value; Cycles' bands."""
    _settings(samples, 0)
    img = _rgb(tmp_path)
    dc, cc = _columns(img['DACRT']), _columns(img['CYCLES'])
    np.testing.assert_allclose(dc, cc, rtol=rtol, atol=atol)
    assert not any("own value" in t for t in said), said
    return cc


def _ramp(nt, stops):
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    els = ramp.color_ramp.elements
    els[0].position, els[0].color = stops[0]
    els[1].position, els[1].color = stops[1]
    return ramp


def _separate_x(nt, output='Generated'):
    tc, sep = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(tc.outputs[output], sep.inputs[0])
    return sep.outputs['X']


def test_generated_ramp_as_diffuse_colour(tmp_path, said):
    """Generated X -> Color Ramp (red to blue) -> Diffuse under a sun: four bands across the
    plane within 1.5% of Cycles' (they had all been the ramp's red end)."""
    mat, nt, out = _material("Ramp")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    ramp = _ramp(nt, [(0.0, (0.9, 0.1, 0.05, 1.0)), (1.0, (0.05, 0.2, 0.9, 1.0))])
    nt.links.new(_separate_x(nt), ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    _plane(mat)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0.0))
    cc = _bands_agree(tmp_path, said, 16, 0.015, 2e-3)
    assert cc[3, 2] > 2 * cc[0, 2], "the ramp should run red to blue across the plane"


def test_object_coordinate_emission_strength(tmp_path, said):
    """Emission Strength = 2 x (Object X + 2), a ramp of light across a 4 x 4 emitting plane:
    bands within 1% of Cycles' (they had been a flat strength of 4)."""
    mat, nt, out = _material("Glow")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (1.0, 0.6, 0.3, 1.0)
    nt.links.new(scenes.multiply_add(nt, _separate_x(nt, 'Object'), 2.0, 4.0), em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    _plane(mat)
    cc = _bands_agree(tmp_path, said, 4, 0.01, 1e-3)
    assert cc[3, 0] > 3 * cc[0, 0]


def test_uv_gradient_as_mix_shader_factor(tmp_path, said):
    """A Mix Shader between a red and a blue Diffuse whose factor is the UV map's U: bands within
    1.5% of Cycles' (the factor had been 0: all red)."""
    mat, nt, out = _material("MixUV")
    a, b = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    a.inputs['Color'].default_value = (0.8, 0.1, 0.1, 1.0)
    b.inputs['Color'].default_value = (0.1, 0.1, 0.8, 1.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(_separate_x(nt, 'UV'), mix.inputs['Fac'])
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    _plane(mat)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0.0))
    cc = _bands_agree(tmp_path, said, 16, 0.015, 2e-3)
    assert cc[3, 2] > 2 * cc[0, 2]


def test_generated_ramp_as_principled_alpha(tmp_path, said):
    """A Principled Alpha = Generated X through a constant Color Ramp (opaque on the right half),
    a white plate over a red floor: the plate's left half shows the floor as in Cycles (bands
    within 1.5%; the plate had been wholly see-through: Alpha read as the ramp at 0)."""
    mat, nt, out = _material("Cut")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.9, 0.9, 0.9, 1.0)
    p.inputs['Roughness'].default_value = 1.0
    p.inputs['IOR'].default_value = 1.0          # no specular layer: a diffuse plate
    ramp = _ramp(nt, [(0.0, (0.0, 0.0, 0.0, 1.0)), (0.5, (1.0, 1.0, 1.0, 1.0))])
    ramp.color_ramp.interpolation = 'CONSTANT'
    nt.links.new(_separate_x(nt), ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], p.inputs['Alpha'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    _plane(mat)
    scenes.plane("Floor", size=8.0, location=(0, 0, -0.5),
                 materials=(scenes.diffuse("Red", (0.8, 0.05, 0.05)),))
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0.0))
    cc = _bands_agree(tmp_path, said, 16, 0.015, 3e-3)
    assert cc[3, 1] > 3 * cc[0, 1], "the right half should be the white plate, the left the red floor"


def test_coordinate_factor_between_diffuse_and_emission(tmp_path, said):
    """A coordinate-only Mix Shader factor (Generated X) between a Diffuse and an Emission: the
    emission weighed per point (texturedmixes._procedural_mix), bands within 1.5% of Cycles'.
    It had fallen back to the factor's own value 0.5 (said), a flat half-bright plane."""
    mat, nt, out = _material("M")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (1.0, 0.5, 0.2, 1.0)
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(_separate_x(nt), mix.inputs['Fac'])
    nt.links.new(d.outputs[0], mix.inputs[1])
    nt.links.new(em.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    _plane(mat)
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0.0))
    cc = _bands_agree(tmp_path, said, 16, 0.015, 3e-3)
    assert not any("Mix Shader factor" in t for t in said), said
    assert cc[3, 0] / cc[3, 2] > 1.5 * cc[0, 0] / cc[0, 2]     # (red emission to the right)
