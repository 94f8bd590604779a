"""Coincident non-emissive faces through Blender (addon/coincidentfaces.py;
tests/integrator/test_coincident_faces_said.py for the rules): a Mirror modifier on a mesh
already symmetric, or a second object sharing a mesh in place, lays exact copies of faces,
which render as one surface here and darker in Cycles (a mirrored cube under a grey world, 1
bounce: 1.094x Cycles' image mean). The render says so once, naming the object(s) and
counting the copied triangles (a float64 brute force over the evaluated meshes); a copy moved
by 1e-5 is not said; an emitter's copy keeps its own message alone."""
import math
from collections import Counter

import bpy
import numpy as np

from . import scenes

SAID = "coincide exactly with other triangles"
EMITTERS = "emissive triangles of"


def _scene():
    scenes.camera(location=(0, -7, 4), rotation=(math.radians(60), 0, 0))
    scenes.plane('Floor', size=10, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    cube = scenes.cube('Cube', size=1.0, location=(0, 0, 0.5), materials=[scenes.diffuse('grey', (0.5, 0.5, 0.5))])
    scenes.world((0.5, 0.5, 0.5))
    return cube


def _said(said):
    said.clear()
    scenes.render_rgba()
    return [t for t in said if SAID in t]


def _brute_force_copies():
    """How many triangles of the evaluated scene repeat another exactly (world space, float32
    corners as a sorted tuple)."""
    c = scenes.world_triangles().astype(np.float32) + np.float32(0.0)
    keys = [tuple(sorted(map(tuple, t.tolist()))) for t in c]
    return sum(c for c in Counter(keys).values() if c > 1)


def test_mirror_on_a_symmetric_mesh_is_said_once(scene, said):
    cube = _scene()
    assert not _said(said)
    m = cube.modifiers.new('mirror', 'MIRROR')         # the cube is symmetric in x already
    m.use_axis = [True, False, False]
    n = _brute_force_copies()
    assert n > 0
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"{n} triangles of 'Cube' {SAID}"), (n, got)
    assert "one surface" in got[0] and "darker" in got[0], got


def test_a_twin_object_is_said_and_a_near_copy_is_not(scene, said):
    cube = _scene()
    twin = scenes.link(bpy.data.objects.new('Twin', cube.data))
    twin.location = cube.location
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"24 triangles of 'Cube', 'Twin' {SAID}"), got
    twin.location = (0, 0, 0.5 + 1e-5)
    assert not _said(said)


def test_an_emitters_copy_keeps_its_own_message_alone(scene, said):
    _scene()
    lamp = scenes.plane('Lamp', size=1, location=(0, 0, 2), materials=[scenes.emission('e', (1, 1, 1), 5.0)])
    lamp.rotation_euler = (math.pi, 0, 0)
    twin = scenes.link(bpy.data.objects.new('LampTwin', lamp.data))
    twin.location, twin.rotation_euler = lamp.location, lamp.rotation_euler
    assert not _said(said)
    assert len([t for t in said if EMITTERS in t and "coincide" in t]) == 1, said


def _ray_type_mixes():
    """A plate hidden from shadow rays (Mix(Diffuse, Transparent, Is Shadow Ray)) and one held
    out for the camera (Mix(Diffuse, Holdout, Is Camera Ray)), beside a Transparent pane that
    keeps the clear twins in the render: the export gives each plate a twin on its faces that
    other ray kinds see (export/assembly.py _clear_twins), no copy of the user's."""
    _scene()
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    for name, second, output, x in (('Plate', 'ShaderNodeBsdfTransparent', 'Is Shadow Ray', 1.0),
                                    ('Held', 'ShaderNodeHoldout', 'Is Camera Ray', -1.0)):
        mat, nt, mix, _, _ = scenes.mix_shader_material(name, 'ShaderNodeBsdfDiffuse', second)
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
        scenes.plane(name, size=1.0, location=(x, 1.0, 1.2), materials=[mat])
    pane, nt, out = scenes._material('pane')
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0], out.inputs['Surface'])
    scenes.plane('Pane', size=1.0, location=(0, -1.5, 1.0), materials=[pane])


def test_the_exports_own_ray_kind_twins_coincide(scene, exported):
    from addon.coincidentfaces import exact_groups
    _ray_type_mixes()
    g = exported().geometry
    rows, _ = exact_groups(g.vertices, g.triangles, np.ones(len(g.triangles), bool))
    assert len(rows) == 8, len(rows)           # both plates and their twins: what the next test renders


def test_the_exports_own_ray_kind_twins_are_not_said(scene, said):
    _ray_type_mixes()
    assert not _said(said), said


def test_copies_of_a_material_built_per_ray_kind_are_counted_once(scene, said):
    # a mirrored cube whose material reads Is Camera Ray between two diffuse colours: the export
    # builds it per ray kind and gives each triangle a copy per variant (rayvariants.py), in the
    # same coincident set as the user's copy. Said as the same mesh with a plain material is
    # (the variants had doubled the count and added "where the copies' materials differ",
    # false: the user's copies share one material)
    cube = _scene()
    m = cube.modifiers.new('mirror', 'MIRROR')
    m.use_axis = [True, False, False]
    plain = _said(said)
    assert len(plain) == 1, said
    mat, nt, mix, _, red = scenes.mix_shader_material('kinds', 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfDiffuse')
    red.inputs['Color'].default_value = (0.9, 0.1, 0.1, 1.0)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    cube.data.materials[0] = mat
    got = _said(said)
    assert got == plain, (got, plain)
    assert got[0].startswith(f"{_brute_force_copies()} triangles of 'Cube' {SAID}"), got
    assert "materials differ" not in got[0], got
