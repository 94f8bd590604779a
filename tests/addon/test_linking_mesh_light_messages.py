"""The render says when Cycles lights light-sampled emissive meshes brighter because of light
linking (lights/linking.py cycles_mesh_light_excess_said): a lamp whose receiver collection holds
only the ground, over emissive spheres that only emit, changes nothing physically, yet Cycles
rendered the spheres' light 4.5% brighter (min419 of fuzz seed 419: 6.8% with Geometry Nodes
instances) while DACRT, unchanged, said nothing. Not said where Cycles agrees: no linking,
Emission Sampling None, or an emissive object with a receiver collection of its own."""
import bpy

from . import scenes


def _scene(scene, link='receiver', sampling='AUTO', own_receivers=0):
    scene.dacrt.samples = 1
    scenes.camera((3, -6, 5), rotation=(0.9, 0, 0.45))
    ground = scenes.plane("Ground", size=14, materials=[scenes.diffuse("G", (0.8, 0.8, 0.8))])
    glow = scenes.emission("Glow", (1, 1, 1), 3.0)
    glow.cycles.emission_sampling = sampling
    spheres = [scenes.uv_sphere(f"Bulb{i}", radius=0.2, segments=8, rings=4, location=(i - 1, 0, 0.8),
                                materials=[glow]) for i in range(3)]
    lamp = scenes.light('AREA', 300.0, (-3, -1, 3.6), rotation=(0.6, -0.6, 0), size=1.0, name="L0")
    coll = bpy.data.collections.new("Recv")
    coll.objects.link(ground)
    if link:
        setattr(lamp.light_linking, f"{link}_collection", coll)
    for sphere in spheres[:own_receivers]:
        sphere.light_linking.receiver_collection = coll
    scenes.render_rgba(scene)


def _excess(said):
    return [t for t in said if "Cycles renders their light 4-7% brighter" in t]


def test_a_lamps_receiver_collection_over_emissive_meshes_is_said(scene, said):
    _scene(scene)
    texts = _excess(said)
    assert len(texts) == 1, said
    assert "light linking of 'L0' with emissive objects 'Bulb0', 'Bulb1', 'Bulb2'" in texts[0], said


def test_a_lamps_blocker_collection_is_said_too(scene, said):
    _scene(scene, link='blocker')
    assert len(_excess(said)) == 1, said


def test_without_linking_nothing_is_said(scene, said):
    _scene(scene, link=None)
    assert not _excess(said), said


def test_emission_sampling_none_says_nothing(scene, said):
    _scene(scene, sampling='NONE')
    assert not _excess(said), said


def test_an_emitter_with_its_own_receivers_says_nothing(scene, said):
    _scene(scene, own_receivers=1)
    assert not _excess(said), said
