"""The export of procedural textures (addon/export/procedurals.py): which chains become a
per-point texture (procedural.ProceduralTexels) and which fall back to the node's own value
with a reason, and the texture coordinates the geometry carries for them (Generated from the
undeformed mesh in its texture space, Object in object space, per instance). Images against
Cycles are in tests/parity/test_procedural.py."""
import bpy
import numpy as np

from addon.procedural import ProceduralTexels
from tests.addon import scenes


def _noise_material(name, noise_type='FBM', dimensions='3D', coordinates=None):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.noise_type, nz.noise_dimensions = noise_type, dimensions
    if coordinates:
        tc = nt.nodes.new('ShaderNodeTexCoord')
        nt.links.new(tc.outputs[coordinates], nz.inputs['Vector'])
    nt.links.new(nz.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _material(data, name):
    return next(m for m in data.materials if m.name == name)


def test_noise_chain_is_a_procedural_texture(scene, exported):
    scenes.camera()
    scenes.cube("Cube", materials=(_noise_material("Noise"),))
    m = _material(exported(), "Noise")
    assert isinstance(m.texture, ProceduralTexels)
    assert m.texture.needs == {'generated'}
    assert not m.approximated, m.approximated


def test_every_noise_dimension_and_type_is_read(scene, exported):
    """1D (W alone) and 4D noise are evaluated per point as 2D and 3D are (they had kept the
    node's own value, said "(4D noise is not read there)"); every noise type too."""
    scenes.camera()
    scenes.cube("Cube", materials=(_noise_material("Ridged", noise_type='RIDGED_MULTIFRACTAL'),))
    scenes.cube("Cube2", location=(3, 0, 0), materials=(_noise_material("FourD", dimensions='4D'),))
    scenes.cube("Cube3", location=(6, 0, 0), materials=(_noise_material("OneD", dimensions='1D'),))
    data = exported()
    for name in ("Ridged", "FourD", "OneD"):
        m = _material(data, name)
        assert isinstance(m.texture, ProceduralTexels), name
        assert not m.approximated, (name, m.approximated)


def test_what_a_procedural_chain_cannot_read_is_named(scene, exported):
    """A supported texture fed by something the per-point evaluation does not read falls back
    to its own value, and the message names that thing (it had blamed the Checker alone:
    "colour from 'Checker Texture' node; its own value used")."""
    scenes.camera()
    # (a Vector Rotate, once the first example, is read: tests/parity/test_wavelength_rotate.py)
    for i, (name, build) in enumerate((("VTransform", 'VECT_TRANSFORM'), ("ObjCoords", 'OBJECT'), ("Camera", 'Camera'))):
        mat = bpy.data.materials.new(name)
        nt = mat.node_tree
        bsdf = next(n for n in nt.nodes if n.type == 'BSDF_PRINCIPLED')
        checker = nt.nodes.new('ShaderNodeTexChecker')
        coords = nt.nodes.new('ShaderNodeTexCoord')
        nt.links.new(checker.outputs['Color'], bsdf.inputs['Base Color'])
        if build == 'VECT_TRANSFORM':
            vm = nt.nodes.new('ShaderNodeVectorTransform')
            nt.links.new(coords.outputs['Object'], vm.inputs[0])
            nt.links.new(vm.outputs['Vector'], checker.inputs['Vector'])
            expect = "('Vector Transform' node is not read there)"
        elif build == 'OBJECT':
            # (Object of another object is read: tests/addon/test_node_messages.py; of two, not)
            coords.object = scenes.camera()
            nt.links.new(coords.outputs['Object'], checker.inputs['Vector'])
            nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Object'], checker.inputs['Color1'])
            expect = "(Texture Coordinate Object of two objects (the shaded one counts) is not read there)"
        else:
            nt.links.new(nt.nodes.new('ShaderNodeNewGeometry').outputs['Tangent'], checker.inputs['Vector'])
            expect = "(Geometry Tangent is not read there)"
        scenes.cube(name, location=(3 * i, 0, 0), materials=(mat,))
        m = _material(exported(), name)
        assert not isinstance(m.texture, ProceduralTexels)
        assert expect in m.approximated and "Checker Texture" in m.approximated, m.approximated


def test_generated_coordinates_are_undeformed_and_object_coordinates_are_not(scene, exported):
    """A Displace modifier (strength 0.3, midlevel 0.5, no texture) pushes the cube's corners
    out by 0.15 along their normals: Cycles'
    Generated coordinates stay those of the undeformed cube (its texture space 0..1), Object
    coordinates are where the surface is."""
    scenes.camera()
    cube = scenes.cube("Cube", size=2.0, materials=(_noise_material("Noise", coordinates='Object'),))
    gen = scenes.cube("Gen", size=2.0, location=(4, 0, 0), materials=(_noise_material("Gen"),))
    for ob in (cube, gen):
        ob.modifiers.new("d", 'DISPLACE').strength = 0.3
    data = exported()
    g = data.geometry
    assert g.coords is not None
    rows, names = np.asarray(g.coords), [m.name for m in data.materials]
    gen_rows = rows[np.asarray(g.material) == names.index("Gen")]
    np.testing.assert_allclose(np.sort(np.unique(gen_rows[..., 0:3].round(5))), [0.0, 1.0])
    obj_rows = rows[np.asarray(g.material) == names.index("Noise")]
    corner = 1.0 + 0.15 / np.sqrt(3.0)          # displaced along the corner's smooth normal
    np.testing.assert_allclose(np.abs(obj_rows[..., 3:6]), corner, rtol=1e-5)


def test_a_modifiers_keyed_render_switch_counts_at_the_rendered_frame(scene, exported, tmp_path):
    """Generated coordinates follow the modifiers on at the frame rendered: a Displace keyed
    on by frame 4 is left out of them (the undeformed cube, 0..1) in an animation render of
    frame 4 from a file at frame 1, where it is off (they had moved with the displaced
    surface), as in a still render of frame 4."""
    scenes.camera()
    cube = scenes.cube("Gen", size=2.0, materials=(_noise_material("Gen"),))
    mod = cube.modifiers.new("d", 'DISPLACE')
    mod.strength = 0.3
    scenes.keyed(mod, 'show_render', {1: False, 4: True})
    scenes.animation_of_one_frame(scene, 4, tmp_path)
    g = exported(animation=True).geometry
    assert g.coords is not None
    assert np.abs(g.vertices).max() > 1.05                      # displaced at frame 4
    np.testing.assert_allclose(np.sort(np.unique(np.asarray(g.coords)[..., 0:3].round(5))), [0.0, 1.0])


def test_mirrored_instances_keep_object_coordinates_per_corner(scene, exported):
    """Two instances, one mirrored (its corners rewound): each exported corner's Object
    coordinate is its vertex's object-space position."""
    scenes.camera()
    a = scenes.cube("A", size=1.0, materials=(_noise_material("Obj", coordinates='Object'),))
    b = bpy.data.objects.new("B", a.data)
    b.location, b.scale = (3, 0, 0), (-1, 1, 1)
    bpy.context.scene.collection.objects.link(b)
    g = exported().geometry
    V, T = np.asarray(g.vertices, np.float64), np.asarray(g.triangles)
    world = V[T]                                  # (m, 3, 3) corners in world space
    obj = np.asarray(g.coords)[..., 3:6]
    # instance A sits at the origin, B at x = 3 mirrored: world = (sx (x) + tx, y, z)
    sx = np.where(world[..., 0].mean(axis=1, keepdims=True) > 1.5, -1.0, 1.0)
    tx = np.where(sx > 0, 0.0, 3.0)
    np.testing.assert_allclose(world[..., 0], sx * obj[..., 0] + tx, atol=1e-5)
    np.testing.assert_allclose(world[..., 1:], obj[..., 1:], atol=1e-5)


def _voronoi_material(name, **settings):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    v = nt.nodes.new('ShaderNodeTexVoronoi')
    for k, value in settings.items():
        if k in v.inputs:
            v.inputs[k].default_value = value
        else:
            setattr(v, k, value)
    nt.links.new(v.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def test_voronoi_features_are_evaluated(scene, exported):
    """Voronoi F1 of one octave (Detail 0, or Roughness 0: Cycles then takes one octave too) and
    of Detail's octaves, F2, Minkowski and 4D are evaluated per point, nothing said (they had
    kept the node's own value, said)."""
    scenes.camera()
    cases = {"F1": {}, "OneOctave": {'Detail': 3.0, 'Roughness': 0.0}, "Fractal": {'Detail': 2.0},
             "F2": {'feature': 'F2'}, "Minkowski": {'distance': 'MINKOWSKI'}, "FourD": {'voronoi_dimensions': '4D'}}
    for i, (name, settings) in enumerate(cases.items()):
        scenes.cube(name, location=(3 * i, 0, 0), materials=(_voronoi_material(name, **settings),))
    data = exported()
    for name in cases:
        m = _material(data, name)
        supported = True
        assert isinstance(m.texture, ProceduralTexels) == supported, name
        assert ("Voronoi Texture" in m.approximated) != supported, (name, m.approximated)


def test_a_group_used_twice_reaches_its_noise_on_the_second_use(scene, exported):
    """One 'Tint' group (a Multiply of its input) used twice, fed by an RGB node and by a Noise:
    the Noise is found through the second use (the walk had marked the group's inner node as
    texture-free on the first), so the chain is evaluated per point, nothing reported."""
    g = bpy.data.node_groups.new("Tint", 'ShaderNodeTree')
    g.interface.new_socket("In", in_out='INPUT', socket_type='NodeSocketColor')
    g.interface.new_socket("Out", in_out='OUTPUT', socket_type='NodeSocketColor')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    mul = scenes.mix_node(g, 'MULTIPLY', gi.outputs[0], (0.9, 0.7, 0.5), 1.0)
    g.links.new(mul.outputs['Result'], go.inputs[0])
    mat, nt, out = scenes._material("Twice")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    first, second = nt.nodes.new('ShaderNodeGroup'), nt.nodes.new('ShaderNodeGroup')
    first.node_tree = second.node_tree = g
    rgb = nt.nodes.new('ShaderNodeRGB')
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    noise = nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(rgb.outputs[0], first.inputs[0])
    nt.links.new(noise.outputs['Color'], second.inputs[0])
    both = scenes.mix_node(nt, 'MIX', first.outputs[0], second.outputs[0], 0.5)
    nt.links.new(both.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.camera()
    scenes.cube("Cube", materials=(mat,))
    m = _material(exported(), "Twice")
    assert isinstance(m.texture, ProceduralTexels) and not m.approximated, m.approximated


def test_geometry_nodes_instances_read_their_own_generated_coordinates(scene, exported):
    """A plane instanced on a host plane's points by Geometry Nodes (not realized): its
    Generated coordinates span its own texture space, 0..1 (the instance's `original` is the
    host, whose mesh of the same vertex count had stood in for the instance's)."""
    scenes.camera()
    mat = _noise_material("Gen")
    inst = scenes.plane("Inst", 0.6, location=(0, 0, -50), materials=(mat,))
    inst.hide_render = True
    host = scenes.plane("Host", 2.0)
    ng = bpy.data.node_groups.new("G", 'GeometryNodeTree')
    ng.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    pts, iop = ng.nodes.new('GeometryNodeMeshToPoints'), ng.nodes.new('GeometryNodeInstanceOnPoints')
    info = ng.nodes.new('GeometryNodeObjectInfo')
    info.inputs['Object'].default_value = inst
    ng.links.new(gi.outputs[0], pts.inputs['Mesh'])
    ng.links.new(pts.outputs[0], iop.inputs['Points'])
    ng.links.new(info.outputs['Geometry'], iop.inputs['Instance'])
    ng.links.new(iop.outputs[0], go.inputs[0])
    host.modifiers.new("D", 'DISPLACE').strength = 0.0     # (a deforming modifier on the host too)
    host.modifiers.new("GN", 'NODES').node_group = ng
    data = exported()
    g = data.geometry
    rows = np.asarray(g.coords)[np.asarray(g.material) == [m.name for m in data.materials].index("Gen")]
    assert len(rows) == 4 * 2                   # four instances of the two-triangle plane
    np.testing.assert_allclose(np.sort(np.unique(rows[..., 0:2].round(5))), [0.0, 1.0])
    np.testing.assert_allclose(rows[..., 2], 0.5)          # a flat axis: Cycles' 1/2


def test_a_deformed_and_rebuilt_mesh_says_its_generated_coordinates_are_approximate(scene, exported):
    """A Displace after a Subdivision: Cycles' undeformed coordinates are the subdivided cage,
    which Python cannot read; the evaluated positions stand in, and the render says so (only
    for meshes a procedural texture reads them on)."""
    scenes.camera()
    a = scenes.cube("Textured", materials=(_noise_material("Gen"),))
    b = scenes.cube("Plain", location=(4, 0, 0), materials=(scenes.diffuse("Plain", (0.5, 0.5, 0.5)),))
    for ob in (a, b):
        ob.modifiers.new("S", 'SUBSURF')
        ob.modifiers.new("D", 'DISPLACE').strength = 0.2
    said = [t for _, t in exported().messages if "Generated coordinates of a mesh both deformed and rebuilt" in t]
    assert said and "'Textured'" in said[0] and "'Plain'" not in said[0] and "(S)" in said[0], said


def test_a_chain_that_cannot_be_read_falls_back_and_says_why(scene, exported, monkeypatch):
    """A node the compile cannot read (a socket missing, as in another Blender version) leaves
    the chain to the nodes' own values, with the reason, instead of failing the render."""
    from addon.export import procedurals

    def missing(node, ident, chain, depth):
        raise KeyError(f"no input {ident!r}")
    monkeypatch.setattr(procedurals, '_float', missing)
    scenes.camera()
    scenes.cube("Cube", materials=(_noise_material("Noise"),))
    m = _material(exported(), "Noise")
    assert not isinstance(m.texture, ProceduralTexels)
    assert "procedural texture chain not evaluated per point (KeyError" in m.approximated, m.approximated


def test_a_mix_factor_that_is_not_computed_names_its_source(scene, exported):
    """A Mix Shader factor by a Light Path ray-type output is computed per ray kind, what remains
    approximated said; a procedural factor between an emission and a colour says why it
    is evaluated per point now (an emission mask: texturedmixes._procedural_mix), its message
    gone (it had said "procedural textures ... not evaluated per point", then its own value)."""
    scenes.camera()
    trick, nt, mix, _, _ = scenes.mix_shader_material("Trick", 'ShaderNodeBsdfPrincipled', 'ShaderNodeEmission', 0.3)
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Diffuse Ray'], mix.inputs['Fac'])
    imaged, nt, mix, _, b = scenes.mix_shader_material("Imaged", 'ShaderNodeBsdfDiffuse', 'ShaderNodeEmission')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Imaged image", np.ones((2, 2, 4), np.float32))
    nt.links.new(tex.outputs['Color'], b.inputs['Color'])
    noise, ramp = nt.nodes.new('ShaderNodeTexNoise'), nt.nodes.new('ShaderNodeMapRange')
    nt.links.new(noise.outputs['Fac'], ramp.inputs[0])
    nt.links.new(ramp.outputs[0], mix.inputs['Fac'])
    scenes.plane("A", materials=(trick,))
    scenes.plane("B", location=(3, 0, 0), materials=(imaged,))
    data = exported()
    # (a Light Path output is computed per ray kind now, rayvariants.py: what is said is what
    # remains approximated, the light samples of an emitter to bounce rays alone)
    text = _material(data, "Trick").approximated
    assert "'Light Path' node" not in text, text
    assert "Light Path Is Diffuse Ray: emitters light the scene by light samples with the emission bounce rays " \
           "see" in text, text
    imaged = _material(data, "Imaged")
    assert "Mix Shader factor" not in imaged.approximated, imaged.approximated
    assert isinstance(imaged.emission_texture, ProceduralTexels)


def test_a_procedurals_own_texture_mapping_moves_its_coordinates(scene, exported):
    """A noise with its node's own Texture Mapping (scale 2, moved 0.5) reads at the mapped
    point: its texture at p equals the unmapped one's at 2 p + 0.5 (Cycles applies
    node.texture_mapping before the texture; a checker so mapped matches Cycles within 0.004)."""
    scenes.camera()
    plain, moved = _noise_material("Plain"), _noise_material("Moved")
    nz = next(n for n in moved.node_tree.nodes if n.type == 'TEX_NOISE')
    nz.texture_mapping.scale = (2.0, 2.0, 2.0)
    nz.texture_mapping.translation = (0.5, 0.5, 0.5)
    scenes.cube("A", materials=(plain,))
    scenes.cube("B", location=(4, 0, 0), materials=(moved,))
    data = exported()
    a, b = _material(data, "Plain").texture, _material(data, "Moved").texture
    p = np.random.default_rng(0).random((64, 3)).astype(np.float32)
    np.testing.assert_allclose(b.evaluate({'generated': p}), a.evaluate({'generated': 2 * p + 0.5}), atol=1e-5)
    assert not np.allclose(b.evaluate({'generated': p}), a.evaluate({'generated': p}), atol=1e-3)


def test_a_procedural_on_uv_beside_an_image_on_a_named_map_is_reported(scene, exported):
    """A procedural on Texture Coordinate UV reads the active render map; beside an image read
    on another map (a UV Map node) one map serves the material's triangles, and the render says
    so (it had silently read the procedural on the image's map: 0.45 / 0.45 across a gradient
    where Cycles gives 0.11 / 0.79)."""
    scenes.camera()
    mat = _noise_material("Mixed", coordinates='UV')
    nt = mat.node_tree
    d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
    img = bpy.data.images.new("Normals", 2, 2)
    img.colorspace_settings.name = 'Non-Color'
    tex, nmap, uv = (nt.nodes.new(t) for t in ('ShaderNodeTexImage', 'ShaderNodeNormalMap', 'ShaderNodeUVMap'))
    tex.image, uv.uv_map = img, 'Second'
    nt.links.new(uv.outputs[0], tex.inputs['Vector'])
    nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    cube = scenes.cube("Cube", materials=(mat,))
    for layer in ('UVMap', 'Second'):       # (on a mesh without UV maps both read (0, 0): the same)
        cube.data.uv_layers.new(name=layer)
    m = _material(exported(), "Mixed")
    assert "textures on several UV maps ('Second', the active render map)" in m.approximated, m.approximated
    nt.links.remove(uv.outputs[0].links[0])                  # both on the active map: nothing to say
    assert "several UV maps" not in _material(exported(), "Mixed").approximated
