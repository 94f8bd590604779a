"""Emission coloured or scaled by attributes against Cycles: an Emission's (or a Principled's)
Color or Strength from a Color Attribute or Attribute node (a mesh's point, corner or face
values; an object's or instancer's), through colour and float nodes, computed per shading point
as Cycles does (the attribute interpolated at the point, then the nodes): for camera hits, BSDF
hits and light samples (export/procedurals.compile_emission, the corner values in
Geometry.attributes, the light choice weighing each emitting triangle by the emission at its
corners and centre, Integrator._attribute_emission_power).

Before, such an emission read the node's own value, reported ("colour from 'Color Attribute'
node; its own value used"): a vertex-coloured panel one flat colour."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_procedural_emission import _floor_and_emitter, _rgb, _settings

pytestmark = pytest.mark.usefixtures('parity_addon')


def _grid(name, material, size=2.0, cuts=3, location=(0, 0, 0)):
    """A size x size grid of (cuts + 1)^2 vertices in the xy plane, shaded by material."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=cuts, y_subdivisions=cuts, size=size, location=location)
    ob = bpy.context.object
    ob.name = name
    ob.data.materials.append(material)
    return ob


def _colours(ob, name, domain, kind, values):
    """A colour attribute of ob's mesh, values(n) (n, 3) per element of the domain."""
    attr = ob.data.color_attributes.new(name, kind, domain)
    c = np.ones((len(attr.data), 4), np.float32)
    c[:, :3] = values(len(attr.data))
    attr.data.foreach_set('color', c.ravel())
    return attr


def _emitter(name, wire, principled=False):
    """A material emitting what wire(nt, emission node) links into its Color or Strength: an
    Emission shader, or a Principled BSDF (black base, no specular layer) whose Emission Color
    and Strength wire links."""
    mat, nt, out = scenes._material(name)
    if principled:
        em = nt.nodes.new('ShaderNodeBsdfPrincipled')
        em.inputs['Base Color'].default_value = (0, 0, 0, 1)
        em.inputs['Specular IOR Level'].default_value = 0.0
        em.inputs['Emission Strength'].default_value = 1.0
    else:
        em = nt.nodes.new('ShaderNodeEmission')
        em.inputs['Strength'].default_value = 1.0
    wire(nt, em)
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _color_socket(em):
    return em.inputs['Emission Color'] if em.type == 'BSDF_PRINCIPLED' else em.inputs['Color']


def _strength_socket(em):
    return em.inputs['Emission Strength'] if em.type == 'BSDF_PRINCIPLED' else em.inputs['Strength']


def _seen_from_above(samples=4):
    """An orthographic camera over the 2 x 2 grid at the origin, filling the 48 x 48 frame; a
    black world; no bounces, box pixel filter (each pixel the emission's mean over it)."""
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    _settings(samples, 0)
    return sc


def _blocks(img, b=6):
    h, w = img.shape[:2]
    return img[:h // b * b, :w // b * b].reshape(h // b, b, w // b, b, 3).mean((1, 3))


def _compare_seen(img, tol):
    """6 x 6-pixel blocks within tol of Cycles' brightest block; returns the error."""
    d, c = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    err = float(np.abs(d - c).max() / c.max())
    assert err < tol, (err, d.round(3).tolist(), c.round(3).tolist())
    assert np.ptp(c, axis=(0, 1)).max() > 0.2 * c.max(), "the colours should vary over the panel"
    return err


def _quiet(said):
    assert not any("own value" in t or "not evaluated" in t or "not read" in t for t in said), said


def _random(seed, lo=0.05, hi=1.0):
    rng = np.random.default_rng(seed)
    return lambda n: lo + (hi - lo) * rng.random((n, 3))


@pytest.mark.parametrize('case', ['point_colour', 'corner_colour_ramp', 'face_colour', 'principled'])
def test_attribute_emission_seen_by_the_camera(tmp_path, said, case):
    """A 4 x 4-vertex grid emitting its colours seen straight on: point FLOAT_COLOR colours into
    an Emission's Color ('point_colour', Strength 2); corner BYTE_COLOR colours through a
    Hue/Saturation and a Color Ramp on their red ('corner_colour_ramp': the ramp runs on the
    interpolated value, as Cycles runs it); face colours read by an Attribute node ('face_colour');
    point colours into a Principled's Emission Color ('principled', Strength 3). Each 6 x 6
    block within 1.5% of Cycles' brightest (measured 0.31%, 0.24%, 0.0%, 0.31%); each had been
    one flat colour, the node's own (97%, 99%, 91%, 97% off)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)

    def wire(nt, em):
        s = scenes.colour_attribute(nt, 'Col', by_attribute_node=case == 'face_colour')
        if case == 'corner_colour_ramp':
            hsv = nt.nodes.new('ShaderNodeHueSaturation')
            hsv.inputs['Saturation'].default_value = 1.4
            nt.links.new(s, hsv.inputs['Color'])
            sep = nt.nodes.new('ShaderNodeSeparateColor')
            nt.links.new(hsv.outputs['Color'], sep.inputs['Color'])
            ramp = nt.nodes.new('ShaderNodeValToRGB')
            ramp.color_ramp.elements[0].color = (2.0, 0.3, 0.05, 1)
            ramp.color_ramp.elements[1].color = (0.05, 0.4, 3.0, 1)
            ramp.color_ramp.elements[0].position = 0.2
            ramp.color_ramp.elements[1].position = 0.8
            nt.links.new(sep.outputs['Red'], ramp.inputs['Fac'])
            s = ramp.outputs['Color']
        nt.links.new(s, _color_socket(em))
        _strength_socket(em).default_value = 3.0 if case == 'principled' else 2.0
    mat = _emitter("AttrLight", wire, principled=case == 'principled')
    ob = _grid("Panel", mat)
    domain, kind = {'point_colour': ('POINT', 'FLOAT_COLOR'), 'corner_colour_ramp': ('CORNER', 'BYTE_COLOR'),
                    'face_colour': ('FACE', 'FLOAT_COLOR'), 'principled': ('POINT', 'FLOAT_COLOR')}[case]
    _colours(ob, 'Col', domain, kind, _random(5))
    _seen_from_above()
    err = _compare_seen(_rgb(tmp_path), 0.015)
    print(f"{case}: worst block {err:.4f} of Cycles' brightest")
    _quiet(said)


def test_float_attribute_into_strength(tmp_path, said):
    """A float point attribute 'glow' (0..1) read by an Attribute node's Fac, squared by a Math
    Power and times 4, into an Emission's Strength (colour a warm white): each block within 1.5%
    of Cycles' brightest (measured 0.33%; the Strength's own value 1 before, 67% off). Cycles
    squares the interpolated value: per corner and interpolated it would be brighter between the
    corners."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)

    def wire(nt, em):
        em.inputs['Color'].default_value = (1.0, 0.8, 0.6, 1)
        node = nt.nodes.new('ShaderNodeAttribute')
        node.attribute_name = 'glow'
        pw = nt.nodes.new('ShaderNodeMath')
        pw.operation = 'POWER'
        pw.inputs[1].default_value = 2.0
        mul = nt.nodes.new('ShaderNodeMath')
        mul.operation = 'MULTIPLY'
        mul.inputs[1].default_value = 4.0
        nt.links.new(node.outputs['Fac'], pw.inputs[0])
        nt.links.new(pw.outputs[0], mul.inputs[0])
        nt.links.new(mul.outputs[0], em.inputs['Strength'])
    ob = _grid("Panel", _emitter("Glow", wire))
    attr = ob.data.attributes.new('glow', 'FLOAT', 'POINT')
    attr.data.foreach_set('value', np.random.default_rng(9).random(len(attr.data)).astype(np.float32))
    _seen_from_above()
    err = _compare_seen(_rgb(tmp_path), 0.015)
    print(f"float strength: worst block {err:.4f} of Cycles' brightest")
    _quiet(said)


def _red_blue_panel(material):
    """The emitter over the floor: a 2 x 2 grid of 4 x 2 vertices facing down, its colour
    attribute red on the vertices at x < 0 and blue at x > 0 (a gradient across the middle
    third), strength 6; hidden from the camera."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=3, y_subdivisions=1, size=2.0, location=(0, 0, 1.2))
    ob = bpy.context.object
    ob.name = "Emitter"
    ob.data.materials.append(material)
    attr = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    x = np.array([v.co.x for v in ob.data.vertices])
    c = np.where((x < 0)[:, None], [[1.0, 0.05, 0.02, 1.0]], [[0.02, 0.1, 1.0, 1.0]]).astype(np.float32)
    attr.data.foreach_set('color', c.ravel())
    ob.rotation_euler = (np.pi, 0.0, 0.0)            # facing the floor (x stays x)
    return ob


@pytest.mark.parametrize('sampling', ['AUTO', 'NONE'])
def test_coloured_panel_lights_the_floor(tmp_path, said, sampling):
    """The red-and-blue panel hidden from the camera lights a white floor: light-sampled with
    MIS (each sampled point's own colour, the triangles weighed by their measured emission) or
    by BSDF rays alone (Emission Sampling None). The floor's mean within 2% of Cycles' (measured
    0.05% and 0.5%), each half within 5%, and the red over blue ratio under each half within 4%
    of Cycles' (2.337 / 0.429 vs 2.332 / 0.429 light-sampled, 2.314 / 0.429 vs 2.334 / 0.433 by
    BSDF rays: 0.2%, 0.9%). It had lit the floor with the node's own colour, a white: the
    floor grey 0.403 where Cycles gives (0.205, 0.030, 0.205), the ratio 1.0 under both halves."""
    def material():
        def wire(nt, em):
            node = nt.nodes.new('ShaderNodeVertexColor')
            node.layer_name = 'Col'
            nt.links.new(node.outputs['Color'], em.inputs['Color'])
            em.inputs['Strength'].default_value = 6.0
        mat = _emitter("RedBlue", wire)
        mat.cycles.emission_sampling = sampling
        return mat
    _floor_and_emitter(material, False, _red_blue_panel)
    _settings(256, 1, box=False)
    img = _rgb(tmp_path)
    d, c = img['DACRT'], img['CYCLES']
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02)
    ratios = {}
    for side, cols in (('red', slice(10, 22)), ('blue', slice(26, 38))):
        dm, cm = d[6:30, cols].mean((0, 1)), c[6:30, cols].mean((0, 1))
        ratios[side] = (dm[0] / dm[2], cm[0] / cm[2])
        np.testing.assert_allclose(dm, cm, rtol=0.05, err_msg=side)
    assert ratios['red'][1] > 2.0 and ratios['blue'][1] < 0.5, ratios
    for side, (dr, cr) in ratios.items():
        assert abs(dr / cr - 1.0) < 0.04, (side, ratios)
    print(f"{sampling}: mean {d.mean((0, 1)).round(4)} vs {c.mean((0, 1)).round(4)}; R/B ratios {ratios}")
    _quiet(said)


def test_object_colour_and_object_attribute_into_emission(tmp_path, said):
    """Per object: Object Info Color into an Emission's Color on two planes of their own
    colours; an Attribute of type Object (a custom property 'tint') into the Color of two
    more, times 2. Each plane's centre within 0.5% of Cycles' (measured 0%; the node's own
    white before)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)

    def info_wire(nt, em):
        nt.links.new(nt.nodes.new('ShaderNodeObjectInfo').outputs['Color'], em.inputs['Color'])

    def prop_wire(nt, em):
        node = nt.nodes.new('ShaderNodeAttribute')
        node.attribute_type = 'OBJECT'
        node.attribute_name = 'tint'
        nt.links.new(node.outputs['Color'], em.inputs['Color'])
        em.inputs['Strength'].default_value = 2.0
    info, prop = _emitter("Info", info_wire), _emitter("Prop", prop_wire)
    colours = [(0.9, 0.2, 0.1, 1), (0.1, 0.8, 0.3, 1), (0.2, 0.3, 0.9, 1), (0.7, 0.6, 0.1, 1)]
    for i, col in enumerate(colours):
        ob = scenes.plane(f"P{i}", size=0.45, location=(-0.75 + 0.5 * i, 0, 0), materials=(info if i < 2 else prop,))
        if i < 2:
            ob.color = col
        else:
            ob['tint'] = col
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 16
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    _settings(4, 0)
    img = _rgb(tmp_path)
    got = {e: np.array([im[8, int(32 + (-0.75 + 0.5 * i) * 32)] for i in range(4)]) for e, im in img.items()}
    c, d = got['CYCLES'], got['DACRT']
    assert len({tuple(np.round(v, 3)) for v in c}) == 4, c
    assert np.abs(d - c).max() < 5e-3 * c.max(), (c.round(4).tolist(), d.round(4).tolist())
    _quiet(said)


def test_instances_and_a_mirrored_copy(tmp_path, said):
    """Geometry Nodes instances of a vertex-coloured grid (point colours), each tinted by its
    own Instancer attribute 'ic' (a Mix Multiply of the two into an Emission's Color, Strength
    2), and a mirrored linked duplicate of the grid (scale x -1: its corners rewound): 4 x 4
    blocks within 2% of Cycles' brightest (measured 1.1% at 16 samples, the quads' edges'
    noise; 0.17% at 128; 71% before)."""
    from .test_instancer_attributes import colour_of, instancer
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)

    def wire(nt, em):
        vc = nt.nodes.new('ShaderNodeVertexColor')
        vc.layer_name = 'Col'
        ic = nt.nodes.new('ShaderNodeAttribute')
        ic.attribute_type, ic.attribute_name = 'INSTANCER', 'ic'
        mix = scenes.mix_node(nt, 'MULTIPLY', vc.outputs['Color'], ic.outputs['Color'], 1.0)
        nt.links.new(mix.outputs['Result'], em.inputs['Color'])
        em.inputs['Strength'].default_value = 2.0
    source = _grid("Source", _emitter("Tinted", wire), size=0.8, location=(0, 100, 0))
    _colours(source, 'Col', 'POINT', 'FLOAT_COLOR', _random(7, 0.2))
    instancer("Scatter", [(x, 0, 0) for x in (-1.5, -0.5, 0.5)], source, stores=(('ic', 'FLOAT_COLOR', colour_of),))
    mirror = bpy.data.objects.new("Mirror", source.data)
    bpy.context.scene.collection.objects.link(mirror)
    mirror.location, mirror.scale = (1.5, 0, 0), (-1.0, 1.0, 1.0)
    mirror['ic'] = (1.0, 1.0, 1.0, 1.0)           # (as type Object: the instancer attribute's fallback)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 16
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    _settings(16, 0)
    img = _rgb(tmp_path)
    d, c = _blocks(img['DACRT'], 4), _blocks(img['CYCLES'], 4)
    err = float(np.abs(d - c).max() / c.max())
    print(f"instances: worst block {err:.4f} of Cycles' brightest")
    assert err < 0.02, (err, d[..., 0].round(3).tolist(), c[..., 0].round(3).tolist())
    _quiet(said)


def test_unsupported_attribute_is_still_reported(tmp_path, said):
    """A View Layer attribute into an Emission's Color is not read per point: the render says
    so and reads the socket's own value, as before."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)

    def wire(nt, em):
        node = nt.nodes.new('ShaderNodeAttribute')
        node.attribute_type, node.attribute_name = 'VIEW_LAYER', 'glow'
        nt.links.new(node.outputs['Color'], em.inputs['Color'])
    _grid("Panel", _emitter("ViewLayer", wire))
    sc = _seen_from_above(1)
    sc.render.engine = 'DACRT'
    scenes.render_rgba(sc)
    assert any("procedural emission not evaluated per point (view layer attribute 'glow'" in t for t in said), said


def _dark_panel(material):
    """A 2 x 2 grid of 17 x 17 vertices facing down 1.2 over the floor, black but for two bright
    corner regions of its colour attribute; hidden from the camera."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=16, y_subdivisions=16, size=2.0, location=(0, 0, 1.2))
    ob = bpy.context.object
    ob.name = "Emitter"
    ob.data.materials.append(material)
    attr = ob.data.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
    co = np.array([v.co[:] for v in ob.data.vertices])
    bright = ((co[:, 0] > 0.6) & (co[:, 1] > 0.6)) | ((co[:, 0] < -0.7) & (co[:, 1] < -0.2) & (co[:, 1] > -0.5))
    c = np.zeros((len(co), 4), np.float32)
    c[:, 3] = 1.0
    c[bright, :3] = (1.0, 0.8, 0.5)
    attr.data.foreach_set('color', c.ravel())
    ob.rotation_euler = (np.pi, 0.0, 0.0)
    return ob


def test_light_choice_follows_the_corners(tmp_path, monkeypatch):
    """A panel black but for two bright corner regions lights a floor: each triangle of an
    emission of attributes alone weighs its corners' and centre's emission in the light choice
    (_attribute_emission_power), so the black triangles keep only the floor, 0.1 x the
    material's mean, and the floor's mean stays within 2% of Cycles' (measured 0.5%). On this
    panel at 16 spp relMSE 0.0072 (random points on the triangles 0.0075, one weight for all
    0.20); on a 64 x 64 grid 0.0038 (random points 0.0089: 4 a triangle; one weight 0.34)."""
    from addon import integrator
    weights = []
    measured = integrator.Integrator._attribute_emission_power

    def kept(self, tex, interp, ext, xf, tris):
        measured(self, tex, interp, ext, xf, tris)
        weights.append(self._tri_emission[:, tris].max(axis=0))
    monkeypatch.setattr(integrator.Integrator, '_attribute_emission_power', kept)

    def material():
        def wire(nt, em):
            node = nt.nodes.new('ShaderNodeVertexColor')
            node.layer_name = 'Col'
            nt.links.new(node.outputs['Color'], em.inputs['Color'])
            em.inputs['Strength'].default_value = 30.0
        return _emitter("Corners", wire)
    _floor_and_emitter(material, False, _dark_panel)
    _settings(256, 1, box=False)
    img = _rgb(tmp_path)
    np.testing.assert_allclose(img['DACRT'].mean((0, 1)), img['CYCLES'].mean((0, 1)), rtol=0.02)
    w = weights[0]
    assert len(w) == 2 * 16 * 16
    floor = w.min()
    assert np.isclose(np.sort(w)[len(w) // 2], floor), "most triangles are black: the floor weight"
    assert w.max() > 50 * floor
    print(f"corners: mean {img['DACRT'].mean((0, 1)).round(4)} vs {img['CYCLES'].mean((0, 1)).round(4)}")


def test_procedural_texture_times_attribute_in_a_diffuse_colour(tmp_path, said):
    """A Checker (Object coordinates) times point colours (a Mix Multiply) into a Diffuse
    colour under a straight-down sun, direct light only: the chain, which compile had left to
    the evaluation (the checker's own colour, said 'procedural texture not evaluated per point
    (Color Attribute ... is not read there)'), is computed per point with the colours
    interpolated there: 6 x 6 blocks within 1.5% of Cycles' brightest (measured 0.19%; 44% before)."""
    import math
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, out = scenes._material("CheckerTimesColour")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tc = nt.nodes.new('ShaderNodeTexCoord')
    ck = nt.nodes.new('ShaderNodeTexChecker')
    ck.inputs['Scale'].default_value = 2.0
    ck.inputs['Color1'].default_value = (0.9, 0.9, 0.9, 1)
    ck.inputs['Color2'].default_value = (0.3, 0.3, 0.3, 1)
    nt.links.new(tc.outputs['Object'], ck.inputs['Vector'])
    vc = nt.nodes.new('ShaderNodeVertexColor')
    vc.layer_name = 'Col'
    mix = scenes.mix_node(nt, 'MULTIPLY', ck.outputs['Color'], vc.outputs['Color'], 1.0)
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob = _grid("Panel", mat)
    _colours(ob, 'Col', 'POINT', 'FLOAT_COLOR', _random(3))
    _seen_from_above()
    scenes.light('SUN', math.pi, angle=0.0)
    err = _compare_seen(_rgb(tmp_path), 0.015)
    print(f"checker x colour: worst block {err:.4f} of Cycles' brightest")
    _quiet(said)
