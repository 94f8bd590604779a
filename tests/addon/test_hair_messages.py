"""What the render says about hair particles and Curves (addon/export/strands.py, scene.py,
materials.py)."""
import math

from . import scenes
from tests.parity.test_hair_fixes import _painted_emitter


def _camera():
    scenes.camera(location=(0, -6, 0), rotation=(math.pi / 2, 0, 0), kind='ORTHO', ortho_scale=3.0)
    scenes.light('SUN', 3.0, rotation=(0.6, 0.4, 0.3))


def test_hair_reading_an_emitter_attribute_cycles_gives_it_says_nothing(scene, said):
    """The emitter's Face Corner Byte Color attribute is read at each strand's root, as Cycles:
    no message (it had said "no attribute 'Col' on the mesh: its colour reads 0, as in Cycles",
    and rendered the strands black)."""
    _camera()
    _painted_emitter()
    scenes.render_rgba(scene)
    assert not [t for t in said if "'Col'" in t], said


def test_hair_reading_an_emitter_attribute_cycles_does_not_names_what_it_reads(scene, said):
    """A Point-domain (or float) colour attribute on the emitter reads 0 in Cycles' hair too:
    the message says which attributes hair particles do read."""
    _camera()
    _painted_emitter(domain='POINT', data_type='FLOAT_COLOR')
    scenes.render_rgba(scene)
    text = [t for t in said if "'Col'" in t]
    assert text and all("no Face Corner Byte Color attribute 'Col' on the emitter (hair particles read only "
                        "those, at each strand's root): its colour reads 0, as in Cycles" in t for t in text), said
