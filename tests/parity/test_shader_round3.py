"""Shader node edge cases against Cycles (hunt 60, "shaders"), each rendered by both engines in
the test: a grid seen from straight above by an orthographic camera (a 1-pixel box filter), its
material's colour from the nodes under test, as an emission (the pixels are the nodes' value)
or as a diffuse colour under a sun straight down (direct light only: almost no noise)."""

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 32


def _direct_box(sc, samples):
    """Both engines at `samples`, direct light only (0 bounces), a 1-pixel Box filter: a
    pixel is the value the nodes give there, so mismatches are exact, not noise."""
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = sc.cycles.use_adaptive_sampling = False
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0


def _scene(wire, shader='emission', setup=None):
    """A 2x2 grid (8x8 quads) filling the view, its material's Emission Color (or Diffuse Color
    under a sun, shader='diffuse') fed by wire(tree) -> socket; setup(object) before."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = RES
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=8, y_subdivisions=8, size=2.0)
    ob = bpy.context.object
    mat, nt, out = scenes._material("M")
    if shader == 'emission':
        sh = nt.nodes.new('ShaderNodeEmission')
        target = sh.inputs['Color']
    else:
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        target = sh.inputs['Color']
        scenes.light('SUN', 3.0, angle=0.0)
    nt.links.new(sh.outputs[0], out.inputs['Surface'])
    nt.links.new(wire(nt), target)
    ob.data.materials.append(mat)
    if setup is not None:
        setup(ob)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    _direct_box(sc, 4)
    return sc


def _both(sc, tmp_path):
    """{engine: RGB (RES, RES, 3)}."""
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        got[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
    return got['CYCLES'], got['DACRT']


def _alternating(name, values, kind='FLOAT', domain='POINT'):
    """setup(object): a point attribute `name` cycling through values."""
    def setup(ob):
        me = ob.data
        a = me.attributes.new(name, kind, domain)
        n = len(a.data)
        v = np.asarray(values, np.float32)[np.arange(n) % len(values)]
        if kind == 'FLOAT':
            a.data.foreach_set('value', v.ravel())
        else:
            a.data.foreach_set('color', v.ravel())
    return setup


def _attribute(name, output):
    def wire(nt):
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = name
        return a.outputs[output]
    return wire


@pytest.mark.parametrize('case', ['fac', 'color'])
def test_negative_attribute_values_clamped_after_interpolation(case, tmp_path):
    """A point attribute with negative values (a float -1 / 1.5; a colour with negative
    channels) into a Diffuse Color: Cycles interpolates the attribute and clamps the closure
    weight per point, so a -1 corner darkens its triangles. It had been clamped per corner
    first: 1.67x (float) and 1.16x (colour) Cycles' mean; now within 1%."""
    if case == 'fac':
        setup = _alternating('f', [-1.0, 1.5])
    else:
        setup = _alternating('f', [(-0.5, 0.3, 1.8, 1.0), (1.2, 0.2, -0.4, 1.0)], 'FLOAT_COLOR')
    sc = _scene(_attribute('f', 'Fac' if case == 'fac' else 'Color'), 'diffuse', setup)
    c, d = _both(sc, tmp_path)
    mc, md = c.mean(axis=(0, 1)), d.mean(axis=(0, 1))
    assert mc.mean() > 0.05
    assert np.abs(md - mc).max() < 0.01 * mc.max(), (mc, md)



def _attribute_math(name, operation, b=0.0, c=0.0):
    """An Attribute's Fac through a Math node."""
    def wire(nt):
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = name
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = operation
        m.inputs[1].default_value, m.inputs[2].default_value = b, c
        nt.links.new(a.outputs['Fac'], m.inputs[0])
        return m.outputs[0]
    return wire


def test_negative_attribute_values_through_nodes(tmp_path, said):
    """An attribute of -1 / 1.5 through an affine chain whose result goes below 0 (x -0.5 + 0.6)
    is interpolated, then clamped, as in Cycles, and nothing said (it had been reported as
    evaluated at the corners: the export's probes took the negative results for a clamp); one
    that bends below 0 (an Absolute) had been taken for an identity on probes of 0 and above
    (silent, 1.9x Cycles), then evaluated at the corners and said; it is computed per point
    after the interpolation, as Cycles, and silent."""
    sc = _scene(_attribute_math('f', 'MULTIPLY_ADD', -0.5, 0.6), 'diffuse', _alternating('f', [-1.0, 1.5]))
    c, d = _both(sc, tmp_path)
    assert c.mean() > 0.05 and abs(d.mean() - c.mean()) < 0.01 * c.mean(), (c.mean(), d.mean())
    assert not any("approximated" in t for t in said), said
    del said[:]
    sc = _scene(_attribute_math('f', 'ABSOLUTE'), 'diffuse', _alternating('f', [-1.0, 1.5]))
    c, d = _both(sc, tmp_path)
    assert c.mean() > 0.05 and abs(d.mean() - c.mean()) < 0.01 * c.mean(), (c.mean(), d.mean())
    assert not any("approximated" in t for t in said), said


def _strip(wires, tmp_path, samples=4):
    """One emissive 2x2 grid per wire(tree) -> socket (its Emission Color) in a row, seen from
    above; {engine: (n, 32, 32, 3)} each grid's pixels."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    n = len(wires)
    sc.render.resolution_x, sc.render.resolution_y = RES * n, RES
    for i, wire in enumerate(wires):
        mat, nt, out = scenes._material(f"M{i}")
        em = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(em.outputs[0], out.inputs['Surface'])
        nt.links.new(wire(nt), em.inputs['Color'])
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=8, y_subdivisions=8, size=2.0, location=(2.0 * i - (n - 1), 0, 0))
        bpy.context.object.data.materials.append(mat)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0 * n)
    scenes.black_world()
    _direct_box(sc, samples)
    c, d = _both(sc, tmp_path)
    split = lambda img: np.stack([img[:, RES * i:RES * (i + 1)] for i in range(n)])
    return split(c), split(d)


def _group(socket_type, name=None):
    """A node group whose one input of socket_type is wired straight to its one output."""
    g = bpy.data.node_groups.new(name or socket_type, 'ShaderNodeTree')
    g.interface.new_socket('In', in_out='INPUT', socket_type=socket_type)
    g.interface.new_socket('Out', in_out='OUTPUT', socket_type=socket_type)
    g.links.new(g.nodes.new('NodeGroupInput').outputs[0], g.nodes.new('NodeGroupOutput').inputs[0])
    return g


def _through_group(socket_type, make):
    def wire(nt):
        node = nt.nodes.new('ShaderNodeGroup')
        node.node_tree = _group(socket_type, f"{socket_type}{len(bpy.data.node_groups)}")
        nt.links.new(make(nt), node.inputs[0])
        return node.outputs[0]
    return wire


def _through_muted(node_type, make, read_as_float=False):
    def wire(nt):
        node = nt.nodes.new(node_type)
        node.mute = True
        nt.links.new(make(nt), node.inputs['Color' if node_type == 'ShaderNodeInvert' else 0])
        if not read_as_float:
            return node.outputs[0]
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = 'ADD'
        m.inputs[1].default_value = 0.0
        nt.links.new(node.outputs[0], m.inputs[0])
        return m.outputs[0]
    return wire


def _generated(nt):
    return nt.nodes.new('ShaderNodeTexCoord').outputs['Generated']


def _mapped(nt):
    m = nt.nodes.new('ShaderNodeMapping')
    m.inputs['Scale'].default_value = (1.0, 2.0, 0.5)
    nt.links.new(_generated(nt), m.inputs['Vector'])
    return m.outputs[0]


def _constant(kind):
    """A constant colour or vector made by a node Blender folds (Combine XYZ, Mix) or does not
    (RGB, Combine Color)."""
    def make(nt):
        if kind == 'combine':
            n = nt.nodes.new('ShaderNodeCombineXYZ')
            for i, x in enumerate((0.9, 0.2, 0.1)):
                n.inputs[i].default_value = x
            return n.outputs[0]
        if kind == 'mix':
            n = nt.nodes.new('ShaderNodeMix')
            n.data_type = 'RGBA'
            n.inputs['Factor'].default_value = 0.0
            n.inputs[6].default_value = (0.9, 0.2, 0.1, 1.0)
            return n.outputs[2]
        if kind == 'rgb':
            n = nt.nodes.new('ShaderNodeRGB')
            n.outputs[0].default_value = (0.9, 0.2, 0.1, 1.0)
            return n.outputs[0]
        n = nt.nodes.new('ShaderNodeCombineColor')
        for i, x in enumerate((0.9, 0.2, 0.1)):
            n.inputs[i].default_value = x
        return n.outputs[0]
    return make


def _value_node(v):
    def make(nt):
        n = nt.nodes.new('ShaderNodeValue')
        n.outputs[0].default_value = v
        return n.outputs[0]
    return make


def _math_of(make):
    """make's output read by a Math Add 0 (as a float)."""
    def wire(nt):
        m = nt.nodes.new('ShaderNodeMath')
        m.operation = 'ADD'
        m.inputs[1].default_value = 0.0
        nt.links.new(make(nt), m.inputs[0])
        return m.outputs[0]
    return wire


def test_values_through_group_sockets_and_muted_nodes(tmp_path):
    """Blender 5.0 inlines the tree for Cycles: a varying value passes a group's Float, Int or
    Color socket, or a muted node of another type, unchanged and is converted where it is read
    by the type of the output that made it (Generated read as a colour: the vector; as a float:
    its average); only a constant Blender folds (Combine XYZ, Mix, Value) is converted at the
    socket (average, luminance, truncation), one from a node it does not fold (RGB, Combine Color)
    passes unchanged. The varying vectors had been averaged at the socket: grey where Cycles
    shows the coordinates (mean |D-C| 0.08-0.18)."""
    cases = [
        _through_group('NodeSocketFloat', _generated),
        _through_muted('ShaderNodeMath', _generated),
        _through_group('NodeSocketFloat', _mapped),
        _through_group('NodeSocketInt', _generated),
        _math_of(_through_group('NodeSocketColor', _generated)),       # average, not luminance
        _through_muted('ShaderNodeInvert', _generated, read_as_float=True),
        _through_group('NodeSocketFloat', _constant('combine')),        # folded: average
        _through_group('NodeSocketFloat', _constant('mix')),            # folded: luminance
        _through_group('NodeSocketFloat', _constant('rgb')),            # not folded: the colour
        _through_group('NodeSocketFloat', _constant('combine_color')),  # not folded: the colour
        _through_group('NodeSocketInt', _value_node(0.7)),              # folded: truncated to 0
    ]
    c, d = _strip(cases, tmp_path)
    inner = (slice(2, -2), slice(2, -2))
    diff = np.abs(d - c)[:, inner[0], inner[1]].mean(axis=(1, 2, 3))
    # the varying ones are coloured (not grey) in Cycles, the truncated constant black
    assert np.abs(c[0, ..., 0] - c[0, ..., 1]).mean() > 0.05
    assert c[10, 8:24, 8:24].max() < 1e-3
    assert diff.max() < 0.01, diff.round(4).tolist()


def _power_of_zero(exponent, vector=False):
    """0 ^ exponent(tree) (Math or Vector Math Power), x 0.2 + 0.5."""
    def wire(nt):
        e = exponent(nt)
        if vector:
            c = nt.nodes.new('ShaderNodeCombineXYZ')
            for i in range(3):
                nt.links.new(e, c.inputs[i])
            p = nt.nodes.new('ShaderNodeVectorMath')
            p.operation = 'POWER'
            p.inputs[0].default_value = (0.0, 0.0, 0.0)
            nt.links.new(c.outputs[0], p.inputs[1])
            post = nt.nodes.new('ShaderNodeVectorMath')
            post.operation = 'MULTIPLY_ADD'
            post.inputs[1].default_value, post.inputs[2].default_value = (0.2,) * 3, (0.5,) * 3
        else:
            p = nt.nodes.new('ShaderNodeMath')
            p.operation = 'POWER'
            p.inputs[0].default_value = 0.0
            nt.links.new(e, p.inputs[1])
            post = nt.nodes.new('ShaderNodeMath')
            post.operation = 'MULTIPLY_ADD'
            post.inputs[1].default_value, post.inputs[2].default_value = 0.2, 0.5
        nt.links.new(p.outputs[0], post.inputs[0])
        return post.outputs[0]
    return wire


def _x_minus_half(nt):
    s = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(_generated(nt), s.inputs[0])
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'SUBTRACT'
    m.inputs[1].default_value = 0.5
    nt.links.new(s.outputs[0], m.inputs[0])
    return m.outputs[0]


def test_power_of_zero_to_a_negative_exponent(tmp_path):
    """Math and Vector Math Power of base 0 and a negative exponent varying over the grid
    (Generated x - 0.5: negative on its left half): Cycles' kernel gives 0 there (the pixels
    0.5 after x 0.2 + 0.5), where numpy's inf had made the emission non-finite and black (mean
    0.126 where Cycles has 0.263). A Power of constants, which Blender folds with its own pow
    before Cycles sees it, is inf there, black in both (said)."""
    cases = [_power_of_zero(_x_minus_half), _power_of_zero(_x_minus_half, vector=True),
             _power_of_zero(_value_node(-1.0))]
    c, d = _strip(cases, tmp_path)
    assert np.abs(c[0, 8:24, 2:10] - 0.5).max() < 1e-3          # the left half: 0 ^ negative -> 0
    assert c[2].max() < 1e-3
    diff = np.abs(d - c)[:, 2:-2, 2:-2].mean(axis=(1, 2, 3))
    assert diff.max() < 0.01, diff.round(4).tolist()


def _modulo(a, read):
    """Vector Math Modulo of a(tree) by (0, 0.7, 0.7): read 'float' (a Math Add 0, the average)
    or 'x' (Separate X + 0.25)."""
    def wire(nt):
        m = nt.nodes.new('ShaderNodeVectorMath')
        m.operation = 'MODULO'
        nt.links.new(a(nt), m.inputs[0])
        m.inputs[1].default_value = (0.0, 0.7, 0.7)
        add = nt.nodes.new('ShaderNodeMath')
        add.operation = 'ADD'
        if read == 'float':
            add.inputs[1].default_value = 0.0
            nt.links.new(m.outputs[0], add.inputs[0])
        else:
            s = nt.nodes.new('ShaderNodeSeparateXYZ')
            nt.links.new(m.outputs[0], s.inputs[0])
            add.inputs[1].default_value = 0.25
            nt.links.new(s.outputs[0], add.inputs[0])
        return add.outputs[0]
    return wire


def test_vector_modulo_by_zero(tmp_path):
    """Vector Math Modulo by a zero component: Cycles' kernel gives 0 there (safe_modulo), so
    Generated mod (0, 0.7, 0.7) read as a float is its other components' average and its X
    + 0.25 is 0.25; DACRT had NaN there, black (Generated mod (0, 0.5, 0.5) on a tilted plane:
    0.0000 where Cycles' mean is 0.0860, 0 where it is 0.25).
    A Modulo of constants, which Blender folds (NaN there), is black in both."""
    cases = [_modulo(_generated, 'float'), _modulo(_generated, 'x'), _modulo(_constant('combine'), 'x')]
    c, d = _strip(cases, tmp_path)
    assert np.abs(c[1, 2:-2, 2:-2] - 0.25).max() < 1e-4 and c[2].max() < 1e-3
    diff = np.abs(d - c)[:, 2:-2, 2:-2].mean(axis=(1, 2, 3))
    assert diff.max() < 0.01, diff.round(4).tolist()


def _nan_image():
    """A 4x4 float image whose left half is NaN (0.5 elsewhere)."""
    px = np.full((4, 4, 4), 0.5, np.float32)
    px[:, :2, :3] = np.nan
    px[..., 3] = 1.0
    return scenes.float_image("NaNs", px)


def _nan_alpha_material(i, kind):
    mat, nt, out = scenes._material(f"N{i}")
    if kind == 'principled':
        p = nt.nodes.new('ShaderNodeBsdfPrincipled')
        noise = nt.nodes.new('ShaderNodeTexNoise')
        noise.inputs['Scale'].default_value = float('nan')
        nt.links.new(noise.outputs['Fac'], p.inputs['Alpha'])
        nt.links.new(p.outputs[0], out.inputs['Surface'])
        return mat
    mix = nt.nodes.new('ShaderNodeMixShader')
    clear, d = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    first_clear = kind == 'mix_first_clear'
    nt.links.new(clear.outputs[0], mix.inputs[1 if first_clear else 2])
    nt.links.new(d.outputs[0], mix.inputs[2 if first_clear else 1])
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = _nan_image(), 'Closest'
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY'
    m.inputs[1].default_value = 1.0
    nt.links.new(tex.outputs['Color'], m.inputs[0])
    nt.links.new(m.outputs[0], mix.inputs['Fac'])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def test_nan_alpha_is_transparent(tmp_path):
    """A NaN Principled Alpha (a Noise of NaN Scale) and a NaN Mix Shader factor computed per
    texel (NaN texels through a Math node) are 0 in Cycles: the Principled fully transparent,
    the Mix its first shader. DACRT had read them as 1: the Principled opaque (0.64 where
    Cycles shows the grey world, 0.30), the Mix its second shader."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    kinds = ('principled', 'mix_first_clear', 'mix_second_clear')
    sc.render.resolution_x, sc.render.resolution_y = RES * len(kinds), RES
    for i, kind in enumerate(kinds):
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=8, y_subdivisions=8, size=2.0, location=(2.0 * i - 2.0, 0, 0))
        bpy.context.object.data.materials.append(_nan_alpha_material(i, kind))
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=6.0)
    scenes.light('SUN', 3.0, angle=0.0)
    scenes.world((0.3, 0.3, 0.3))
    _direct_box(sc, 16)
    c, d = _both(sc, tmp_path)
    mc = np.array([c[:, RES * i:RES * (i + 1)].mean() for i in range(len(kinds))])
    md = np.array([d[:, RES * i:RES * (i + 1)].mean() for i in range(len(kinds))])
    assert abs(mc[0] - 0.3) < 1e-3                 # the world seen through
    assert np.abs(md - mc).max() < 0.02 * mc.max(), (mc, md)
