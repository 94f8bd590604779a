"""The Shadow-off emitter WARNING (test_shadowless_emitter_message.py) is said only where some
emitting face can be reached by light samples alone: where a face of its own placement, which
stops bounce rays but not shadow rays, can stand between a receiver and it. A light card (a
plane with Ray Visibility > Shadow off, the usual softbox set-up) has all its faces in one
plane, so none can hide another and the image cannot depend on the light-selection pdf: it had
been warned, though DACRT matches Cycles (shadowless_card.py: 0.2993 vs 0.2992, blocks within
noise). Two parallel cards in one object, or a closed emitter (a sphere's far side lies behind
its near side), are still said.

DACRT's messages at 1 sample, 32x24, Light Tree on."""
import math

import bpy
import pytest

from tests.parity import rendering

from . import scenes

SAID = "have Ray Visibility > Shadow off"


def _card(name, rotation, cuts=0, twin_offset=None):
    """An emissive 1.5 m card (Emission 8) with Shadow off, rotated, optionally subdivided into a
    grid (cuts), optionally with a second parallel card in the same mesh, twin_offset away
    along its normal."""
    h = 0.75
    verts = [(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)]
    faces = [(0, 1, 2, 3)]
    if twin_offset is not None:
        verts += [(x, y, twin_offset) for x, y, _ in verts[:4]]
        faces.append((4, 5, 6, 7))
    ob = scenes.mesh(name, verts, faces, location=(1.5, -1.0, 2.0),
                     materials=[scenes.emission(name + 'glow', (1, 0.9, 0.8), 8.0)])
    if cuts:
        import bmesh
        bm = bmesh.new()
        bm.from_mesh(ob.data)
        bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=cuts, use_grid_fill=True)
        bm.to_mesh(ob.data)
        bm.free()
    ob.rotation_euler = rotation
    ob.visible_shadow = False
    return ob


def _scene(sc, **card):
    scenes.plane('Floor', size=10, materials=[scenes.diffuse('fl', (0.8, 0.8, 0.8))])
    scenes.uv_sphere('Ball', radius=0.7, location=(0, 0, 0.7), materials=[scenes.diffuse('b', (0.3, 0.5, 0.8))])
    scenes.camera(location=(0, -6, 3), rotation=(math.radians(65), 0, 0))
    scenes.black_world()
    _card('Card', (math.radians(150), math.radians(-30), math.radians(17)), **card)
    rendering.matched(sc, 1, bounces=1)
    sc.dacrt.use_light_tree = True
    sc.cycles.use_light_tree = True


def _said(sc, said):
    said.clear()
    sc.render.engine = 'DACRT'
    bpy.ops.render.render()
    return [t for t in said if SAID in t]


@pytest.mark.parametrize('cuts', [0, 5])
def test_card_not_said(scene, said, cuts):
    """A card, also subdivided into a grid, rotated off every axis (its float32 corners off
    the plane by rounding)."""
    _scene(scene, cuts=cuts)
    assert not _said(scene, said)


def test_two_parallel_cards_in_one_object_said(scene, said):
    """One card 0.3 m behind the other in the same mesh: the near one hides the far one from
    bounce rays, not from light samples."""
    _scene(scene, twin_offset=0.3)
    got = _said(scene, said)
    assert len(got) == 1 and "'Card'" in got[0], got


def test_closed_emitter_said_beside_a_card(scene, said):
    """A Shadow-off emissive sphere beside the card: said, naming the sphere alone."""
    _scene(scene)
    bulb = scenes.uv_sphere('Bulb', radius=0.3, location=(-1.5, -1.0, 2.0),
                            materials=[scenes.emission('bulbglow', (1, 0.9, 0.8), 20.0)])
    bulb.visible_shadow = False
    got = _said(scene, said)
    assert len(got) == 1 and "'Bulb'" in got[0] and "'Card'" not in got[0], got


def test_card_image_matches_cycles(scene, said, tmp_path):
    """What backs the silence: DACRT's image of the card scene is Cycles' (light tree on in both)."""
    _scene(scene)
    scene.cycles.samples = 128
    scene.render.engine = 'CYCLES'
    c = rendering.render_combined(scene, str(tmp_path / 'c.exr'))
    rendering.matched(scene, 64, bounces=1)
    scene.render.engine = 'DACRT'
    said.clear()
    d = rendering.render_combined(scene, str(tmp_path / 'd.exr'))
    assert not [t for t in said if SAID in t]
    assert d[..., :3].mean() == pytest.approx(c[..., :3].mean(), rel=0.02)
