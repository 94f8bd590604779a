"""What a material built per Light Path ray kind (export/rayvariants.py) says: only what stays
approximated, and only where it holds in the scene. A depth clamp past the first bounce (the
bounces here read Ray Depth 1), a Transparent Depth, Is Reflection Ray beside a Translucent
BSDF (rays off it read as off a reflection), Is Glossy Ray; and nothing where the build per
kind is exact (a camera-only clamp, Is Reflection Ray without a translucent or glass surface,
a deep clamp with no bounce past the first rendered)."""
import pytest

from tests.addon import scenes

RAY_DEPTH = "Light Path Ray Depth read as 1 on every bounce"
TRANSPARENT_DEPTH = "Light Path Transparent Depth read as 0 on every surface"
BENT = "Light Path Is Reflection Ray read as after a diffuse reflection on every bounce ray"
GLOSSY = "Light Path Is Glossy Ray read as on a diffuse path"


def _clamped_emission(name, output, below):
    """An emission of strength 6 x (output < below) over a diffuse."""
    mat, nt, out = scenes._material(name)
    e, d, add = (nt.nodes.new(k) for k in ('ShaderNodeEmission', 'ShaderNodeBsdfDiffuse', 'ShaderNodeAddShader'))
    less, scale = nt.nodes.new('ShaderNodeMath'), nt.nodes.new('ShaderNodeMath')
    less.operation, scale.operation = 'LESS_THAN', 'MULTIPLY'
    less.inputs[1].default_value, scale.inputs[1].default_value = below, 6.0
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], less.inputs[0])
    nt.links.new(less.outputs[0], scale.inputs[0])
    nt.links.new(scale.outputs[0], e.inputs['Strength'])
    nt.links.new(d.outputs[0], add.inputs[0])
    nt.links.new(e.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    return mat


def _mixed_by(name, output):
    mat, nt, mix, a, b = scenes.mix_shader_material(name, 'ShaderNodeBsdfDiffuse', 'ShaderNodeEmission')
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
    return mat


def _said(data, name):
    return [t for _, t in data.messages if f"'{name}'" in t]


@pytest.mark.parametrize('below, bounces, said', [(2.0, 2, True), (2.0, 0, False), (1.0, 2, False)])
def test_ray_depth_clamp_says_the_depth_only_past_the_first_bounce(scene, exported, below, bounces, said):
    scenes.camera()
    scene.dacrt.max_bounces = bounces
    scenes.plane("Panel", materials=(_clamped_emission("Panel", 'Ray Depth', below),))
    text = ' '.join(_said(exported(), "Panel"))
    assert (RAY_DEPTH in text) == said, text
    assert "'Light Path' node" not in text, text


def test_transparent_depth_is_said(scene, exported):
    scenes.camera()
    scenes.plane("Panel", materials=(_clamped_emission("Panel", 'Transparent Depth', 1.0),))
    text = ' '.join(_said(exported(), "Panel"))
    assert TRANSPARENT_DEPTH in text, text


@pytest.mark.parametrize('translucent', [False, True])
def test_reflection_ray_said_beside_a_translucent_surface_only(scene, exported, translucent):
    scenes.camera()
    scenes.plane("Panel", materials=(_mixed_by("Panel", 'Is Reflection Ray'),))
    if translucent:
        mat, nt, out = scenes._material("Leaf")
        nt.links.new(nt.nodes.new('ShaderNodeBsdfTranslucent').outputs[0], out.inputs['Surface'])
        scenes.plane("Leaf", location=(3, 0, 0), materials=(mat,))
    text = ' '.join(_said(exported(), "Panel"))
    assert (BENT in text) == translucent, text


def test_glossy_ray_is_said(scene, exported):
    scenes.camera()
    scenes.plane("Panel", materials=(_mixed_by("Panel", 'Is Glossy Ray'),))
    text = ' '.join(_said(exported(), "Panel"))
    assert GLOSSY in text, text


@pytest.mark.parametrize('camera_sees_the_attribute', [True, False])
def test_object_info_colour_with_a_ray_kind_mix_is_built_once_and_said(scene, exported, camera_sees_the_attribute):
    """A colour per object (Object Info Random through a Color Ramp) in a material mixed by Is
    Camera Ray: the per-object colour is evaluated on the material's own triangles, out of any
    ray kind, so the material is not built per ray kind: its Light Path reads its own value,
    said (built per kind, a camera-only Object Info colour had shown the bounce build's on its
    copies, unsaid: 1.13-1.49x Cycles)."""
    scenes.camera()
    mat, nt, mix, d, e = scenes.mix_shader_material("Panel", 'ShaderNodeBsdfDiffuse', 'ShaderNodeEmission')
    oi, ramp = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeValToRGB')
    nt.links.new(oi.outputs['Random'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    lp = nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray']
    if camera_sees_the_attribute:
        inv = nt.nodes.new('ShaderNodeMath')
        inv.operation, inv.inputs[0].default_value = 'SUBTRACT', 1.0
        nt.links.new(lp, inv.inputs[1])
        lp = inv.outputs[0]
    nt.links.new(lp, mix.inputs['Fac'])
    scenes.plane("Panel", materials=(mat,))
    data = exported()
    assert [m.name for m in data.materials].count("Panel") == 1
    text = ' '.join(_said(data, "Panel"))
    assert "(value from 'Light Path' node); its own value 0.5 used" in text, text


def _leaf(x=3.0):
    mat, nt, out = scenes._material("Leaf")
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTranslucent').outputs[0], out.inputs['Surface'])
    scenes.plane("Leaf", location=(x, 0, 0), materials=(mat,))


@pytest.mark.parametrize('translucent', [False, True])
def test_diffuse_depth_said_beside_a_translucent_surface_only(scene, exported, translucent):
    """A ray off a Translucent BSDF reads Diffuse Depth 0 in Cycles 5.0 (a transmission bounce;
    measured behind a white translucent plate), where DACRT's bounce rays read 1: said where the
    scene has one, at Max Bounces 0 too (no deeper bounce then for the depth note to say it).
    It had not been said: Diffuse Depth was left out of the outputs checked for such rays."""
    scenes.camera()
    scene.dacrt.max_bounces = 0
    scenes.plane("Panel", materials=(_mixed_by("Panel", 'Diffuse Depth'),))
    if translucent:
        _leaf()
    text = ' '.join(_said(exported(), "Panel"))
    said = "Light Path Diffuse Depth read as after a diffuse reflection on every bounce ray"
    assert (said in text) == translucent, text


@pytest.mark.parametrize('glass', [False, True])
def test_ray_depth_past_the_first_bounce_said_at_max_bounces_zero_where_glass_goes_deeper(scene, exported, glass):
    """At Max Bounces 0 a diffuse path ends at its first bounce, but one through glass goes on
    (Cycles counts the pass: the floor behind a pane casts its shadow ray at Ray Depth 2): the
    depth note is said there, where the scene has glass, and not without."""
    scenes.camera()
    scene.dacrt.max_bounces = 0
    scenes.plane("Panel", materials=(_clamped_emission("Panel", 'Ray Depth', 2.0),))
    if glass:
        mat, nt, out = scenes._material("Glass")
        nt.links.new(nt.nodes.new('ShaderNodeBsdfGlass').outputs[0], out.inputs['Surface'])
        scenes.plane("Pane", location=(3, 0, 0), materials=(mat,))
    text = ' '.join(_said(exported(), "Panel"))
    assert (RAY_DEPTH in text) == glass, text


def test_transmission_depth_note_names_translucent_surfaces(scene, exported):
    scenes.camera()
    scenes.plane("Panel", materials=(_mixed_by("Panel", 'Transmission Depth'),))
    text = ' '.join(_said(exported(), "Panel"))
    assert "Transmission Depth off a Translucent BSDF too" in text, text
