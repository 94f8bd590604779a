"""Hair and point clouds against Cycles where DACRT's tessellation or export had differed
(addon/hair.py, addon/export/strands.py, addon/export/scene.py, addon/export/assembly.py).
The scenes of test_points_curves: a sun and a white world, an orthographic camera on a
transparent film (mean alpha: the area covered; mean colour: the light caught)."""
import math

import bpy


import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.test_points_curves import _scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _small_scene(samples=64):
    sc = _scene()
    sc.render.resolution_x = sc.render.resolution_y = 64
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.use_adaptive_sampling = False
    return sc


def _means(sc, tmp_path):
    layer = sc.view_layers[0].name
    return {e: np.array([exr[f"{layer}.Combined.{c}"].mean() for c in 'RGBA'], np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}


def _zigzag(turn):
    """9 points in the view plane turning by `turn` degrees at each inner point."""
    half = math.radians(180 - turn) / 2
    xs = np.linspace(-1.2, 1.2, 9)
    step = xs[1] - xs[0]
    zs = np.array([0.0 if i % 2 == 0 else step / math.tan(half) for i in range(9)]) - 0.3
    return np.stack([xs, np.zeros(9), zs], 1)


@pytest.mark.parametrize('ctype,points', [
    ('POLY', _zigzag(90)),
    ('POLY', _zigzag(150)),                     # each turn split into two rings
    ('CATMULL_ROM', np.array([[-0.6, 0, -1], [0, 0, 1], [0.6, 0, -1]], float)),      # a V
], ids=['poly_zigzag_90', 'poly_zigzag_150', 'catmull_rom_v'])
def test_curves_keep_their_width_through_sharp_turns(ctype, points, tmp_path):
    """Each tube ring at a turn is mitred (stretched along the bend, a sharp turn split into two
    rings): before, a ring square to the mean tangent showed cos(turn / 2) of the width, a Poly
    zig-zag of 90-degree turns rendered 26% thin, of 150-degree turns 63%, a Catmull-Rom V 3.4%
    (a Poly V of 147 degrees 36%)."""
    sc = _small_scene(64)
    ob = scenes.hair_curves("Bent", [points], radius=0.05, material=scenes.diffuse("Blue", (0.3, 0.6, 0.9)))
    ob.data.set_types(type=ctype)
    m = _means(sc, tmp_path)
    d, c = m['DACRT'], m['CYCLES']
    # a single curve's rings show the view their corners here (the first curve's phase: 0.65%
    # wide, averaged out over many curves by the golden-ratio turns); with the Poly caps and
    # joints round as Cycles' spheres, the 90-degree zig-zag's mesh covers 0.9% more than the
    # exact union of cylinders and spheres seen this way (Monte Carlo over its projection;
    # 1.002-1.003 at the other phases), rendered 1.2%
    np.testing.assert_allclose(d[3], c[3], rtol=0.015 if ctype == 'POLY' else 0.01, err_msg="covered area (alpha)")
    # the light caught: the bright blue channel 1-2% over at the Poly joints (more light
    # between the zig-zag's legs), where it had been 26-63% short
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.025, err_msg="colour")


def _emitter(name="Emitter", size=1.0, materials=None, location=(0, 0, -0.6)):
    em = scenes.plane(name, size=size, materials=materials or [scenes.diffuse("Fur", (0.9, 0.6, 0.3))])
    em.location = location
    em.show_instancer_for_render = False
    em.modifiers.new("Hair", 'PARTICLE_SYSTEM')
    return em, em.particle_systems[0].settings


@pytest.mark.parametrize('children', [False, True], ids=['parents', 'children'])
def test_spiral_kink_strands_end_at_their_tips(children, tmp_path):
    """Kink Spiral: Cycles asks co_hair for kink_extra_steps more points than the path cache
    holds (parents: all 4 past it, children: 1) and bpy gives (0, 0, 0) there: every strand had
    run a tube from its tip to the world origin (alpha 0.0606 vs Cycles' 0.0283; children
    0.0720 vs 0.0411)."""
    sc = _small_scene(32)
    em, s = _emitter(location=(0.8, 0, -0.8))
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 30, 0.5, 0.04
    s.kink = 'SPIRAL'
    if children:
        s.child_type, s.rendered_child_count = 'INTERPOLATED', 3
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    for engine, exr in exrs.items():      # between the tips and the world origin (row 0 at the bottom)
        assert exr[f"{layer}.Combined.A"][28:34, 32:].max() < 1e-3, engine
    d, c = ({e: np.array([exr[f"{layer}.Combined.{ch}"].mean() for ch in 'RGBA']) for e, exr in exrs.items()}[e]
            for e in ('DACRT', 'CYCLES'))
    assert c[3] > 0.01
    np.testing.assert_allclose(d[3], c[3], rtol=0.01, err_msg="covered area (alpha)")
    # the parents' tight curls catch 1.5% less light (so without the extra steps too)
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.02, err_msg="colour")


@pytest.mark.parametrize('scale', [(2.0, 1.0, 1.0), (0.6, 1.0, 1.5)], ids=['x2', 'squashed'])
def test_points_on_a_scaled_object_are_shaded_as_in_cycles(scale, tmp_path):
    """Cycles shades a point by normalize(P - centre) in world space (point_shader_setup): on a
    non-uniformly scaled object the ellipsoid takes the sphere's radial directions stretched by
    the matrix, where the inverse transpose (a mesh's normals) had given the ellipsoid's own
    normal: under a sun alone 0.0540 vs Cycles' 0.0466 at scale (2, 1, 1). (Under a white world
    too: test_stretched_points_radial_normal.)"""
    sc = _small_scene(128)
    sc.world.node_tree.nodes['Background'].inputs['Strength'].default_value = 0.0
    ob = scenes.point_cloud("P", [(0.0, 0.0, 0.0)], radius=0.5, material=scenes.diffuse("Grey", (0.8, 0.8, 0.8)))
    ob.scale = scale
    m = _means(sc, tmp_path)
    d, c = m['DACRT'], m['CYCLES']
    np.testing.assert_allclose(d[3], c[3], rtol=0.01, err_msg="covered area (alpha)")
    # (2, 1, 1) within 0.1%, the squashed one 0.3% (1.6% dark before the radial Ng), was 12-16% bright
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.02, err_msg="colour")


def test_hair_particles_take_the_emitters_shadow_terminator_offset(tmp_path):
    """Cycles' hair is its emitter's object and takes its Shadow Terminator Shading Offset;
    DACRT's hair had none (offset 0.5: red 0.0397 vs Cycles' 0.0196)."""
    sc = _small_scene(64)
    em, s = _emitter(size=2, materials=[scenes.diffuse("Blue", (0.3, 0.6, 0.9))])
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 30, 1.2, 0.15
    em.shadow_terminator_shading_offset = 0.5
    m = _means(sc, tmp_path)
    d, c = m['DACRT'], m['CYCLES']
    np.testing.assert_allclose(d[3], c[3], rtol=0.01, err_msg="covered area (alpha)")
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.01, err_msg="colour")


def _painted_emitter(domain='CORNER', data_type='BYTE_COLOR'):
    """A hair emitter whose colour attribute 'Col' is red left of x = 0, green right of it; its
    material reads it through a Color Attribute node (or, with domain None, plain diffuse)."""
    import bmesh
    mat = bpy.data.materials.new("M")
    nt = mat.node_tree
    nt.nodes.clear()
    out, d = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeVertexColor')
    a.layer_name = 'Col'
    if domain is not None:
        nt.links.new(a.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    em, s = _emitter(size=2, materials=[mat])
    me = em.data
    bm = bmesh.new()
    bm.from_mesh(me)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=7, use_grid_fill=True)
    bm.to_mesh(me)
    bm.free()
    ca = me.color_attributes.new('Col', data_type, domain or 'CORNER')
    if (domain or 'CORNER') == 'CORNER':
        x = np.array([me.vertices[loop.vertex_index].co.x for loop in me.loops])
    else:
        x = np.array([v.co.x for v in me.vertices])
    for i, xi in enumerate(x):
        ca.data[i].color = (0.9, 0.1, 0.1, 1) if xi < 0 else (0.1, 0.9, 0.1, 1)
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 80, 0.8, 0.05
    return em


def _halves(sc, tmp_path):
    layer = sc.view_layers[0].name
    return {e: np.array([[exr[f"{layer}.Combined.{c}"][:, cols].mean() for c in 'RGB']
                         for cols in (slice(0, 32), slice(32, 64))])
            for e, exr in scenes.render_engines(sc, tmp_path).items()}


def test_hair_particles_read_the_emitters_colour_attribute(tmp_path):
    """Cycles gives each strand the emitter's Face Corner Byte Color attribute at its root
    (ObtainCacheParticleVcol: mcol_on_emitter); DACRT's strands had read 0 (black, said to be
    'as in Cycles'). Each half's dominant channel (red left, green right) relative to the same
    strands in plain grey, per engine (DACRT's grey strands on the left are 7% brighter than
    Cycles', with or without the attribute): within 1%."""
    sc = _small_scene(64)
    _painted_emitter(domain=None)
    plain = _halves(sc, tmp_path / 'plain')
    bpy.data.objects.remove(bpy.data.objects['Emitter'])
    _painted_emitter()
    painted = _halves(sc, tmp_path / 'painted')
    for e in ('CYCLES', 'DACRT'):
        assert painted[e][0, 0] > 3 * painted[e][0, 1] and painted[e][1, 1] > 3 * painted[e][1, 0], (e, painted[e])
    rel = {e: np.array([painted[e][0, 0] / plain[e][0, 0], painted[e][1, 1] / plain[e][1, 1]]) for e in plain}
    np.testing.assert_allclose(rel['DACRT'], rel['CYCLES'], rtol=0.01)


def _hair_material(param, values):
    mat = bpy.data.materials.new("Hair")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    n = nt.nodes.new('ShaderNodeBsdfHairPrincipled')
    n.parametrization = param
    for name, v in values.items():
        n.inputs[name].default_value = v
    nt.links.new(n.outputs[0], out.inputs['Surface'])
    return mat, n


@pytest.mark.parametrize('param,values', [
    ('MELANIN', {'Melanin': 0.8}),
    ('MELANIN', {'Melanin': 0.3, 'Melanin Redness': 0.4, 'Tint': (1.0, 0.7, 0.5, 1.0), 'Radial Roughness': 0.5}),
    ('ABSORPTION', {'Absorption Coefficient': (0.2, 1.0, 3.0)}),
], ids=['melanin', 'melanin_tinted', 'absorption'])
def test_principled_hair_by_melanin_or_absorption_renders_as_its_direct_colouring(param, values, tmp_path):
    """A Principled Hair BSDF in Melanin or Absorption Coefficient parametrization has no Color:
    DACRT had rendered the 0.8 grey fallback (Melanin 0.8: (0.273, 0.273, 0.273) where Cycles
    renders a dark brown (0.074, 0.031, 0.013)). It now renders as the Direct Coloring colour
    Cycles' colour-to-absorption map gives the same absorption, as DACRT renders that mode (a
    diffuse of the colour): Cycles renders the two nodes alike (which checks the derivation),
    and so does DACRT. (The as-diffuse approximation itself is far from Cycles' hair lobes on
    these thin strands: 0.004 vs 0.074 red for Melanin 0.8.)"""
    from addon.export.reflectors import principled_hair_color
    sc = _small_scene(64)
    mat, node = _hair_material(param, values)
    curves = [np.stack([np.full(8, x) + 0.1 * np.sin(np.linspace(0, 6, 8)), np.zeros(8), np.linspace(-1.2, 1.2, 8)], 1)
              for x in np.linspace(-1.1, 1.1, 12)]
    scenes.hair_curves("Strands", curves, radius=0.06, material=mat)
    by_absorption = _means(sc, tmp_path / 'absorption')
    color = principled_hair_color(node, [])
    node.parametrization = 'COLOR'
    node.inputs['Color'].default_value = (*color, 1.0)
    by_color = _means(sc, tmp_path / 'color')
    np.testing.assert_allclose(by_absorption['CYCLES'][:3], by_color['CYCLES'][:3], rtol=0.01, atol=2e-4,
                               err_msg="Cycles: the derived colour is not the same absorption")
    np.testing.assert_allclose(by_absorption['DACRT'][:3], by_color['DACRT'][:3], rtol=0.005, atol=1e-4)
