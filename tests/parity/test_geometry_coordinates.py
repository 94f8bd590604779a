"""The Geometry node's Position, Normal and True Normal and Texture Coordinate's Normal read per
shading point in compiled colour chains (export/procedurals.py, integrator._coordinates), against
Cycles: a "snow on top" Normal Z ramp on a smooth and a flat sphere, a Position Z height gradient
over a floor and cubes, True Normal on a smooth sphere (its facets), the object-space normal of a
rotated cube, an emission strength from Position X, and a double-sided plane seen from above and
from below (Cycles turns N and Ng to face the ray: Normal Z is -1 seen from below).

Before, each read the node's own value, (0, 0, 0), said as "value from 'Geometry' node; its own
value used" (a flat colour: the ramp at 0)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(name):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    return scenes._material(name)


def _ramp(nt, stops):
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    els = ramp.color_ramp.elements
    els[0].position, els[0].color = stops[0]
    els[1].position, els[1].color = stops[1]
    return ramp


def _component(nt, socket, axis):
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(socket, sep.inputs[0])
    return sep.outputs[axis]


def _emit(nt, out, color=None, strength=None):
    em = nt.nodes.new('ShaderNodeEmission')
    if color is not None:
        nt.links.new(color, em.inputs['Color'])
    if strength is not None:
        nt.links.new(strength, em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return em


def _side_camera(size=48, scale=2.4):
    """An orthographic camera on -Y looking at the origin (image rows run along Z)."""
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = size
    scenes.camera((0, -6, 0), (math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=scale)
    scenes.black_world()
    return sc


def _blocks_agree(tmp_path, said, samples, bounces, rtol, atol):
    """Render with both engines, check DACRT's 4 x 4 block means against Cycles' and that no
    node was read at its own value; (DACRT's, Cycles' blocks)."""
    _settings(samples, bounces)
    img = _rgb(tmp_path)
    d, c = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    np.testing.assert_allclose(d, c, rtol=rtol, atol=atol)
    assert not any("own value" in t for t in said), said
    return d, c


def _blocks(img, n=4, trim=1):
    """Mean colour of n x n blocks (rows bottom to top, then columns), trimmed at their edges."""
    h, w = img.shape[0] // n, img.shape[1] // n
    return np.array([[img[i * h + trim:(i + 1) * h - trim, j * w + trim:(j + 1) * w - trim].mean((0, 1))
                      for j in range(n)] for i in range(n)])


def _normal_ramp_material(output='Normal'):
    """Geometry <output> Z -> Color Ramp (rock brown at -1..0.2, snow white at 0.7) -> emission."""
    mat, nt, out = _material("Snow")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMapRange')          # Z in -1..1 -> 0..1
    m.inputs['From Min'].default_value = -1.0
    nt.links.new(_component(nt, geo.outputs[output], 'Z'), m.inputs['Value'])
    ramp = _ramp(nt, [(0.6, (0.25, 0.12, 0.05, 1.0)), (0.85, (0.9, 0.95, 1.0, 1.0))])
    nt.links.new(m.outputs['Result'], ramp.inputs['Fac'])
    _emit(nt, out, color=ramp.outputs['Color'])
    return mat


@pytest.mark.parametrize('smooth', [True, False], ids=['smooth', 'flat'])
def test_normal_z_ramp_on_a_sphere(tmp_path, said, smooth):
    """Geometry Normal Z -> Map Range -> Color Ramp (rock to snow) emitted by a UV sphere (16 x 8,
    smooth or flat shaded) seen from the side: 4 x 4 blocks within 1.5% of Cycles' (they had
    all been the ramp's rock end)."""
    mat = _normal_ramp_material()
    scenes.uv_sphere("Ball", 1.0, segments=16, rings=8, smooth=smooth, materials=(mat,))
    _side_camera()
    d, c = _blocks_agree(tmp_path, said, 64, 0, 0.015, 3e-3)
    assert c[3, 1:3, 2].mean() > 2 * c[1, 1:3, 2].mean(), "snow on top, rock below"


def test_true_normal_on_a_smooth_sphere(tmp_path, said):
    """Geometry True Normal Z through the same ramp on a smooth-shaded sphere: the facets'
    normals (not the smooth ones), blocks within 1.5% of Cycles'."""
    mat = _normal_ramp_material('True Normal')
    scenes.uv_sphere("Ball", 1.0, segments=12, rings=6, smooth=True, materials=(mat,))
    _side_camera()
    d, c = _blocks_agree(tmp_path, said, 64, 0, 0.015, 3e-3)


def test_position_z_gradient_on_floor_and_cubes(tmp_path, said):
    """A height gradient: Geometry Position Z -> Map Range (0..2) -> Color Ramp (green to white)
    as the Diffuse colour of a floor and two cubes (one raised) under a sun, seen in
    perspective: 4 x 4 blocks within 2% of Cycles'."""
    mat, nt, out = _material("Height")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMapRange')
    m.inputs['From Max'].default_value = 2.0
    nt.links.new(_component(nt, geo.outputs['Position'], 'Z'), m.inputs['Value'])
    ramp = _ramp(nt, [(0.0, (0.1, 0.5, 0.1, 1.0)), (1.0, (0.95, 0.95, 0.95, 1.0))])
    nt.links.new(m.outputs['Result'], ramp.inputs['Fac'])
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Floor", 8.0, materials=(mat,))
    scenes.cube("Low", 1.0, location=(-1.2, 0.5, 0.5), materials=(mat,))
    scenes.cube("High", 1.0, location=(1.2, 0.0, 1.5), materials=(mat,))
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera((0, -7, 4), (math.radians(62), 0, 0))
    scenes.black_world()
    scenes.light('SUN', 3.0, rotation=(0.5, 0.3, 0.0))
    dd, cc = _blocks_agree(tmp_path, said, 16, 0, 0.02, 4e-3)


def test_object_normal_of_a_rotated_cube(tmp_path, said):
    """Texture Coordinate Normal x 0.5 + 0.5 emitted by a cube rotated (0.5, 0.3, 0.8) rad:
    its faces show their object-space normals (the rotation undone), blocks within 1.5% of
    Cycles' (the world normal would differ by far more)."""
    mat, nt, out = _material("ObjN")
    tc = nt.nodes.new('ShaderNodeTexCoord')
    vm = nt.nodes.new('ShaderNodeVectorMath')
    vm.operation = 'MULTIPLY_ADD'
    vm.inputs[1].default_value = (0.5, 0.5, 0.5)
    vm.inputs[2].default_value = (0.5, 0.5, 0.5)
    nt.links.new(tc.outputs['Normal'], vm.inputs[0])
    _emit(nt, out, color=vm.outputs['Vector'])
    ob = scenes.cube("Box", 1.4, materials=(mat,))
    ob.rotation_euler = (0.5, 0.3, 0.8)
    _side_camera(scale=2.6)
    d, c = _blocks_agree(tmp_path, said, 64, 0, 0.015, 3e-3)


@pytest.mark.parametrize('x0', [1.0, 50.0], ids=['near', 'far'])
def test_emission_strength_from_position(tmp_path, said, x0):
    """Emission Strength = Position X + 4 - x0 on a 4 x 4 plane moved to x = x0 (world space: 2 ..
    6 across it, where the object's X would give 2 - x0 .. 6 - x0); at x0 = 50 the render
    recentres the scene (sceneprep.recentred), which Position undoes: columns within 1% of
    Cycles'."""
    mat, nt, out = _material("Glow")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMath')
    m.inputs[1].default_value = 4.0 - x0
    nt.links.new(_component(nt, geo.outputs['Position'], 'X'), m.inputs[0])
    em = _emit(nt, out, strength=m.outputs[0])
    em.inputs['Color'].default_value = (0.3, 0.2, 0.1, 1.0)
    scenes.plane("Plane", 4.0, location=(x0, 0.0, 0.0), materials=(mat,))
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera((x0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    _settings(64, 0)
    img = _rgb(tmp_path)
    d, c = _blocks(img['DACRT'])[1:3].mean(0), _blocks(img['CYCLES'])[1:3].mean(0)
    np.testing.assert_allclose(d, c, rtol=0.01, atol=1e-3)
    assert c[3, 0] > 2 * c[0, 0]
    assert not any("own value" in t for t in said), said


@pytest.mark.parametrize('output', ['Normal', 'True Normal'])
def test_double_sided_plane_from_both_sides(tmp_path, said, output):
    """An emitting plane (normal +Z) whose red is (Geometry <output> Z) x 0.5 + 0.5, seen from
    above and from below: Cycles turns N and Ng to face the ray (its shader setup negates them
    on a back face), so red is 1 from above and 0 from below (measured); the same here, both
    sides' means within 1% of Cycles' (the winding normal alone gave 1 below)."""
    mat, nt, out = _material("Sides")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value = m.inputs[2].default_value = 0.5
    nt.links.new(_component(nt, geo.outputs[output], 'Z'), m.inputs[0])
    comb = nt.nodes.new('ShaderNodeCombineXYZ')
    nt.links.new(m.outputs[0], comb.inputs['X'])
    comb.inputs['Y'].default_value = 0.2
    _emit(nt, out, color=comb.outputs['Vector'])
    scenes.plane("Plane", 4.0, materials=(mat,))
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    cam = scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=3.0)
    scenes.black_world()
    _settings(2, 0)
    means = {}
    for side, (loc, rot) in {'above': ((0, 0, 5), (0, 0, 0)), 'below': ((0, 0, -5), (math.pi, 0, 0))}.items():
        cam.location, cam.rotation_euler = loc, rot
        img = _rgb(tmp_path / side)
        means[side] = {e: img[e].mean((0, 1)) for e in img}
        np.testing.assert_allclose(means[side]['DACRT'], means[side]['CYCLES'], rtol=0.01, atol=1e-3,
                                   err_msg=side)
    assert means['above']['CYCLES'][0] > 0.9 and means['below']['CYCLES'][0] < 0.1, means
    assert not any("own value" in t for t in said), said


def _normal_color_material(socket_of):
    """Emission of (a normal) x 0.5 + 0.5; socket_of(nt) gives the normal's socket."""
    mat, nt, out = _material("NormalColour")
    vm = nt.nodes.new('ShaderNodeVectorMath')
    vm.operation = 'MULTIPLY_ADD'
    vm.inputs[1].default_value = (0.5, 0.5, 0.5)
    vm.inputs[2].default_value = (0.5, 0.5, 0.5)
    nt.links.new(socket_of(nt), vm.inputs[0])
    _emit(nt, out, color=vm.outputs['Vector'])
    return mat


@pytest.mark.parametrize('output', ['texcoord', 'geometry'])
def test_normals_of_a_scaled_and_mirrored_smooth_sphere(tmp_path, said, output):
    """The normal as a colour on a smooth sphere scaled (1.6, 0.7, -1.0) (non-uniform and
    mirrored) and turned: Texture Coordinate Normal (Cycles: the world N turned back by the
    object's transform and normalized; here the object-space corner normals interpolated and
    normalized) and Geometry Normal (world), blocks within 1.5% of Cycles'."""
    if output == 'texcoord':
        mat = _normal_color_material(lambda nt: nt.nodes.new('ShaderNodeTexCoord').outputs['Normal'])
    else:
        mat = _normal_color_material(lambda nt: nt.nodes.new('ShaderNodeNewGeometry').outputs['Normal'])
    ob = scenes.uv_sphere("Ball", 1.0, segments=24, rings=12, smooth=True, materials=(mat,))
    ob.scale, ob.rotation_euler = (1.6, 0.7, -1.0), (0.3, 0.0, 0.5)
    _side_camera(scale=3.6)
    d, c = _blocks_agree(tmp_path, said, 64, 0, 0.015, 3e-3)


def test_geometry_normal_under_a_normal_map(tmp_path, said):
    """A Diffuse whose Normal is a Normal Map (a constant tilt toward +X, its Z 0.8) and whose
    Color is Geometry Normal Z mapped from 0.6..1 through a red-to-blue ramp, on a plane under a
    sun: Cycles' Geometry Normal is the surface's N (Z = 1: blue), not the mapped normal the BSDF
    reads (Z 0.8: the ramp's middle), and so here (the chain is read before the normal map bends
    the normal): blocks within 1.5% of Cycles'."""
    mat, nt, out = _material("Tilted")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tilt = np.array([0.5 + 0.5 * 0.6, 0.5, 0.5 + 0.5 * 0.8, 1.0], np.float32)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Tilt", np.tile(tilt, (4, 4, 1)))
    tex.image.colorspace_settings.name = 'Non-Color'
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMapRange')
    m.inputs['From Min'].default_value = 0.6
    nt.links.new(_component(nt, geo.outputs['Normal'], 'Z'), m.inputs['Value'])
    ramp = _ramp(nt, [(0.0, (0.9, 0.1, 0.1, 1.0)), (1.0, (0.1, 0.1, 0.9, 1.0))])
    nt.links.new(m.outputs['Result'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    plane = scenes.plane("Plane", 4.0, materials=(mat,))
    plane.data.uv_layers.new(name="UVMap")
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    scenes.light('SUN', 3.0, rotation=(0.0, 0.6, 0.0))
    dd, cc = _blocks_agree(tmp_path, said, 16, 0, 0.015, 2e-3)
    assert cc[..., 2].mean() > 5 * cc[..., 0].mean(), "the ramp's blue end: N unbent"


def test_emitter_lit_from_its_back_by_normal(tmp_path, said):
    """A 1.5 x 1.5 emitter 1 above a floor, facing up, whose Strength is 4 x (0.5 - Normal Z / 2):
    dark seen from its front (above), 4 from its back, which faces the floor: the floor is lit
    by the back (Cycles turns N to each ray: light samples from the floor see -Z), blocks within
    3% of Cycles' brightest."""
    mat, nt, out = _material("Under")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = -2.0, 2.0
    nt.links.new(_component(nt, geo.outputs['Normal'], 'Z'), m.inputs[0])
    _emit(nt, out, strength=m.outputs[0])
    scenes.plane("Lamp", 1.5, location=(0, 0, 1.0), materials=(mat,))
    scenes.plane("Floor", 8.0, materials=(scenes.diffuse("Grey", (0.8, 0.8, 0.8)),))
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, -6, 2.5), (math.radians(70), 0, 0))
    scenes.black_world()
    _settings(128, 1)
    img = _rgb(tmp_path)
    dd, cc = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    np.testing.assert_allclose(dd, cc, rtol=0, atol=0.03 * cc.max())
    np.testing.assert_allclose(dd.mean(), cc.mean(), rtol=0.02)
    assert not any("own value" in t for t in said), said


def test_snow_mix_into_principled_and_mix_shader(tmp_path, said):
    """Studio forms of "snow on top" on a smooth sphere under a sun: Normal Z -> Color Ramp as
    the factor of a Mix (colour) of rock and snow into a Principled Base Color (left sphere), and
    True Normal Z -> Map Range as a Mix Shader's factor between a rock and a snow Diffuse (right
    sphere): 4 x 4 blocks within 2% of Cycles' brightest."""
    mat, nt, out = _material("SnowMix")
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    ramp = _ramp(nt, [(0.3, (0.0, 0.0, 0.0, 1.0)), (0.6, (1.0, 1.0, 1.0, 1.0))])
    nt.links.new(_component(nt, geo.outputs['Normal'], 'Z'), ramp.inputs['Fac'])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    mix.inputs['A'].default_value = (0.25, 0.12, 0.05, 1.0)
    mix.inputs['B'].default_value = (0.9, 0.92, 0.95, 1.0)
    nt.links.new(ramp.outputs['Color'], mix.inputs['Factor'])
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Roughness'].default_value = 1.0
    p.inputs['IOR'].default_value = 1.0
    nt.links.new(mix.outputs['Result'], p.inputs['Base Color'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    mat2, nt2, out2 = scenes._material("SnowShader")
    geo2 = nt2.nodes.new('ShaderNodeNewGeometry')
    m = nt2.nodes.new('ShaderNodeMapRange')
    m.inputs['From Min'].default_value = 0.2
    m.inputs['From Max'].default_value = 0.7
    nt2.links.new(_component(nt2, geo2.outputs['True Normal'], 'Z'), m.inputs['Value'])
    rock, snow = nt2.nodes.new('ShaderNodeBsdfDiffuse'), nt2.nodes.new('ShaderNodeBsdfDiffuse')
    rock.inputs['Color'].default_value = (0.25, 0.12, 0.05, 1.0)
    snow.inputs['Color'].default_value = (0.9, 0.92, 0.95, 1.0)
    ms = nt2.nodes.new('ShaderNodeMixShader')
    nt2.links.new(m.outputs['Result'], ms.inputs['Fac'])
    nt2.links.new(rock.outputs[0], ms.inputs[1])
    nt2.links.new(snow.outputs[0], ms.inputs[2])
    nt2.links.new(ms.outputs[0], out2.inputs['Surface'])
    scenes.uv_sphere("Left", 1.0, segments=24, rings=12, location=(-1.1, 0, 0), materials=(mat,))
    scenes.uv_sphere("Right", 1.0, segments=24, rings=12, location=(1.1, 0, 0), materials=(mat2,))
    _side_camera(scale=4.6)
    scenes.light('SUN', 3.0, rotation=(0.6, 0.0, 0.3))
    _settings(64, 0)
    img = _rgb(tmp_path)
    d, c = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    np.testing.assert_allclose(d, c, rtol=0, atol=0.02 * c.max())
    np.testing.assert_allclose(d.mean(), c.mean(), rtol=0.01)
    assert not any("own value" in t for t in said), said
