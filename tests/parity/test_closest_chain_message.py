"""Colour nodes after an image that read its Alpha (a Mix by the image's own Alpha) are baked into
its texels (addon/export/texelbaking.py) where they cannot run after the lookup. Read 'Closest',
nothing is blended: the texel looked up is the nodes on the very texel Cycles reads, so the
render equals Cycles' and nothing is said; it had been reported "applied to its texels before
the blend (Cycles blends, decodes, then applies them)". Read 'Linear', this chain now runs
after the lookup on the blended colour and alpha (as Cycles): equal too, nothing said.

Sun-lit plane (sunplane), an 8-bit RGBA PNG of 2x2 texels, one 4x4-pixel block each: Diffuse
colour and Emission colour, every block within 0.3% of Cycles' brightest."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES = 8, 4
PX = np.array([[[200, 40, 90, 255], [10, 220, 60, 64]], [[90, 90, 200, 128], [250, 250, 10, 200]]], np.uint8)
SAID = "colour nodes after image 'rgba.png' applied to its texels before the blend"



@pytest.mark.parametrize('target', ['diffuse', 'emission'])
def test_closest_image_mixed_by_its_alpha_not_reported(tmp_path, said, target):
    path = scenes.write_image(tmp_path / "rgba.png", PX)

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type = 'RGBA'
        mix.inputs['A'].default_value = (0.8, 0.1, 0.1, 1.0)
        nt.links.new(tex.outputs['Alpha'], mix.inputs['Factor'])
        nt.links.new(tex.outputs['Color'], mix.inputs['B'])
        nt.links.new(mix.outputs['Result'], diffuse.inputs['Color'])

    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, SAMPLES)
    nt = bpy.data.materials['Textured'].node_tree
    if target == 'emission':
        e = nt.nodes.new('ShaderNodeEmission')
        mix = next(n for n in nt.nodes if n.type == 'MIX')
        nt.links.new(mix.outputs['Result'], e.inputs['Color'])
        nt.links.new(e.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    said.clear()
    got = {e: sunplane.render_rgb(e, tmp_path).reshape(2, 4, 2, 4, 3).mean((1, 3)) for e in ('DACRT', 'CYCLES')}
    d, c = got['DACRT'], got['CYCLES']
    err = np.abs(d - c).max() / c.max()
    assert err < 0.003, (err, d.round(4).tolist(), c.round(4).tolist())
    assert not [t for t in said if SAID in t], said
    # read 'Linear', the chain runs after the lookup on the blended colour and alpha, as in
    # Cycles (it had been baked into the texels before the blend, said;
    # tests/parity/test_image_alpha_chains.py): equal, nothing said
    next(n for n in nt.nodes if n.type == 'TEX_IMAGE').interpolation = 'Linear'
    sc = bpy.context.scene
    sc.cycles.samples = sc.dacrt.samples = 64       # (blended blocks vary within a pixel: 4 spp 0.8% apart)
    said.clear()
    got = {e: sunplane.render_rgb(e, tmp_path).reshape(2, 4, 2, 4, 3).mean((1, 3)) for e in ('DACRT', 'CYCLES')}
    d, c = got['DACRT'], got['CYCLES']
    err = np.abs(d - c).max() / c.max()
    assert err < 0.003, (err, d.round(4).tolist(), c.round(4).tolist())
    assert not [t for t in said if SAID in t], said
