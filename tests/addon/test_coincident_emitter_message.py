"""A duplicated emitter through Blender (tests/integrator/test_coincident_emitters.py for the
light sampling): a second object sharing an emissive plane's mesh in place (a duplicated
import; a Mirror applied twice makes the same) renders as the plane alone, and the render says
once that the emissive triangles coincide (Cycles renders coincident faces darker: the repro
scene at 64x48, 0 bounces, Cycles 0.1346 against the plane alone 0.2002; DACRT had 0.2838).
A twin that is a Diffuse copy (an object-linked material) leaves one surface too: the
emitter's or the diffuse one's, by which the tracer's hits return."""
import numpy as np

from . import scenes
from .emittertwins import lamp_scene, twin

SAID = "coincide with other triangles: rendered as one surface (Cycles renders coincident faces darker)"


def _render(said):
    said.clear()
    img = scenes.render_rgba()[..., :3]
    return img, [t for t in said if SAID in t]


def test_twin_renders_as_the_plane_alone_said_once(scene, said):
    lamp = lamp_scene(scene, 1.0, 16)
    single, got = _render(said)
    assert single.mean() > 0.05 and not got
    twin(lamp)
    doubled, got = _render(said)
    np.testing.assert_array_equal(doubled, single)       # (the twin: the higher index)
    assert len(got) == 1 and got[0] == f"4 emissive triangles of 'Lamp', 'Twin' {SAID}", got


def test_diffuse_twin_leaves_one_surface(scene, said):
    lamp = lamp_scene(scene, 1.0, 16)
    single, _ = _render(said)
    twin(lamp, material=scenes.diffuse('twin', (0.8, 0.8, 0.8)))
    doubled, got = _render(said)
    # which copy the hits return is the export's order (here the emitter's): its image alone
    np.testing.assert_array_equal(doubled, single)
    assert len(got) == 1 and got[0].startswith("2 emissive triangles of "), got
