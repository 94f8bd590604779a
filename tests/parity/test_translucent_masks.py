"""A leaf whose Translucent BSDF a mask weighs: a Mix Shader of a Diffuse and a Translucent BSDF
by a Checker, a Noise or an image's colour, lit from behind, against Cycles block by block.
The transmission is weighed per shading point as the albedo is (export/texturedmixes.py
_procedural_mix, Closure.translucent_tex, the integrator's _translucency_maps). Before, the
transmission was one colour per material, at the factor's own value 0.5 (said): the checker
gone from the light through the leaf, lit blocks 0.50-1.90x Cycles'."""
import bpy
import numpy as np
import pytest

from addon.passes import result_name
from tests.addon import scenes

from .test_procedural_emission import _settings
from .test_translucent import _leaf_scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _mask(nt, kind, tmp_path):
    """The factor's output socket: a Checker (2 x 2 cells over the leaf), a Noise, or a 2 x 2
    image's colour read on Generated coordinates (Closest)."""
    if kind == 'checker':
        node = nt.nodes.new('ShaderNodeTexChecker')
        node.inputs['Scale'].default_value = 2.0
        return node.outputs['Fac']
    if kind == 'noise':
        node = nt.nodes.new('ShaderNodeTexNoise')
        node.inputs['Scale'].default_value = 3.0
        return node.outputs['Fac']
    px = np.array([[[255, 255, 255], [0, 0, 0]], [[40, 40, 40], [200, 200, 200]]], np.uint8)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "mask.png", px))
    node = nt.nodes.new('ShaderNodeTexImage')
    node.image, node.interpolation, node.extension = img, 'Closest', 'EXTEND'
    coords = nt.nodes.new('ShaderNodeTexCoord')
    nt.links.new(coords.outputs['Generated'], node.inputs['Vector'])
    return node.outputs['Color']


def _masked_leaf(kind, tmp_path):
    sc = _leaf_scene()
    nt = bpy.data.materials["Leaf"].node_tree
    mix = next(n for n in nt.nodes if n.type == 'MIX_SHADER')
    nt.links.new(_mask(nt, kind, tmp_path), mix.inputs['Fac'])
    _settings(64, 4)
    sc.view_layers[0].use_pass_diffuse_color = True
    return sc


def _blocks(img, size=8):
    """(H/size, W/size, 3) block means of an (H, W, 3) image."""
    h, w = img.shape[0] // size, img.shape[1] // size
    return img[:h * size, :w * size].reshape(h, size, w, size, 3).mean((1, 3))


def _lit_blocks_agree(sc, tmp_path, what):
    """Both engines' Combined and Diffuse Color images ({engine: {pass: (h, w, 3)}}, the pass
    name) after checking the back-lit blocks (Cycles' green above 0.3: at least 6, differing
    2x so `what` shows through the leaf) agree within 4%."""
    layer = sc.view_layers[0].name
    col = result_name('DiffCol', bpy.app.version)
    out = {}
    for engine, exr in scenes.render_engines(sc, tmp_path).items():
        out[engine] = {p: np.stack([exr[f"{layer}.{p}.{c}"] for c in 'RGB'], -1) for p in ('Combined', col)}
    c, d = (_blocks(out[e]['Combined']) for e in ('CYCLES', 'DACRT'))
    lit = c[..., 1] > 0.3
    assert lit.sum() >= 6, c[..., 1]
    assert c[lit][:, 1].max() > 2.0 * c[lit][:, 1].min(), f"the {what} should show through the leaf"
    np.testing.assert_allclose(d[lit], c[lit], rtol=0.04)
    return out, col


@pytest.mark.parametrize('kind', ['checker', 'noise', 'image'])
def test_translucency_weighed_by_a_mask_per_point(kind, tmp_path, said):
    """The blocks the transmission lights (Cycles' green above 0.3) within 4% of Cycles' and
    the image's mean within 1.5% (measured 0.97-1.03 and 0.5%); the Diffuse Color pass, which
    counts the transmission, within 1% block by block (measured exact). The mask shows: those
    blocks differ 2x in Cycles."""
    sc = _masked_leaf(kind, tmp_path)
    out, col = _lit_blocks_agree(sc, tmp_path, 'mask')
    np.testing.assert_allclose(out['DACRT']['Combined'].mean((0, 1)), out['CYCLES']['Combined'].mean((0, 1)),
                               rtol=0.015)
    np.testing.assert_allclose(_blocks(out['DACRT'][col]), _blocks(out['CYCLES'][col]), rtol=0.01, atol=1e-4)
    assert not any("translucency is one colour" in t for t in said), said


@pytest.mark.parametrize('kind', ['checker', 'image'])
def test_translucent_colour_from_a_texture_per_point(kind, tmp_path, said):
    """The Translucent BSDF's Color from a Checker's colour or an image's (the leaf's own
    texture), the Mix at 0.5: the back-lit blocks within 4% of Cycles' (measured 0.98-1.02)
    and the Diffuse Color pass within 1%. Before, the colour stood at the socket's own value
    (said), one colour over the whole leaf: lit blocks 0.67-5.8x Cycles' (checker), 0.20-3.0x
    (image)."""
    sc = _leaf_scene()
    nt = bpy.data.materials["Leaf"].node_tree
    t = next(n for n in nt.nodes if n.type == 'BSDF_TRANSLUCENT')
    mask = _mask(nt, kind, tmp_path)
    if kind == 'checker':
        mask = mask.node.outputs['Color']
        mask.node.inputs['Color1'].default_value = (0.9, 0.8, 0.2, 1.0)
        mask.node.inputs['Color2'].default_value = (0.1, 0.3, 0.05, 1.0)
    nt.links.new(mask, t.inputs['Color'])
    _settings(64, 4)
    sc.view_layers[0].use_pass_diffuse_color = True
    out, col = _lit_blocks_agree(sc, tmp_path, 'texture')
    np.testing.assert_allclose(_blocks(out['DACRT'][col]), _blocks(out['CYCLES'][col]), rtol=0.01, atol=1e-4)
    assert not any("Translucent BSDF colour" in t for t in said), said


def test_normal_pass_weighs_the_masked_transmission_per_point(tmp_path, said):
    """The masked leaf (Checker) bumped hard (one Bump on both BSDFs), seen from the front at
    a slant: Cycles' Normal pass averages the Diffuse's bent normal and the Translucent's raised
    one by their weights at each point; here too, the transmission's weight per point (the
    material's stand-in for it had weighed the raised normal on the cells where the mask leaves
    no transmission: blocks up to 0.060 off). Blocks within 0.02 of Cycles' (measured 0.005)."""
    sc = _masked_leaf('checker', tmp_path)
    nt = bpy.data.materials["Leaf"].node_tree
    noise = nt.nodes.new('ShaderNodeTexNoise')
    noise.inputs['Scale'].default_value = 6.0
    bump = nt.nodes.new('ShaderNodeBump')
    bump.inputs['Distance'].default_value = 1.0
    nt.links.new(noise.outputs['Fac'], bump.inputs['Height'])
    for n in nt.nodes:
        if n.type in ('BSDF_DIFFUSE', 'BSDF_TRANSLUCENT'):
            nt.links.new(bump.outputs['Normal'], n.inputs['Normal'])
    sc.camera.rotation_euler = (np.radians(80), 0.0, np.radians(-25))
    sc.camera.location = (-2.5, -5.5, 2.2)
    sc.view_layers[0].use_pass_normal = True
    sc.cycles.samples = sc.dacrt.samples = 16
    layer = sc.view_layers[0].name
    nrm = {e: _blocks(np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], -1))
           for e, exr in scenes.render_engines(sc, tmp_path).items()}
    leaf = np.abs(nrm['CYCLES'][..., 1]) > 0.3          # blocks on the leaf (its normal along -y)
    assert leaf.sum() >= 8, nrm['CYCLES'][..., 1]
    np.testing.assert_allclose(nrm['DACRT'][leaf], nrm['CYCLES'][leaf], atol=0.02)
    assert not any("BSDFs with different" in t for t in said), said
