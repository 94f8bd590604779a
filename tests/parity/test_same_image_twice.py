"""One image read by two Image Texture nodes (two scales, another interpolation or extension,
a decal's colour and its own alpha on other coordinates), or through a node group used twice,
is two lookups: looked up per point as two different images are (test_two_images.py). The
export had counted images, not lookups, so the evaluation read the second as its average colour
('two image textures mixed'): blocks 0.16-0.33 off Cycles'. A UV-mapped plane under a white
world without bounces (radiance = albedo), seen square by an orthographic camera; 4x4 blocks."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from .test_two_images import albedo_plane_blocks

pytestmark = pytest.mark.usefixtures('parity_addon')


def _image(tmp_path):
    rng = np.random.default_rng(12)
    px = (rng.random((4, 4, 4)) * 255).astype(np.uint8)      # 8-bit sRGB with straight alpha
    return bpy.data.images.load(scenes.write_image(tmp_path / "a.png", px))


def _mapped(nt, node, scale, rotation=0.0, location=(0.0, 0.0)):
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.inputs['Scale'].default_value = (scale, scale, 1)
    mp.inputs['Rotation'].default_value = (0, 0, rotation)
    mp.inputs['Location'].default_value = (*location, 0)
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    nt.links.new(mp.outputs[0], node.inputs['Vector'])


def _two_nodes(nt, img):
    ta, tb = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeTexImage')
    ta.image = tb.image = img
    return ta, tb


def two_scales(nt, img):
    """The usual tiling break-up: the image times itself at three times the scale."""
    ta, tb = _two_nodes(nt, img)
    ta.interpolation, tb.interpolation = 'Closest', 'Linear'
    _mapped(nt, tb, 3.0)
    return scenes.mix_node(nt, 'MULTIPLY', ta.outputs['Color'], tb.outputs['Color'], 1.0).outputs['Result']


def decal(nt, img):
    """Colour tiled and turned, mixed by the same file's alpha on the plain UV map."""
    ta, tb = _two_nodes(nt, img)
    ta.interpolation = tb.interpolation = 'Linear'
    _mapped(nt, tb, 2.5, rotation=0.4)
    m = scenes.mix_node(nt, 'MIX', tb.outputs['Color'], (0.1, 0.7, 0.2), 0.5)
    nt.links.new(ta.outputs['Alpha'], m.inputs['Factor'])
    return m.outputs['Result']


def clip_cubic(nt, img):
    """Only the extension and interpolation differ (and a shift that shows the clip)."""
    ta, tb = _two_nodes(nt, img)
    ta.interpolation, tb.interpolation, tb.extension = 'Closest', 'Cubic', 'CLIP'
    _mapped(nt, tb, 1.5, location=(-0.2, -0.2))
    return scenes.mix_node(nt, 'MIX', ta.outputs['Color'], tb.outputs['Color'], 0.5).outputs['Result']


def group_twice(nt, img):
    """A 'tiling' group holding one Image Texture, used twice at two scales."""
    g = bpy.data.node_groups.new("Tile", 'ShaderNodeTree')
    g.interface.new_socket('Vector', in_out='INPUT', socket_type='NodeSocketVector')
    g.interface.new_socket('Color', in_out='OUTPUT', socket_type='NodeSocketColor')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    t = g.nodes.new('ShaderNodeTexImage')
    t.image, t.interpolation = img, 'Closest'
    g.links.new(gi.outputs[0], t.inputs['Vector'])
    g.links.new(t.outputs['Color'], go.inputs[0])
    users = []
    for scale in (1.0, 3.0):
        n = nt.nodes.new('ShaderNodeGroup')
        n.node_tree = g
        _mapped(nt, n, scale)
        users.append(n)
    return scenes.mix_node(nt, 'MULTIPLY', users[0].outputs[0], users[1].outputs[0], 1.0).outputs['Result']


@pytest.mark.parametrize("chain", [two_scales, decal, clip_cubic, group_twice], ids=lambda f: f.__name__)
def test_one_image_looked_up_twice_matches_cycles(tmp_path, chain, said):
    blocks = albedo_plane_blocks(lambda nt: chain(nt, _image(tmp_path)))
    assert not any("two image textures" in t for t in said), said
    diff = np.abs(blocks['DACRT'] - blocks['CYCLES'])
    # 64 samples of a world-lit albedo: a block's mean is within ~0.002 of Cycles' (Closest
    # texel edges inside a block add a little pixel-sampling noise)
    assert diff.max() < 0.006, (diff.max(), blocks)
