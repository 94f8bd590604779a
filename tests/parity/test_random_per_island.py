"""The Geometry node's Random Per Island agrees with Cycles: one number per island of a mesh, the
hash of the island's representative vertex in the disjoint set Cycles joins edge by edge
(export/islands.py). Eight islands of 2x2 quads in one mesh, their vertex indices shuffled (so
which vertex represents an island depends on the union's rules and the edge order), seen by an
orthographic camera: the number into an Emission's Color on one such mesh and, through a Color
Ramp, into a Diffuse BSDF's Color under a white world (no bounces) on another. Each island's
inner pixels within 1e-3 (emission: measured 0) and 0.02 (diffuse, noisy) of Cycles'. The output
had stood at the reading input's own value, said (every island the same colour)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

COLUMNS, ROWS = 4, 2


def _islands_mesh(name, y0, material):
    rng = np.random.default_rng(5)
    verts, faces = [], []
    for k in range(COLUMNS * ROWS):
        cx, cy = -COLUMNS + 1 + 2 * (k % COLUMNS), y0 + 2 * (k // COLUMNS) - ROWS + 1
        base = len(verts)
        verts += [(cx + 0.85 * (i - 1), cy + 0.85 * (j - 1), 0.0) for j in range(3) for i in range(3)]
        faces += [(base + j * 3 + i, base + j * 3 + i + 1, base + (j + 1) * 3 + i + 1, base + (j + 1) * 3 + i)
                  for j in range(2) for i in range(2)]
    order = rng.permutation(len(verts))          # new index of each vertex
    inverse = np.argsort(order)
    verts = [verts[i] for i in inverse]
    faces = [tuple(int(order[v]) for v in f) for f in faces]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    me.materials.append(material)
    return ob


def _material(kind):
    mat, nt, _ = scenes._material(kind)     # (its output node: 'Material Output')
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    if kind == 'emission':
        sh = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(geo.outputs['Random Per Island'], sh.inputs['Color'])
    else:
        sh = nt.nodes.new('ShaderNodeBsdfDiffuse')
        ramp = nt.nodes.new('ShaderNodeValToRGB')
        ramp.color_ramp.elements[0].color = (0.9, 0.1, 0.05, 1)
        ramp.color_ramp.elements[1].color = (0.05, 0.3, 0.9, 1)
        nt.links.new(geo.outputs['Random Per Island'], ramp.inputs[0])
        nt.links.new(ramp.outputs[0], sh.inputs['Color'])
    nt.links.new(sh.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    return mat


def test_random_per_island_matches_cycles():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 16 * COLUMNS, 16 * 2 * ROWS
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0 * COLUMNS)
    scenes.world((1.0, 1.0, 1.0), 1.0)
    _islands_mesh('emitting', ROWS, _material('emission'))
    _islands_mesh('diffuse', -ROWS, _material('diffuse'))
    rendering.matched(sc, 64)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        img = scenes.render_rgba(sc)[..., :3]
        # each island's inner 8x8 pixels (16 pixels a unit; islands 1.7 wide, 2 apart)
        got[engine] = np.array([[img[8 * r + 4:8 * r + 12, 16 * c + 4:16 * c + 12].mean(axis=(0, 1))
                                 for c in range(COLUMNS)] for r in range(2 * ROWS)])
    diff = np.abs(got['DACRT'] - got['CYCLES'])
    assert diff[ROWS:].max() < 1e-3, (diff[ROWS:].max(), got['DACRT'][ROWS:, :, 0], got['CYCLES'][ROWS:, :, 0])
    assert diff[:ROWS].max() < 0.02, (diff[:ROWS].max(), got['DACRT'][:ROWS], got['CYCLES'][:ROWS])
    # the islands differ from each other (the test sees the numbers, not one stand-in)
    assert np.ptp(got['CYCLES'][ROWS:, :, 0]) > 0.3
