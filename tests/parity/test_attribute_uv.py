"""An Attribute node naming a UV map, into an Image Texture's Vector, reads that map as Cycles
does (its attribute lookup by name, the UV Map node's): on the active map and on a second one
whose UVs are turned and squeezed. It had been read on the active map (said): blocks 0.95 off
Cycles' on the second map. A plane lit by a sun of strength pi, direct light only."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _blocks(texture, vector, said):
    """(DACRT, Cycles) 4x4 block means (RGB) of a plane whose Diffuse colour is `texture`
    (a new node's bl_idname, its Vector fed by the output `vector` returns given the node
    tree) on a plane with two UV maps, the active 'UVMap' and 'Second', turned and squeezed;
    and what each render said (the last, DACRT's, kept in said)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.light('SUN', math.pi)
    scenes.black_world()
    mat, nt, out = scenes._material("Textured")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new(texture)
    nt.links.new(vector(nt), tex.inputs['Vector'])
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    me = scenes.plane("P", size=2.0, materials=(mat,)).data
    me.uv_layers.new(name="UVMap")
    second = me.uv_layers.new(name="Second")
    for corner in second.data:
        u, v = corner.uv
        corner.uv = (v * 0.6 + 0.2, 1 - u)
    if texture == 'ShaderNodeTexImage':
        px = np.random.default_rng(32).random((4, 4, 4)).astype(np.float32)
        px[..., 3] = 1.0
        tex.image, tex.interpolation = scenes.float_image("A", px), 'Linear'
    else:                   # (a Checker)
        tex.inputs['Scale'].default_value = 3.0
        tex.inputs['Color1'].default_value = (0.9, 0.5, 0.1, 1.0)
    rendering.matched(sc, 16)
    blocks = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        img = scenes.render_rgba(sc)
        blocks[engine] = img[..., :3].reshape(4, 8, 4, 8, 3).mean(axis=(1, 3))
    return blocks['DACRT'], blocks['CYCLES']


@pytest.mark.parametrize("name,output", [("UVMap", 'Vector'), ("Second", 'Vector'), ("Second", 'Color'),
                                         ("Second", 'Fac'), ("", 'Vector'), ("Missing", 'Vector')])
def test_an_attribute_naming_a_uv_map_matches_cycles(name, output, said):
    """Also its Fac output and an attribute no mesh has (unnamed, or a name of none): what
    the per-point coordinate chain computes there, as Cycles."""
    def attribute(nt):
        at = nt.nodes.new('ShaderNodeAttribute')
        at.attribute_name = name
        return at.outputs[output]
    d, c = _blocks('ShaderNodeTexImage', attribute, said)
    assert not any("read as the UV map" in t for t in said), said
    assert np.abs(d - c).max() < 0.005, (np.abs(d - c).max(), d, c)


@pytest.mark.parametrize("name", ["", "UVMap", "Second", "Missing"])
def test_a_uv_map_node_before_a_procedural_matches_cycles(name, said):
    """A UV Map node into a Checker's Vector: the active map (no name, or its own), a second
    one by name, a name no mesh has (0, as in Cycles). The texture had been given up ("'UV Map'
    node is not read there") and stood at its Color's own value: a Checker 1.19x Cycles'
    (fuzz seed 11001, a Gabor on a UV Map node). (The Checker's edges cross blocks: their
    samples' noise, up to 0.0055 at 16 spp.)"""
    def uv_map(nt):
        uv = nt.nodes.new('ShaderNodeUVMap')
        uv.uv_map = name
        return uv.outputs['UV']
    d, c = _blocks('ShaderNodeTexChecker', uv_map, said)
    assert not any("not evaluated per point" in t for t in said), said
    assert np.abs(d - c).max() < 0.01, (np.abs(d - c).max(), d, c)
