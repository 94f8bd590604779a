"""Identical Image Texture nodes (one image, every setting and the same Vector) are one node in
Cycles: ShaderGraph::deduplicate_nodes merges them (bottom up: their own identical Mapping
chains, or a group used twice on the same inputs, merge first). So where one's Color is used
and the other's Alpha, the merged node's Alpha is used and the Color of an image stored with
associated alpha is unassociated (rgb / alpha) for both readers (nodegraph.Identical). The
export had decided per node, reading the first colour associated, silently: a leaf PNG with a
second node for its Alpha 0.86x Cycles in red; a Premultiplied image whose two nodes' colours
are mixed by one's Alpha 0.73x (compiled per point as two lookups since procedurals counted
nodes). Controls, not merged in Cycles either: the second node's extension or Mapping scale
differs. A UV-mapped plane under a white world without bounces, seen square by an
orthographic camera; one block of pixels per texel."""
import bpy
import numpy as np
import pytest

from addon import nodegraph
from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

N, RES = 4, 32         # texels a side; pixels a side (a block of RES // N per texel)


def _leaf_png(tmp_path):
    """An 8-bit straight-alpha PNG (Cycles stores it associated): a leaf's colour and cut-out."""
    yy, xx = np.mgrid[0:N, 0:N]
    px = np.zeros((N, N, 4), np.float32)
    px[..., 0], px[..., 1], px[..., 2] = 0.9, (yy + 0.5) / N, 0.2
    px[..., 3] = ((xx + yy) % 4) / 3.0 * 0.8 + 0.2
    return bpy.data.images.load(scenes.write_image(tmp_path / "leaf.png", np.rint(px * 255).astype(np.uint8)))


def _premultiplied():
    yy, xx = np.mgrid[0:N, 0:N]
    px = np.zeros((N, N, 4), np.float32)
    px[..., 0], px[..., 1], px[..., 2] = (xx + 0.5) / N, (yy + 0.5) / N, ((xx + yy) % 2) * 0.8
    px[..., 3] = ((xx // 2 + yy // 2) % 2) * 0.7 + 0.3
    img = scenes.float_image("Grad", px)
    img.alpha_mode = 'PREMUL'
    return img


def _mapped(nt, node, scale):
    """node's Vector from a Mapping of its own, fed by a Texture Coordinate node of its own."""
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.inputs['Scale'].default_value = (scale, scale, 1)
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    nt.links.new(mp.outputs[0], node.inputs['Vector'])


def _pair(nt, img):
    ta, tb = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeTexImage')
    ta.image = tb.image = img
    ta.interpolation = tb.interpolation = 'Closest'
    return ta, tb


def leaf(nt, bsdf, tmp_path):
    """One node's Color into Base Color, an identical node's Alpha into Alpha."""
    ta, tb = _pair(nt, _leaf_png(tmp_path))
    nt.links.new(ta.outputs['Color'], bsdf.inputs['Base Color'])
    nt.links.new(tb.outputs['Alpha'], bsdf.inputs['Alpha'])
    return ta, tb


def leaf_own_mappings(nt, bsdf, tmp_path):
    """As leaf, each node through a Mapping (same settings) and Texture Coordinate of its own."""
    ta, tb = leaf(nt, bsdf, tmp_path)
    _mapped(nt, ta, 1.0)
    _mapped(nt, tb, 1.0)
    return ta, tb


def leaf_extend(nt, bsdf, tmp_path):
    """Control: the Alpha node's extension differs, so Cycles keeps two nodes."""
    ta, tb = leaf(nt, bsdf, tmp_path)
    tb.extension = 'EXTEND'
    return ta, tb


def leaf_other_scale(nt, bsdf, tmp_path):
    """Control: the Alpha node's Mapping differs (scale 1.0001, the same texels on the plane)."""
    ta, tb = leaf(nt, bsdf, tmp_path)
    _mapped(nt, ta, 1.0)
    _mapped(nt, tb, 1.0001)
    return ta, tb


def mixed_by_alpha(nt, bsdf, tmp_path):
    """A Premultiplied float image: both nodes' Colors into a Mix whose Factor is one's Alpha."""
    ta, tb = _pair(nt, _premultiplied())
    m = scenes.mix_node(nt, 'MIX', ta.outputs['Color'], tb.outputs['Color'])
    nt.links.new(tb.outputs['Alpha'], m.inputs['Factor'])
    nt.links.new(m.outputs['Result'], bsdf.inputs['Base Color'])
    return ta, tb


def group_twice(nt, bsdf, tmp_path):
    """A group holding the leaf's Image Texture used twice on one Mapping: its Color from one
    user, its Alpha from the other."""
    g = bpy.data.node_groups.new("Leaf", 'ShaderNodeTree')
    g.interface.new_socket('Vector', in_out='INPUT', socket_type='NodeSocketVector')
    g.interface.new_socket('Color', in_out='OUTPUT', socket_type='NodeSocketColor')
    g.interface.new_socket('Alpha', in_out='OUTPUT', socket_type='NodeSocketFloat')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    t = g.nodes.new('ShaderNodeTexImage')
    t.image, t.interpolation = _leaf_png(tmp_path), 'Closest'
    g.links.new(gi.outputs[0], t.inputs['Vector'])
    g.links.new(t.outputs['Color'], go.inputs[0])
    g.links.new(t.outputs['Alpha'], go.inputs[1])
    mp = nt.nodes.new('ShaderNodeMapping')
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    users = []
    for _ in range(2):
        n = nt.nodes.new('ShaderNodeGroup')
        n.node_tree = g
        nt.links.new(mp.outputs[0], n.inputs[0])
        users.append(n)
    nt.links.new(users[0].outputs['Color'], bsdf.inputs['Base Color'])
    nt.links.new(users[1].outputs['Alpha'], bsdf.inputs['Alpha'])
    return None, None


MERGED = (leaf, leaf_own_mappings, mixed_by_alpha, group_twice)
CONTROLS = (leaf_extend, leaf_other_scale)


def _material(build, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat = bpy.data.materials.new("M")
    nt = mat.node_tree
    bsdf = nt.nodes['Principled BSDF']
    bsdf.inputs['Specular IOR Level'].default_value = 0
    ta, tb = build(nt, bsdf, tmp_path)
    return mat, nt, ta, tb


@pytest.mark.parametrize("build", MERGED + CONTROLS, ids=lambda f: f.__name__)
def test_identical_image_nodes_match_cycles(tmp_path, build, said):
    mat, _, _, _ = _material(build, tmp_path)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = RES
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.world((1, 1, 1))
    scenes.plane("P", size=2, materials=(mat,)).data.uv_layers.new(name='UVMap')
    rendering.fair_scene_settings(sc)
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    sc.view_settings.view_transform = 'Standard'
    blocks = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device, sc.cycles.max_bounces = 32, False, 'CPU', 0
        sc.cycles.use_adaptive_sampling = False
        sc.dacrt.samples, sc.dacrt.max_bounces = 32, 0
        img = scenes.render_rgba(sc)
        b = RES // N
        blocks[engine] = img[..., :3].reshape(N, b, N, b, 3).mean(axis=(1, 3))
    assert not any("two image textures" in t for t in said), said
    diff = np.abs(blocks['DACRT'] - blocks['CYCLES'])
    # a world-lit albedo without bounces: a block's mean is within ~0.002 of Cycles' (the
    # first node's colour read associated had been up to 0.3 off where alpha is 0.2)
    assert diff.max() < 0.01, (diff.max(), blocks)


@pytest.mark.parametrize("build", MERGED[:3] + CONTROLS, ids=lambda f: f.__name__)
def test_identical_keys_only_where_cycles_merges(tmp_path, build):
    """nodegraph.Identical gives both nodes one key exactly where Cycles merges them, and
    used_outputs then counts the first node's Alpha as used."""
    _, nt, ta, tb = _material(build, tmp_path)
    same = nodegraph.Identical()
    merged = build in MERGED
    assert (same.node(ta) == same.node(tb)) == merged
    used = nodegraph.used_outputs(nt)
    assert used.reads(ta, 'Alpha') == merged
    assert nodegraph.output_key(ta, 'Alpha') not in used       # (its own Alpha is not linked)
