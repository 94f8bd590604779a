"""What the export says about node set-ups it renders as Cycles does, or not: only what differs,
naming the cause. Each scene is a plane (or grid) under a uniform white world with no bounces,
seen from above by an orthographic camera, so a pixel is the Diffuse colour; Cycles renders the
same scene where the test compares values. From a hunt: a fractal Voronoi had been reported as
'Voronoi F1 EUCLIDEAN 3D is not read there' (all three read), an Attribute's Fac straight into a
colour as 'nodes after attribute ... applied at the corners' (means 0.5036 in both engines),
a Subdivision + Cast mesh reading Object coordinates only as 'Generated coordinates ...
approximated' (0.6941 both), a Texture Mapping's min/max as 'ignored' (Cycles does not read it
either: blender/shader.cpp get_tex_mapping)."""
import bpy
import numpy as np

from . import scenes


def _setup(scene, res=(16, 12)):
    scene.render.resolution_x, scene.render.resolution_y = res
    scene.view_settings.view_transform = 'Standard'
    scenes.world((1, 1, 1))
    scenes.camera((0, 0, 3), kind='ORTHO', ortho_scale=2.0)
    scene.dacrt.samples, scene.dacrt.max_bounces = 8, 0
    c = scene.cycles
    c.device, c.samples, c.max_bounces, c.use_denoising, c.use_adaptive_sampling = 'CPU', 16, 0, False, False


def _diffuse(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat, nt, d


def _render(scene, engine):
    scene.render.engine = engine
    return scenes.render_rgba(scene)[..., :3]


def _grid(name, mat, size=2.0):
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=8, y_subdivisions=8, size=size)
    ob = bpy.context.object
    ob.name = name
    ob.data.materials.append(mat)
    return ob


def test_fractal_voronoi_is_read_and_what_is_not_is_named(scene, said):
    """A fractal Voronoi (Detail 2, Roughness 0.5) is evaluated per point, said nothing of; a
    setting the export does not read is named alone (not the octaves it reads)."""
    _setup(scene)
    mat, nt, d = _diffuse("Cells")
    v = nt.nodes.new('ShaderNodeTexVoronoi')
    v.inputs['Scale'].default_value, v.inputs['Detail'].default_value = 4.0, 2.0
    v.inputs['Roughness'].default_value = 0.5
    nt.links.new(v.outputs['Distance'], d.inputs['Color'])
    scenes.plane("Plane", materials=(mat,))
    _render(scene, 'DACRT')
    assert not any("Voronoi" in t for t in said), said
    v.distance = 'MINKOWSKI'
    _render(scene, 'DACRT')
    assert not any("Voronoi" in t for t in said), said
    v.voronoi_dimensions = '4D'
    _render(scene, 'DACRT')
    assert not any("Voronoi" in t for t in said), said
    tc = nt.nodes.new('ShaderNodeNewGeometry')      # a coordinate kind not read: named alone
    nt.links.new(tc.outputs['Tangent'], v.inputs['Vector'])
    _render(scene, 'DACRT')
    text = " | ".join(said)
    assert "(Geometry Tangent is not read there)" in text and "4D" not in text
    said.clear()
    nt.links.remove(v.inputs['Vector'].links[0])
    v.inputs['Detail'].default_value = 0.0      # one octave, 3D Euclidean: evaluated per point, silent
    v.distance, v.voronoi_dimensions = 'EUCLIDEAN', '3D'
    _render(scene, 'DACRT')
    assert not any("Voronoi" in t for t in said), said


def test_attribute_fac_into_a_colour_is_exact_and_silent(scene, said):
    _setup(scene)
    mat, nt, d = _diffuse("Weights")
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = 'w'
    nt.links.new(a.outputs['Fac'], d.inputs['Color'])
    ob = scenes.plane("Plane", materials=(mat,))
    at = ob.data.attributes.new('w', 'FLOAT', 'POINT')
    for i, e in enumerate(at.data):
        e.value = 0.2 * (i + 1)
    dacrt, cycles = _render(scene, 'DACRT'), _render(scene, 'CYCLES')
    assert abs(dacrt.mean() - cycles.mean()) < 2e-3, (dacrt.mean(), cycles.mean())
    assert abs(np.median(dacrt - cycles)) < 2e-3
    assert not any("applied at the mesh's corners" in t for t in said), said
    # a non-linear chain after it (Gamma 2) is computed per point, after the interpolation, as
    # Cycles: exact and silent too (it had been applied at the corners, said)
    g = nt.nodes.new('ShaderNodeGamma')
    g.inputs['Gamma'].default_value = 2.0
    nt.links.new(a.outputs['Color'], g.inputs['Color'])
    nt.links.new(g.outputs['Color'], d.inputs['Color'])
    said.clear()
    dacrt, cycles = _render(scene, 'DACRT'), _render(scene, 'CYCLES')
    assert abs(dacrt.mean() - cycles.mean()) < 2e-3, (dacrt.mean(), cycles.mean())
    assert abs(np.median(dacrt - cycles)) < 2e-3
    assert not any("applied at the mesh's corners" in t for t in said), said


def test_rebuilt_mesh_reading_object_coordinates_is_silent(scene, said):
    _setup(scene)
    mat, nt, d = _diffuse("ObjectChecker")
    tc, ch = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexChecker')
    ch.inputs['Scale'].default_value = 4.0
    nt.links.new(tc.outputs['Object'], ch.inputs['Vector'])
    nt.links.new(ch.outputs['Color'], d.inputs['Color'])
    ob = _grid("Grid", mat, 1.6)
    ob.modifiers.new('ss', 'SUBSURF')
    ob.modifiers.new('cast', 'CAST').factor = 0.5
    dacrt, cycles = _render(scene, 'DACRT'), _render(scene, 'CYCLES')
    assert abs(dacrt.mean() - cycles.mean()) < 5e-3, (dacrt.mean(), cycles.mean())
    assert not any("Generated coordinates" in t for t in said), said
    nt.links.new(tc.outputs['Generated'], ch.inputs['Vector'])      # Generated ones: still said
    said.clear()
    _render(scene, 'DACRT')
    assert any("Generated coordinates of a mesh both deformed and rebuilt by modifiers" in t for t in said), said


def test_texture_mapping_min_max_is_not_read_as_in_cycles(scene, said):
    _setup(scene)
    mat, nt, d = _diffuse("Clamped")
    ch = nt.nodes.new('ShaderNodeTexChecker')
    ch.inputs['Scale'].default_value = 3.0
    nt.links.new(ch.outputs['Color'], d.inputs['Color'])
    scenes.plane("Plane", materials=(mat,))
    plain = {e: _render(scene, e) for e in ('DACRT', 'CYCLES')}
    tm = ch.texture_mapping
    tm.use_min = tm.use_max = True
    tm.min, tm.max = (0.4, 0.4, 0.4), (0.6, 0.6, 0.6)     # (a clamp would make it one flat colour)
    said.clear()
    clamped = {e: _render(scene, e) for e in ('DACRT', 'CYCLES')}
    # Cycles renders the same with it and without it; DACRT too, and says nothing about it
    assert np.abs(clamped['CYCLES'] - plain['CYCLES']).max() < 0.05
    assert np.ptp(clamped['CYCLES']) > 0.3
    assert np.abs(clamped['DACRT'] - plain['DACRT']).max() == 0.0
    assert abs(clamped['DACRT'].mean() - clamped['CYCLES'].mean()) < 5e-3
    assert not any("min/max" in t for t in said), said


def _object_checker(name):
    mat, nt, d = _diffuse(name)
    tc, ch = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexChecker')
    ch.inputs['Scale'].default_value = 2.0
    nt.links.new(tc.outputs['Object'], ch.inputs['Vector'])
    nt.links.new(ch.outputs['Color'], d.inputs['Color'])
    return mat, nt, tc


def _as_cycles(scene):
    """(DACRT's image, Cycles') and the share of pixels more than 0.3 apart (a square of the
    wrong colour: the Checker's are 0.8 and 0.2; its edges are sampled differently)."""
    dacrt, cycles = _render(scene, 'DACRT'), _render(scene, 'CYCLES')
    return dacrt, cycles, (np.abs(dacrt - cycles).max(axis=-1) > 0.3).mean()


def test_object_coordinates_of_an_object_as_cycles(scene, said):
    """Texture Coordinate Object with its Object field set: to the object wearing the material
    (as Cycles renders it empty), with a second object sharing the material (it reads the first
    one's space), then to an empty moved, turned and scaled. It had fallen back to the Checker's
    own colour (mean 0.8199 where Cycles has 0.5453), said as 'Texture Coordinate Object of
    another object is not read there'."""
    _setup(scene, (24, 18))
    mat, nt, tc = _object_checker("SelfCoords")
    ob = scenes.plane("Plane", size=1.0, location=(0.5, 0.1, 0.0), materials=(mat,))
    other = scenes.plane("Other", size=1.0, location=(-0.5, -0.3, 0.0), materials=(mat,))
    other.rotation_euler = (0, 0, 0.3)
    tc.object = ob
    dacrt, cycles, apart = _as_cycles(scene)
    assert abs(dacrt.mean() - cycles.mean()) < 5e-3 and apart < 0.02, (dacrt.mean(), cycles.mean(), apart)
    e = scenes.link(bpy.data.objects.new("Handle", None))
    e.location, e.rotation_euler, e.scale = (0.3, -0.2, 0.0), (0, 0, 0.4), (0.7, 1.3, 1.0)
    tc.object = e
    dacrt, cycles, apart = _as_cycles(scene)
    assert abs(dacrt.mean() - cycles.mean()) < 5e-3 and apart < 0.02, (dacrt.mean(), cycles.mean(), apart)
    assert not any("Texture Coordinate" in t for t in said), said
    # the shaded object's own Object coordinates and the empty's in one chain: one space is read
    # per point, so the chain falls back, saying why
    tc2 = nt.nodes.new('ShaderNodeTexCoord')
    ch = next(n for n in nt.nodes if n.type == 'TEX_CHECKER')
    nt.links.new(tc2.outputs['Object'], ch.inputs['Color1'])
    said.clear()
    _render(scene, 'DACRT')
    assert any("Texture Coordinate Object of two objects (the shaded one counts) is not read there" in t
               for t in said), said
