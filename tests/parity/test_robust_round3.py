"""Bad node set-ups and values rendered as Cycles renders them (hunt "robust", round 3). Each
scene is a plane filling an orthographic view from above under a uniform white world, no
bounces, so a pixel is the surface's albedo (or emission + albedo); both engines render it and
the means are compared."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(res=(16, 12), samples=16):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = res
    sc.view_settings.view_transform = 'Standard'
    scenes.world((1, 1, 1))
    scenes.camera((0, 0, 3), kind='ORTHO', ortho_scale=2.0)
    sc.dacrt.samples, sc.dacrt.max_bounces = samples, 0
    c = sc.cycles
    c.device, c.samples, c.max_bounces, c.use_denoising, c.use_adaptive_sampling = 'CPU', samples, 0, False, False
    return sc


def _diffuse(name, color=(0.3, 0.45, 0.7)):
    mat = scenes.diffuse(name, color)
    nt = mat.node_tree
    return mat, nt, next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')


def _both(sc):
    out = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        out[engine] = scenes.render_rgba(sc)[2:-2, 2:-2, :3].astype(np.float64)   # (the plane alone)
    return out


def _group_without_output(name, socket_type):
    ng = bpy.data.node_groups.new(name, 'ShaderNodeTree')
    s = ng.interface.new_socket("Out", in_out='OUTPUT', socket_type=socket_type)
    if socket_type != 'NodeSocketShader':
        s.default_value = (0.9, 0.1, 0.1, 1.0) if socket_type == 'NodeSocketColor' else \
            (0.5, 0.5, 0.5) if socket_type == 'NodeSocketVector' else 0.7
    return ng


@pytest.mark.parametrize('kind', ['NodeSocketColor', 'NodeSocketFloat', 'NodeSocketVector'])
def test_group_without_group_output_reads_zero(kind):
    """A group whose tree has no Group Output: Cycles reads each output as 0 of its type (the
    interface default and the input's own value unused): a colour or float into the Diffuse
    Color is black, a vector into a Checker's Vector the point 0 (one colour, not the pattern
    of its default coordinates). Before, the Diffuse's own colour (0.3, 0.45, 0.7) and the
    checker's pattern (means 0.45 / 0.45 where Cycles gives 0.1 / 0.8)."""
    sc = _scene()
    mat, nt, d = _diffuse("M")
    g = nt.nodes.new('ShaderNodeGroup')
    g.node_tree = _group_without_output("NoOut", kind)
    if kind == 'NodeSocketVector':
        c = nt.nodes.new('ShaderNodeTexChecker')
        c.inputs['Scale'].default_value = 3.0
        c.inputs['Color1'].default_value = (0.8, 0.1, 0.1, 1.0)
        c.inputs['Color2'].default_value = (0.1, 0.8, 0.1, 1.0)
        nt.links.new(g.outputs[0], c.inputs['Vector'])
        nt.links.new(c.outputs['Color'], d.inputs['Color'])
    else:
        nt.links.new(g.outputs[0], d.inputs['Color'])
    scenes.plane("P", materials=(mat,))
    img = _both(sc)
    mc, md = (img[e].mean(axis=(0, 1)) for e in ('CYCLES', 'DACRT'))
    assert np.abs(md - mc).max() < 0.02, (mc, md)
    if kind == 'NodeSocketVector':
        assert np.ptp(img['CYCLES'], axis=(0, 1)).max() < 0.05     # one colour: the checker at 0
    else:
        assert mc.max() < 0.01


def _nan_attribute_plane(name, domain='CORNER', kind='FLOAT_COLOR', nan_channel=0):
    """A plane (two triangles) whose attribute 'Col' is (0.8, 0.5, 0.2) with NaN in one channel
    at the first corner / point (a FLOAT attribute: 0.6, NaN there)."""
    ob = scenes.plane(name)
    me = ob.data
    if kind == 'FLOAT':
        a = me.attributes.new('Col', 'FLOAT', domain)
        v = np.full(len(a.data), 0.6, np.float32)
        v[0] = np.nan
        a.data.foreach_set('value', v)
    else:
        a = me.color_attributes.new('Col', kind, domain)
        c = np.tile(np.array([0.8, 0.5, 0.2, 1.0], np.float32), (len(a.data), 1))
        c[0, nan_channel] = np.nan
        a.data.foreach_set('color', c.ravel())
    return ob


def test_nan_in_one_channel_of_a_colour_attribute_blacks_that_channel_only():
    """NaN in the R channel of one corner of a corner colour attribute into a Diffuse Color:
    Cycles drops that channel of the closure on the triangles around it, G and B stay shaded.
    Before, every channel of both triangles was black: (0, 0, 0) where Cycles gives
    (0, 0.5, 0.2)."""
    sc = _scene()
    mat, nt, d = _diffuse("M")
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = 'Col'
    nt.links.new(a.outputs['Color'], d.inputs['Color'])
    ob = _nan_attribute_plane("P")
    ob.data.materials.append(mat)
    img = _both(sc)
    mc, md = (img[e].mean(axis=(0, 1)) for e in ('CYCLES', 'DACRT'))
    assert mc[0] < 0.01 and mc[1] > 0.4, mc
    assert np.abs(md - mc).max() < 0.02, (mc, md)


@pytest.mark.parametrize('case', ['emission', 'float_combine'])
def test_nan_attribute_through_emission_or_nodes_blacks_the_channel_it_reaches(case):
    """A NaN attribute value reaching a shader other than straight into a Diffuse Color: (a) a
    corner colour attribute NaN in R at one corner into an Emission's Color, (b) a point Float
    attribute NaN at one vertex through Combine Color's R into a Diffuse Color. Cycles
    interpolates the NaN over the triangles around it and the nodes after compute with it: the
    channel it reaches is black there. Before, it was read as 0 at that corner and blended into
    the rest (the emission's R lit 1.03 where Cycles' is 0.002; the Combine's R 0.70 vs 0.42)."""
    sc = _scene()
    if case == 'emission':
        mat = scenes.emission("M", (1, 1, 1), 2.0)
        nt = mat.node_tree
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = 'Col'
        nt.links.new(a.outputs['Color'], next(n for n in nt.nodes if n.type == 'EMISSION').inputs['Color'])
        ob = _nan_attribute_plane("P")
    else:
        mat, nt, d = _diffuse("M")
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = 'Col'
        cc = nt.nodes.new('ShaderNodeCombineColor')
        cc.inputs[1].default_value, cc.inputs[2].default_value = 0.6, 0.3
        nt.links.new(a.outputs['Fac'], cc.inputs[0])
        nt.links.new(cc.outputs[0], d.inputs['Color'])
        ob = _nan_attribute_plane("P", 'POINT', 'FLOAT')
    ob.data.materials.append(mat)
    img = _both(sc)
    mc, md = (img[e].mean(axis=(0, 1)) for e in ('CYCLES', 'DACRT'))
    assert mc[0] < (0.1 if case == 'emission' else 0.5), mc        # R black on the NaN's triangles
    assert np.abs(md - mc).max() < 0.02, (mc, md)


def _mix_cycle(nt):
    """Two Mix (Color) nodes linked into each other (Blender marks one link invalid): the
    second's Result."""
    a, b = nt.nodes.new('ShaderNodeMix'), nt.nodes.new('ShaderNodeMix')
    a.data_type = b.data_type = 'RGBA'
    nt.links.new(a.outputs[2], b.inputs[6])
    nt.links.new(b.outputs[2], a.inputs[6])
    return b.outputs[2]


@pytest.mark.parametrize('where', ['feeding', 'aside', 'world'])
def test_link_cycle_renders_black(where):
    """A link cycle in a material's tree, feeding the Diffuse Color or on a branch feeding
    nothing, or in the world's: Cycles compiles nothing of the tree, black. Before, the invalid
    link was skipped and the rest rendered: the Mix's grey (0.5) or the Diffuse colour, and the
    white world (1.0) instead of black."""
    sc = _scene()
    mat, nt, d = _diffuse("M")
    if where == 'world':
        wt = sc.world.node_tree
        wt.links.new(_mix_cycle(wt), next(n for n in wt.nodes if n.type == 'BACKGROUND').inputs['Color'])
        bpy.ops.mesh.primitive_plane_add(size=0.5)         # (a small plane: the world around it)
        bpy.context.object.data.materials.append(mat)
    else:
        out = _mix_cycle(nt)
        if where == 'feeding':
            nt.links.new(out, d.inputs['Color'])
        scenes.plane("P", materials=(mat,))
    img = _both(sc)
    mc, md = (img[e].mean(axis=(0, 1)) for e in ('CYCLES', 'DACRT'))
    assert mc.max() < 0.01, mc
    assert np.abs(md - mc).max() < 0.01, (mc, md)
