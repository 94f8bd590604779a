"""Messages of studio set-ups (the studio hunt): what a layer says names the layer when the scene
renders several; a light's Glossy / Diffuse visibility mismatch is said only where a glossy part is
rendered as diffuse, naming the instancer whose flag it is; the shadow-catcher warning only for
objects that render something. Each had been said falsely or without its subject: "the scene has
no renderable geometry" of a layer left empty on purpose beside one that renders 34 triangles, a
glossy warning in an all-diffuse scene, a catcher warning for the camera and an empty."""
import math

import bpy

from tests.addon import scenes


def _box(scene, material=None):
    scenes.camera((0, -6, 1), (math.pi / 2, 0, 0))
    scene.dacrt.samples = 1
    mat = material or scenes.diffuse("Grey", (0.5, 0.5, 0.5))
    floor = scenes.plane("Floor", size=6.0, materials=[mat])
    cube = scenes.cube("Cube", size=1.0, location=(0, 0, 0.5), materials=[mat])
    lamp = scenes.light('POINT', 500.0, location=(0, -2, 3), name="Lamp")
    return floor, cube, lamp


def _instanced(scene, ob, collection, instancer):
    """ob moved into a new collection, placed by a new empty `instancer` (returned)."""
    group = bpy.data.collections.new(collection)
    scene.collection.objects.unlink(ob)
    group.objects.link(ob)
    holder = bpy.data.objects.new(instancer, None)
    holder.instance_type, holder.instance_collection = 'COLLECTION', group
    scene.collection.objects.link(holder)
    return holder


def _render(said):
    said.clear()
    bpy.ops.render.render()
    return list(said)


# -- view layers ---------------------------------------------------------------------------
def _two_layers(scene):
    """Layer 'Beauty' renders the geometry; layer 'FX' excludes its collection."""
    geo = bpy.data.collections.new("Geo")
    scene.collection.children.link(geo)
    floor, cube, _ = _box(scene)
    for ob in (floor, cube):
        scene.collection.objects.unlink(ob)
        geo.objects.link(ob)
    scene.view_layers[0].name = "Beauty"
    fx = scene.view_layers.new("FX")
    fx.layer_collection.children["Geo"].exclude = True
    scene.render.use_single_layer = False


def _summaries(capfd):
    """The per-layer summary lines Blender printed (RenderEngine.report, not _report_messages)."""
    return [line for line in capfd.readouterr().out.splitlines() if " triangles, " in line]


def test_an_empty_layer_beside_a_full_one_is_named(scene, said, capfd):
    _two_layers(scene)
    capfd.readouterr()
    text = _render(said)
    empty = [t for t in text if "no renderable geometry" in t]
    assert len(empty) == 1 and "view layer 'FX' has no renderable geometry" in empty[0], text
    assert not any("the scene has no renderable geometry" in t for t in text), text
    summaries = _summaries(capfd)
    assert len(summaries) == 2, summaries
    assert "DACRT: view layer 'Beauty': " in summaries[0] and ": 0 triangles" not in summaries[0], summaries
    assert "DACRT: view layer 'FX': 0 triangles" in summaries[1], summaries


def test_one_layer_says_the_scene(scene, said, capfd):
    """A scene rendering one layer (the other not in use) keeps the words it had."""
    _two_layers(scene)
    scene.view_layers["Beauty"].use = False
    capfd.readouterr()
    text = _render(said)
    assert any("the scene has no renderable geometry" in t for t in text), text
    summaries = _summaries(capfd)
    assert len(summaries) == 1 and "view layer" not in summaries[0], summaries


def test_render_single_layer_still_names_the_layer(scene, said, capfd):
    """A script's render renders every layer in use whatever Render Single Layer says."""
    _two_layers(scene)
    scene.render.use_single_layer = True
    capfd.readouterr()
    text = _render(said)
    assert any("view layer 'FX' has no renderable geometry" in t for t in text), text
    assert not any("the scene has no renderable geometry" in t for t in text), text


def test_the_surfaces_filter_names_its_layer(scene, said):
    _two_layers(scene)
    scene.view_layers["FX"].layer_collection.children["Geo"].exclude = False
    scene.view_layers["FX"].use_solid = False
    text = _render(said)
    assert any("surfaces are off in the filter of view layer 'FX' (Surfaces)" in t for t in text), text


# -- light ray visibility ------------------------------------------------------------------
def _glossy_said(text):
    return [t for t in text if "glossy layers (rendered as diffuse)" in t]


def test_glossy_visibility_off_in_an_all_diffuse_scene_is_not_warned(scene, said):
    _, _, lamp = _box(scene)
    lamp.visible_glossy = False
    assert _glossy_said(_render(said)) == []


def test_glossy_visibility_off_beside_a_glossy_layer_is_warned(scene, said):
    """A Principled's specular layer renders as diffuse: it takes the lamp by its Diffuse
    visibility, where Cycles' glossy rays would not see it."""
    _, _, lamp = _box(scene, scenes.principled("Plastic", (0.5, 0.5, 0.5), specular=0.5))
    lamp.visible_glossy = False
    text = _glossy_said(_render(said))
    assert len(text) == 1 and "'Lamp'" in text[0] and "Glossy off with Diffuse on" in text[0], text


def _shader(name, kind, **props):
    mat, nt, out = scenes._material(name)
    node = nt.nodes.new(kind)
    for k, v in props.items():
        setattr(node, k, v)
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def test_diffuse_class_closures_are_not_glossy(scene, said):
    """A Sheen BSDF and a Toon BSDF's Diffuse component are diffuse closures in Cycles: its
    image is the same with the lamp's Glossy visibility on or off (measured 0.6151 / 0.0226)."""
    _, cube, lamp = _box(scene, _shader("Toon", 'ShaderNodeBsdfToon'))
    cube.data.materials[0] = _shader("Sheen", 'ShaderNodeBsdfSheen')
    lamp.visible_glossy = False
    assert _glossy_said(_render(said)) == []


def test_a_toon_glossy_component_is_glossy(scene, said):
    _, _, lamp = _box(scene, _shader("ToonGlossy", 'ShaderNodeBsdfToon', component='GLOSSY'))
    lamp.visible_glossy = False
    assert len(_glossy_said(_render(said))) == 1


def test_a_principled_without_glossy_layers_is_not_glossy(scene, said):
    _, _, lamp = _box(scene, scenes.principled("Matte", (0.5, 0.5, 0.5), specular=0.0))
    lamp.visible_glossy = False
    assert _glossy_said(_render(said)) == []


def test_the_instancer_whose_flag_it_is_is_named(scene, said):
    _, _, lamp = _box(scene, scenes.principled("Plastic", (0.5, 0.5, 0.5), specular=0.5))
    _instanced(scene, lamp, "Rig", "LightRig").visible_glossy = False
    text = _glossy_said(_render(said))
    assert len(text) == 1 and "'Lamp' (instanced by 'LightRig')" in text[0], text


# -- shadow catcher --------------------------------------------------------------------------
def _catcher_said(text):
    return [t for t in text if "shadow catcher is not supported" in t]


def test_catcher_flag_on_camera_and_empty_is_not_warned(scene, said):
    _box(scene)
    empty = bpy.data.objects.new("Locator", None)
    scene.collection.objects.link(empty)
    empty.is_shadow_catcher = scene.camera.is_shadow_catcher = True
    assert _catcher_said(_render(said)) == []


def test_catcher_flag_on_an_empty_curve_is_not_warned(scene, said):
    """A curve with no splines and a path with no bevel render nothing in either engine."""
    _box(scene)
    for name, points in (("Empty", 0), ("Path", 3)):
        cu = bpy.data.curves.new(name, 'CURVE')
        if points:
            cu.splines.new('POLY').points.add(points - 1)
        ob = bpy.data.objects.new(name, cu)
        scene.collection.objects.link(ob)
        ob.is_shadow_catcher = True
    assert _catcher_said(_render(said)) == []


def test_catcher_flag_on_a_mesh_and_an_instancer_is_warned(scene, said):
    floor, cube, _ = _box(scene)
    floor.is_shadow_catcher = True
    _instanced(scene, cube, "Props", "Holder").is_shadow_catcher = True
    text = _catcher_said(_render(said))
    assert len(text) == 1 and "'Floor'" in text[0] and "'Holder'" in text[0], text
