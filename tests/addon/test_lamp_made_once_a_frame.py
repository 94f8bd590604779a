"""A frame makes each light's renderer lamp once: the export's float32 check makes it and the
integrator's set-up takes it (lights/madelamp.py), where both had made it (many_lights' 12 lamps:
~2 ms of a frame's set-up). A light the export changes after its check (an instancer hiding it
from the camera) is made again, and every image is the one of lamps made afresh."""
import bpy
import numpy as np
import pytest

import addon.lightsetup
from addon.lights import base

from . import scenes


@pytest.fixture
def lamps_made(monkeypatch):
    """The lights (by name) a lamp was made of during the test, in order."""
    names = []
    real = base.Lamp.__init__

    def init(self, light=None, color=None):
        if light is not None:
            names.append(light.name)
        real(self, light, color)
    monkeypatch.setattr(base.Lamp, '__init__', init)
    return names


def _lit_scene(scene):
    scenes.plane("Floor", size=6.0, materials=[scenes.diffuse("grey", (0.6, 0.6, 0.6))])
    scenes.light('POINT', 40.0, (1.0, 0.5, 1.5), name="Bulb", shadow_soft_size=0.2)
    scenes.light('SPOT', 80.0, (-1.0, 0.5, 2.0), name="Spot", spot_size=0.9)
    scenes.light('SUN', 1.5, rotation=(0.4, 0.2, 0.0), name="Sun")
    panel = scenes.light('AREA', 30.0, (0.0, -0.8, 1.0), name="Panel", size=0.6)
    panel.visible_camera = True
    # an instanced panel whose instancer hides it from camera rays: the export turns its
    # camera visibility off after the check
    col = bpy.data.collections.new("Parts")
    inst = bpy.data.objects.new("Hidden", bpy.data.lights.new("Hidden", 'AREA'))
    inst.data.energy, inst.data.size, inst.visible_camera = 30.0, 0.8, True
    col.objects.link(inst)
    empty = scenes.link(bpy.data.objects.new("Instancer", None))
    empty.instance_type, empty.instance_collection, empty.location = 'COLLECTION', col, (0.4, 0.3, 0.6)
    empty.visible_camera = False
    scenes.camera(location=(0, 0, 4.0))
    scene.dacrt.samples = 4


def test_each_light_is_made_into_a_lamp_once_a_frame(scene, lamps_made):
    _lit_scene(scene)
    scenes.render_rgba(scene)
    # the hidden instance's lamp is made twice: changed after its check
    assert sorted(lamps_made) == sorted(["Bulb", "Spot", "Sun", "Panel", "Hidden", "Hidden"]), lamps_made


def test_lamps_taken_from_the_check_render_as_lamps_made_afresh(scene, monkeypatch):
    _lit_scene(scene)
    taken = scenes.render_rgba(scene)
    monkeypatch.setattr(addon.lightsetup, 'taken_lamp', lambda light, make: make(light))
    fresh = scenes.render_rgba(scene)
    assert taken.tobytes() == fresh.tobytes()
    assert np.isfinite(taken).all() and taken[..., :3].max() > 0


def test_a_stereo_frames_second_view_makes_its_own_lamps(scene, lamps_made):
    """Each view of a multiview render has its own integrator: the first takes the lamps the
    export checked, the second makes its own (a lamp is never shared between two set-ups)."""
    _lit_scene(scene)
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'
    bpy.ops.render.render()
    assert sorted(lamps_made) == sorted(["Bulb", "Spot", "Sun", "Panel"] * 2 + ["Hidden"] * 3), lamps_made
