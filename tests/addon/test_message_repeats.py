"""Each message is said once per render: the views of a stereo render and the view layers of a
frame export and prepare the same scene, and had repeated every message (a regression hunt saw
the new float32-precision warning twice); a new render says it again, also with Persistent Data,
which keeps the same engine between renders."""
import bpy

from . import scenes

NO_LIGHTS = "the scene has no light objects"


def _unlit(scene):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=4)
    scenes.world((0.5, 0.5, 0.5))
    scene.dacrt.samples = 1


def _count(capfd):
    return capfd.readouterr().out.count(NO_LIGHTS)


def test_two_view_layers_say_it_once(scene, capfd):
    """What is the same for both layers (the plane's default surface) is said once; what each
    layer finds of its own content is said by each, naming it (test_studio_messages.py)."""
    _unlit(scene)
    scene.view_layers.new("Second")
    bpy.ops.render.render()
    out = capfd.readouterr().out
    assert out.count("objects without a material") == 1, out
    assert out.count("view layer 'ViewLayer' has no light objects") == 1, out
    assert out.count("view layer 'Second' has no light objects") == 1, out


def test_stereo_views_say_it_once(scene, capfd):
    """The integrator's messages (here: a zero-strength light skipped) come from each view's own
    integrator."""
    _unlit(scene)
    scenes.light('POINT', 0.0, location=(0, 0, 2))
    scene.render.use_multiview = True
    scene.render.views_format = 'STEREO_3D'
    bpy.ops.render.render()
    assert capfd.readouterr().out.count("light(s) with zero strength") == 1


def test_every_render_says_it_also_with_persistent_data(scene, capfd):
    _unlit(scene)
    scene.render.use_persistent_data = True
    bpy.ops.render.render()
    bpy.ops.render.render()
    assert _count(capfd) == 2
