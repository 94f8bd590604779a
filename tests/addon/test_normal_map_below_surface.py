"""A normal map that bends the normal below the surface (texels of tangent-space z < 0, as the
OBJ importer makes of a map_Bump height image: a grey image wired into a Normal Map) is said,
once, naming the materials, when the light tree is on and the material has no transmission:
Cycles' light tree weighs lights by the unbent normal and never samples a light wholly behind
it, so the back of such a surface lit from the front stays dark in Cycles where DACRT lights it
(the realscenes hunt: a plane's back under a sun in front, image mean 0.3946 vs Cycles 0.1827,
2.16x; a point light 1.64x, an emissive quad 2.06x; Light Tree off: both 0.3946). Before, it
was not said. A proper normal map (z > 0 everywhere), Light Tree off, or a translucent material
(Cycles' tree then counts the back hemisphere too) say nothing."""
import math

import bpy
import numpy as np
import pytest

from . import scenes

SAID = "normal map bends normals below the surface"


def _normal_mapped(name, blue, translucent=False):
    """A Principled BSDF whose Normal is a tangent-space Normal Map of a 4 x 4 image of
    (0.5, 0.5, blue) in its left half and (0.5, 0.5, 1) in its right (a stripe of blue < 0.5
    points into the surface); with translucent, mixed half and half with a Translucent BSDF."""
    px = np.ones((4, 4, 4), np.float32)
    px[..., :2] = 0.5
    px[:, :2, 2] = blue
    img = scenes.float_image(name + "_img", px)
    img.colorspace_settings.name = 'Non-Color'
    mat, nt, out = scenes._material(name)
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    nm = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(tex.outputs['Color'], nm.inputs['Color'])
    nt.links.new(nm.outputs['Normal'], p.inputs['Normal'])
    shader = p.outputs[0]
    if translucent:
        mix = nt.nodes.new('ShaderNodeMixShader')
        tr = nt.nodes.new('ShaderNodeBsdfTranslucent')
        nt.links.new(p.outputs[0], mix.inputs[1])
        nt.links.new(tr.outputs[0], mix.inputs[2])
        shader = mix.outputs[0]
    nt.links.new(shader, out.inputs['Surface'])
    return mat


def _scene(materials, light_tree=True):
    sc = bpy.context.scene
    for i, mat in enumerate(materials):
        ob = scenes.plane(f"P{i}", location=(2.5 * i, 0, 0), materials=[mat])
        ob.rotation_euler = (math.radians(90), 0, 0)
    scenes.camera((0, 6, 0), (math.radians(90), 0, math.radians(180)))   # behind the planes
    scenes.light('SUN', 3.0, rotation=(math.radians(50), 0, math.radians(20)))   # on their front
    sc.dacrt.use_light_tree = light_tree
    return sc


def _said(data):
    return [m for _, m in data.messages if SAID in m]


def test_a_height_image_as_normal_map_is_said_once_naming_its_materials(exported):
    _scene([_normal_mapped("Bumped", 0.2), _normal_mapped("AlsoBumped", 0.45), _normal_mapped("Proper", 1.0)])
    said = _said(exported())
    assert len(said) == 1, said
    assert "'Bumped'" in said[0] and "'AlsoBumped'" in said[0] and "'Proper'" not in said[0], said
    assert "light tree" in said[0].lower() and "dark in Cycles" in said[0], said


@pytest.mark.parametrize('case', ['proper map', 'light tree off', 'translucent'])
def test_nothing_said_where_cycles_agrees(case, exported):
    if case == 'proper map':
        _scene([_normal_mapped("Proper", 0.9)])
    elif case == 'light tree off':
        _scene([_normal_mapped("Bumped", 0.2)], light_tree=False)
    else:
        _scene([_normal_mapped("Leaf", 0.2, translucent=True)])
    assert _said(exported()) == []


def test_an_obj_map_bump_is_said(exported, tmp_path):
    """The OBJ importer's own wiring: map_Bump of a grey PNG (sRGB) into a Normal Map."""
    h = 8
    img = bpy.data.images.new("height", h, h)
    px = np.full((h, h, 4), 1.0, np.float32)
    px[..., :3] = np.linspace(0.2, 0.8, h)[None, :, None]
    img.pixels.foreach_set(px.ravel())
    img.filepath_raw = str(tmp_path / "height.png")
    img.file_format = 'PNG'
    img.save()
    (tmp_path / "t.mtl").write_text("newmtl wallpaper\nKd 0.8 0.8 0.8\nmap_Bump -bm 1 height.png\n")
    (tmp_path / "t.obj").write_text("mtllib t.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
                                    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl wallpaper\nf 1/1 2/2 3/3 4/4\n")
    bpy.ops.wm.obj_import(filepath=str(tmp_path / "t.obj"))
    mat = bpy.data.materials["wallpaper"]
    assert any(n.type == 'NORMAL_MAP' for n in mat.node_tree.nodes)
    scenes.camera((0, 6, 0), (math.radians(90), 0, math.radians(180)))
    scenes.light('SUN', 3.0, rotation=(math.radians(50), 0, math.radians(20)))
    said = _said(exported())
    assert len(said) == 1 and "'wallpaper'" in said[0], said


@pytest.mark.parametrize('strength, said', [(1.0, True), (0.8, True), (0.3, False)])
def test_the_strength_decides(strength, said, exported):
    """Texel (0.5, 0.5, 0.2): the tangent normal (0, 0, -1) blended toward the surface's by
    Cycles' strength, normalize(N + (n - N) s), is below it where s > 0.5."""
    mat = _normal_mapped("Bumped", 0.2)
    next(n for n in mat.node_tree.nodes if n.type == 'NORMAL_MAP').inputs['Strength'].default_value = strength
    _scene([mat])
    assert bool(_said(exported())) == said


def test_nothing_said_without_lamps_or_emitters(exported):
    """Lit by the world alone (the light tree does not cull the background by the normal)."""
    _scene([_normal_mapped("Bumped", 0.2)])
    for ob in [o for o in bpy.context.scene.objects if o.type == 'LIGHT']:
        bpy.data.objects.remove(ob)
    scenes.world((0.5, 0.5, 0.5))
    assert _said(exported()) == []


def test_an_emitter_is_enough(exported):
    _scene([_normal_mapped("Bumped", 0.2)])
    for ob in [o for o in bpy.context.scene.objects if o.type == 'LIGHT']:
        bpy.data.objects.remove(ob)
    mat, nt, out = scenes._material("Glow")
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Lamp", location=(0, -3, 0), materials=[mat])
    said = _said(exported())
    assert len(said) == 1 and "'Bumped'" in said[0], said
