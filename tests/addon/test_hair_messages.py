"""What the render says about hair particles and Curves (addon/export/strands.py, scene.py,
materials.py, shaders.py)."""
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


def _emitter_linked(render_type):
    import bpy
    _camera()
    sun = next(o for o in bpy.data.objects if o.type == 'LIGHT')
    em = scenes.plane("Emitter", size=2)
    em.modifiers.new("Hair", 'PARTICLE_SYSTEM')
    s = em.particle_systems[0].settings
    s.type, s.count, s.hair_length = 'HAIR', 10, 0.5
    if render_type == 'OBJECT':
        s.render_type, s.instance_object = 'OBJECT', scenes.plane("Leaf", size=0.1)
    col = bpy.data.collections.new("Receivers")
    col.objects.link(em)
    sun.light_linking.receiver_collection = col
    return em


def test_a_hair_emitter_in_a_link_collection_is_not_called_an_instancer(scene, said):
    """Light linking: a hair emitter (Render As Path) makes no instances and its hair is linked
    with it; it had been warned about as an instancer whose instances are not linked."""
    _emitter_linked('PATH')
    scenes.render_rgba(scene)
    assert not [t for t in said if "instancer 'Emitter'" in t], said


def test_a_particle_instancer_in_a_link_collection_is_still_named(scene, said):
    _emitter_linked('OBJECT')
    scenes.render_rgba(scene)
    assert [t for t in said if "instancer 'Emitter' in its receiver collection" in t], said


def test_principled_hair_by_melanin_names_the_colour_it_renders(scene, said):
    """Melanin mode has no Color: the message had said only 'Principled Hair BSDF as diffuse'
    (rendering 0.8 grey); it names the melanin and the colour it renders."""
    import numpy as np
    from tests.parity.test_hair_fixes import _hair_material
    _camera()
    mat, _ = _hair_material('MELANIN', {'Melanin': 0.8})
    scenes.hair_curves("Strands", [np.array([[0, 0, -1.0], [0, 0, 0], [0.1, 0, 1]])], radius=0.05, material=mat)
    scenes.render_rgba(scene)
    assert any("Principled Hair BSDF as diffuse of the colour its Melanin 0.8 (Melanin Redness 1, Tint (1, 1, 1)) "
               "absorbs as in Cycles' Direct Coloring: (0.0126, 0.00167, 3.16e-05)" in t for t in said), said


def test_a_nan_radius_is_said_as_the_radius(scene, said):
    """A Curves point of NaN radius had made NaN tube vertices, reported as "vertices with NaN
    ... coordinates" (the user's positions are fine): the message names the radius."""
    import numpy as np
    _camera()
    ob = scenes.hair_curves("H", [np.stack([np.zeros(8), np.zeros(8), np.linspace(-1, 1, 8)], 1)], radius=0.05)
    r = np.full(8, 0.05, np.float32)
    r[3] = np.nan
    ob.data.attributes['radius'].data.foreach_set('value', r)
    scenes.render_rgba(scene)
    assert "'H': 1 point(s) of NaN or infinite radius: no tube is rendered around them" in said, said
    assert not [t for t in said if 'coordinates' in t], said
