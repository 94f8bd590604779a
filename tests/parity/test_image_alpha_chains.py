"""Nodes that read an image's Color and Alpha together, or its Alpha through a non-affine node,
render as Cycles renders them: Cycles blends the stored texels (colour and alpha), then runs the
nodes per shading point, and so does the export (texelbaking.py _after_lookup, the blended alpha
passed to the chain: texture.EncodedTexels reads_alpha). The export had probed the colour (at
alpha 1) and the alpha (at colour 0.5) apart, so:
- a decal mixed over the Mix node's default grey 0.5 by its own alpha read as the bare image
  (0.5 at colour 0.5 for every alpha; the colour at alpha 1): the alpha dropped, 2.7x dark,
  even 'Closest';
- the image in the Mix's A with Factor = its Alpha read as 'alpha only' and was baked per texel
  before the blend (+50% red, silent), as was an Alpha -> Power 4 (+76%) or Color Ramp, into a
  colour or an Emission Strength (+66%), none of it reported.

Sun-lit plane (sunplane: direct light only, box filter), an 8-bit straight-alpha PNG of 4x4
texels magnified across the view ('Linear' blends between texels; 'Closest' reads one): blocks
of 4x4 pixels of both engines agree within 1% of the brightest. A chain the lookup cannot run
(a UDIM image kept as its linear texels) is baked with that said, unless it is affine in the
alpha (exact baked). Also: a Constant Color Ramp's switch (Cycles' 257-entry table), and a
half-float EXR's colour under alpha 0 mixed by its alpha (Cycles reads a half 0 as 2^-15)."""
import bpy
import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES, BLOCK = 32, 16, 4
TOLERANCE = 0.01
RNG = np.random.default_rng(4)
COLOURS = RNG.uniform(0.05, 0.95, (4, 4, 3))
MASK = np.array([[1, 0, 0, 1], [0, 1, 1, 0], [1, 1, 0, 0], [0, 0, 1, 1]], np.float64)   # hard 0/1 alpha
SOFT = RNG.uniform(0.0, 1.0, (4, 4))


def _png(path, alpha):
    import OpenImageIO as oiio
    px = np.concatenate([COLOURS, alpha[..., None]], axis=-1)
    buf = oiio.ImageBuf(oiio.ImageSpec(4, 4, 4, 'uint8'))
    buf.set_pixels(oiio.ROI(), np.rint(px * 255).astype(np.uint8))
    assert buf.write(str(path)), buf.geterror()
    return str(path)


def _mix(nt):
    m = nt.nodes.new('ShaderNodeMix')
    m.data_type = 'RGBA'
    return m, next(o for o in m.outputs if o.type == 'RGBA' and o.enabled)


def _blocks(rgb):
    n = SIZE // BLOCK
    return rgb.reshape(n, BLOCK, n, BLOCK, 3).mean((1, 3))


def _compare(tmp_path, said, path, interpolation, chain, emission=False, samples=SAMPLES):
    """Render the plane, image `path` read with interpolation, chain(nt, tex, diffuse) wiring it
    into the Diffuse colour (or, emission, returning an Emission node that replaces it); returns
    the engines' relative block difference; nothing said about the image."""
    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.image.alpha_mode = 'STRAIGHT'
        tex.interpolation, tex.extension = interpolation, 'REPEAT'
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, samples)
    nt = bpy.data.materials['Textured'].node_tree
    tex, d = (next(n for n in nt.nodes if n.type == t) for t in ('TEX_IMAGE', 'BSDF_DIFFUSE'))
    shader = chain(nt, tex, d)
    if emission:
        nt.links.new(shader.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    said.clear()
    got = {e: _blocks(sunplane.render_rgb(e, tmp_path)) for e in ('DACRT', 'CYCLES')}
    d, c = got['DACRT'], got['CYCLES']
    assert c.max() > 0.05
    err = float(np.abs(d - c).max() / c.max())
    assert err < TOLERANCE, (err, d.mean((0, 1)).round(4).tolist(), c.mean((0, 1)).round(4).tolist())
    assert not [t for t in said if 'a.png' in t or 'before the blend' in t], said


def _decal_over_default(nt, tex, d):
    """Mix: A unlinked (the node's default grey 0.5), B = image Color, Factor = image Alpha."""
    m, out = _mix(nt)
    assert tuple(m.inputs['A'].default_value)[:3] == pytest.approx((0.5, 0.5, 0.5))
    nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
    nt.links.new(tex.outputs['Color'], m.inputs['B'])
    nt.links.new(out, d.inputs['Color'])


@pytest.mark.parametrize('interpolation', ['Closest', 'Linear'])
def test_decal_over_the_mix_default_grey(tmp_path, said, interpolation):
    """Had been the bare image (black where transparent): 2.7x dark, Closest too."""
    _compare(tmp_path, said, _png(tmp_path / 'a.png', MASK), interpolation, _decal_over_default)


def test_decal_over_the_mix_default_grey_emission(tmp_path, said):
    def chain(nt, tex, d):
        _decal_over_default(nt, tex, d)
        e = nt.nodes.new('ShaderNodeEmission')
        nt.links.new(d.inputs['Color'].links[0].from_socket, e.inputs['Color'])
        return e
    _compare(tmp_path, said, _png(tmp_path / 'a.png', MASK), 'Linear', chain, emission=True)


@pytest.mark.parametrize('alpha', ['soft', 'mask'])
def test_image_in_a_mixed_by_its_alpha(tmp_path, said, alpha):
    """Mix: A = image Color, B = green, Factor = image Alpha (had been baked per texel: red
    0.328 for Cycles' 0.219 at soft alpha, silent)."""
    def chain(nt, tex, d):
        m, out = _mix(nt)
        m.inputs['B'].default_value = (0.0, 1.0, 0.0, 1.0)
        nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
        nt.links.new(tex.outputs['Color'], m.inputs['A'])
        nt.links.new(out, d.inputs['Color'])
    _compare(tmp_path, said, _png(tmp_path / 'a.png', SOFT if alpha == 'soft' else MASK), 'Linear', chain)


def _power(nt, tex):
    p = nt.nodes.new('ShaderNodeMath')
    p.operation = 'POWER'
    p.inputs[1].default_value = 4.0
    nt.links.new(tex.outputs['Alpha'], p.inputs[0])
    return p


def test_alpha_power_into_a_colour(tmp_path, said):
    """Alpha -> Power 4 -> Diffuse Color (had been +76%, silent)."""
    _compare(tmp_path, said, _png(tmp_path / 'a.png', MASK), 'Linear',
             lambda nt, tex, d: nt.links.new(_power(nt, tex).outputs[0], d.inputs['Color']))


def test_alpha_color_ramp_into_a_colour(tmp_path, said):
    """Alpha -> Color Ramp (linear, a kink at 0.3) -> Diffuse Color."""
    def chain(nt, tex, d):
        r = nt.nodes.new('ShaderNodeValToRGB')
        els = r.color_ramp.elements
        els[0].color, els[1].color = (0.9, 0.1, 0.1, 1.0), (0.1, 0.1, 0.9, 1.0)
        mid = els.new(0.3)
        mid.color = (0.1, 0.8, 0.1, 1.0)
        nt.links.new(tex.outputs['Alpha'], r.inputs['Fac'])
        nt.links.new(r.outputs['Color'], d.inputs['Color'])
    _compare(tmp_path, said, _png(tmp_path / 'a.png', SOFT), 'Linear', chain)


def test_alpha_power_into_emission_strength(tmp_path, said):
    """Alpha -> Power 4 -> Emission Strength, a constant colour (had been +66%, silent)."""
    def chain(nt, tex, d):
        e = nt.nodes.new('ShaderNodeEmission')
        e.inputs['Color'].default_value = (1.0, 0.6, 0.3, 1.0)
        nt.links.new(_power(nt, tex).outputs[0], e.inputs['Strength'])
        return e
    _compare(tmp_path, said, _png(tmp_path / 'a.png', MASK), 'Linear', chain, emission=True)


def _udim_said(tmp_path, said, interpolation, chain, emission=False):
    """What rendering (DACRT) a Non-Color, channel-packed UDIM image (kept as its linear texels,
    which the lookup does not run nodes after) through chain says about it."""
    for n in (1001, 1002):
        _png(tmp_path / f"t.{n}.png", MASK)

    def wire(nt, tex, diffuse):
        img = bpy.data.images.load(str(tmp_path / "t.1001.png"))
        img.source = 'TILED'
        img.colorspace_settings.name, img.alpha_mode = 'Non-Color', 'CHANNEL_PACKED'
        tex.image, tex.interpolation = img, interpolation
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, 8, 1)
    nt = bpy.data.materials['Textured'].node_tree
    tex, d = (next(n for n in nt.nodes if n.type == t) for t in ('TEX_IMAGE', 'BSDF_DIFFUSE'))
    shader = chain(nt, tex, d)
    if emission:
        nt.links.new(shader.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    said.clear()
    sunplane.render_rgb('DACRT', tmp_path)
    return [t for t in said if 'before the blend' in t]


def _affine(nt, tex):
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = 0.5, 0.1
    nt.links.new(tex.outputs['Alpha'], m.inputs[0])
    return m


def test_alpha_chain_baked_before_the_blend_is_said(tmp_path, said):
    """Alpha -> Power 4 baked into a UDIM image's texels: said for 'Linear' (had been silent),
    not for 'Closest' (exact) nor for an affine Multiply Add (exact baked)."""
    power = lambda nt, tex, d: nt.links.new(_power(nt, tex).outputs[0], d.inputs['Color'])
    assert _udim_said(tmp_path, said, 'Linear', power), said
    assert not _udim_said(tmp_path, said, 'Closest', power), said
    assert not _udim_said(tmp_path, said, 'Linear',
                          lambda nt, tex, d: nt.links.new(_affine(nt, tex).outputs[0], d.inputs['Color'])), said


def test_emission_strength_baked_before_the_blend_is_said(tmp_path, said):
    def chain(make):
        def wire(nt, tex, d):
            e = nt.nodes.new('ShaderNodeEmission')
            nt.links.new(make(nt, tex).outputs[0], e.inputs['Strength'])
            return e
        return wire
    assert [t for t in _udim_said(tmp_path, said, 'Linear', chain(_power), True) if 'strength' in t], said
    assert not _udim_said(tmp_path, said, 'Linear', chain(_affine), True), said



def test_alpha_constant_color_ramp_into_a_colour(tmp_path, said):
    """Alpha -> Color Ramp (Constant, a stop at 0.5) -> Diffuse Color. Cycles' ramp table has
    257 entries at i / 256 (colornodes.ramp_table), so the stop switches at 0.5; with 256 at
    i / 255 it had switched at 128 / 255 (blocks 2% off, red mean 0.335 for Cycles' 0.332). (A
    step on a blend: each pixel's colours vary, so more samples.)"""
    def chain(nt, tex, d):
        r = nt.nodes.new('ShaderNodeValToRGB')
        r.color_ramp.interpolation = 'CONSTANT'
        els = r.color_ramp.elements
        els[0].color, els[1].color, els[1].position = (0.9, 0.1, 0.1, 1.0), (0.1, 0.1, 0.9, 1.0), 0.5
        nt.links.new(tex.outputs['Alpha'], r.inputs['Fac'])
        nt.links.new(r.outputs['Color'], d.inputs['Color'])
    _compare(tmp_path, said, _png(tmp_path / 'a.png', MASK), 'Linear', chain, samples=128)


@pytest.mark.parametrize('fmt', ['half', 'float'])
def test_exr_glow_under_zero_alpha_mixed_by_its_alpha(tmp_path, said, fmt):
    """An OpenEXR (stored associated) whose texels all store (0.9, 0.2, 0.1), at alphas 1, 0,
    0.5, 0.25, mixed over a base by its own alpha (Closest). Cycles keeps a half-float file as
    halves and reads 0 as 2^-15 (texture.half_as_cycles_reads): the colour under alpha 0 is
    divided by that and the Mix gives base + stored colour there (an additive glow); a float
    file's alpha 0 is 0, the base alone. The half case's glow texel had been the base alone
    (0.218 red for Cycles' 1.061)."""
    import OpenImageIO as oiio
    px = np.zeros((2, 2, 4), np.float32)
    px[..., :3] = (0.9, 0.2, 0.1)
    px[..., 3] = [[1.0, 0.0], [0.5, 0.25]]
    path = str(tmp_path / "glow.exr")
    buf = oiio.ImageBuf(oiio.ImageSpec(2, 2, 4, fmt))
    buf.set_pixels(oiio.ROI(), px)
    assert buf.write(path), buf.geterror()
    base = np.array([0.2, 0.6, 0.9])

    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        m, out = _mix(nt)
        m.inputs['A'].default_value = (*base, 1.0)
        nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
        nt.links.new(tex.outputs['Color'], m.inputs['B'])
        nt.links.new(out, diffuse.inputs['Color'])
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, 8, 4)
    said.clear()
    got = {e: sunplane.render_rgb(e, tmp_path).reshape(2, 4, 2, 4, 3).mean((1, 3)) for e in ('DACRT', 'CYCLES')}
    d, c = got['DACRT'], got['CYCLES']
    assert np.abs(d - c).max() / c.max() < 0.003, (d.round(4).tolist(), c.round(4).tolist())
    glow = d[1, 1] / (2.0 / np.pi)       # the alpha-0 texel (the file's top right; sunplane: E / pi)
    want = base + px[0, 1, :3] if fmt == 'half' else base
    assert np.allclose(glow, want, rtol=2e-3), (glow, want)
    assert not [t for t in said if 'glow.exr' in t], said
