"""NaN in the world's and lights' settings (a script or driver gone wrong): Cycles' film drops a
world channel that is not finite and keeps the others; DACRT had blacked out the whole world,
and a NaN Strength (of the world's Background or of a light's Emission) was read as 0 without
a word."""
import numpy as np

from . import scenes

NAN = float('nan')


def _render(scene):
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    return scenes.render_rgba(scene)


def test_world_colour_with_a_nan_channel_keeps_the_others(scene, said):
    """Cycles renders a Background colour (NaN, 0.5, 0.5) as (0, 0.5, 0.5) (a tester's scene:
    0 / 0.4234 / 0.4234; DACRT's had been black, now 0 / 0.4232 / 0.4232)."""
    scenes.camera()
    scenes.world((NAN, 0.5, 0.5))
    img = _render(scene)
    assert np.allclose(img[..., :3], (0.0, 0.5, 0.5), atol=1e-6)
    assert any("world approximated: its colour x strength (nan, 0.5, 0.5) is not finite in some channel" in t
               for t in said), said


def test_world_colour_with_a_nan_channel_lights_the_scene_with_the_others(scene, said):
    scenes.camera()
    scenes.plane("Floor", size=20, materials=(scenes.diffuse("White", (1.0, 1.0, 1.0)),))
    scenes.world((NAN, 0.5, 0.5))
    img = _render(scene)
    assert np.all(img[..., 0] == 0.0) and np.all(img[..., 1] > 0.2) and np.isfinite(img).all()


def test_nan_world_strength_is_named(scene, said):
    """Black in both renderers; the message had only said 'a black world'."""
    scenes.camera()
    scenes.world((0.2, 0.25, 0.3), NAN)
    img = _render(scene)
    assert np.all(img[..., :3] == 0.0)
    assert any("world approximated: NaN read as 0 for 'Strength' of 'Background'" in t for t in said), said


def test_nan_emission_strength_in_a_light_node_tree_is_named(scene, said):
    """No light in both renderers; DACRT had said nothing."""
    scenes.camera()
    scenes.black_world()
    scenes.plane("Floor", size=20, materials=(scenes.diffuse("White", (0.8, 0.8, 0.8)),))
    sun = scenes.light('SUN', 3.0)
    sun.data.use_nodes = True
    em = next(n for n in sun.data.node_tree.nodes if n.type == 'EMISSION')
    em.inputs['Strength'].default_value = NAN
    img = _render(scene)
    assert np.all(img[..., :3] == 0.0)
    assert any("light 'Sun': node tree approximated: NaN read as 0 for 'Strength' of 'Emission'" in t
               for t in said), said
