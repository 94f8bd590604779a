"""An Image Texture's Alpha linked only through nodes Cycles' ConstantFolder removes does not
count as used: Cycles folds (Alpha x 0 -> 0, a Mix at factor 0 -> its A, a Mix Multiply by white
-> its A, ...) before it looks at what is linked, so it reads the colour of an associated-alpha
image as stored, not divided by alpha (nodegraph.used_outputs, Folder). The export had counted
any link reaching the output, so it divided: a half EXR's colour under alpha 0 by 2^-15 (3388x
Cycles' mean), an 8-bit straight PNG decal's 3.4x. Controls: a Mix Multiply by 0.999 does not
fold, and Alpha x 1 folds to the Alpha itself: both still divide, in both engines. Also a
clamped Mix at factor 1, a factor Alpha ^ 0 and the legacy MixRGB Multiply by white.

Sun-lit plane (sunplane: direct light, box filter), 4x4 texels read 'Closest', 4x4-pixel blocks
of both engines compared per texel."""
import bpy
import numpy as np
import pytest

from addon import nodegraph
from tests.addon import scenes
from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES, BLOCK = 16, 4, 4
# colour and alpha per texel; alpha-0 texels with colour under them (an EXR glow)
TEXELS = np.array([
    (0.5, 0.2, 0.1, 0.0), (0.5, 0.3, 0.2, 1.0), (0.9, 0.1, 0.2, 1.0), (1.0, 1.0, 1.0, 0.5),
    (0.3, 0.3, 0.9, 0.25), (0.2, 0.1, 0.5, 0.5), (0.0, 0.7, 0.2, 1.0), (0.4, 0.3, 0.2, 0.0),
    (0.2, 0.8, 0.2, 1.0), (0.0, 0.0, 0.0, 0.0), (0.6, 0.1, 0.1, 0.1), (0.9, 0.1, 0.4, 0.75),
    (0.05, 0.05, 0.05, 1.0), (0.5, 0.5, 0.0, 0.3), (0.6, 0.6, 0.0, 0.9), (0.1, 0.2, 0.3, 0.9),
], np.float32).reshape(4, 4, 4)


def _image(tmp_path, kind):
    """A half-float OpenEXR (stored associated) or an 8-bit straight PNG (sRGB) of TEXELS."""
    import OpenImageIO as oiio
    if kind == 'exr':
        path, spec, px = tmp_path / 'glow.exr', oiio.ImageSpec(4, 4, 4, 'half'), TEXELS
    else:
        path, spec = tmp_path / 'decal.png', oiio.ImageSpec(4, 4, 4, 'uint8')
        px = np.rint(TEXELS * 255).astype(np.uint8)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), px)
    assert buf.write(str(path)), buf.geterror()
    return str(path)


def _mix(nt, blend, a, b):
    m = nt.nodes.new('ShaderNodeMix')
    m.data_type, m.blend_type = 'RGBA', blend
    for ident, v in (('A_Color', a), ('B_Color', b)):
        nodegraph.input_by_id(m, ident).socket.default_value = (*v, 1.0)
    return m, next(o for o in m.outputs if o.type == 'RGBA' and o.enabled)


def alpha_x0(nt, tex):
    """Mix: Factor = Alpha x 0 (Math), A = the image colour, B = red (Cycles: 0, then A)."""
    mth = nt.nodes.new('ShaderNodeMath')
    mth.operation, mth.inputs[1].default_value = 'MULTIPLY', 0.0
    nt.links.new(tex.outputs['Alpha'], mth.inputs[0])
    m, out = _mix(nt, 'MIX', (0, 0, 0), (1, 0, 0))
    nt.links.new(mth.outputs[0], m.inputs['Factor'])
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'A_Color').socket)
    return out


def multiply_white(nt, tex, white=1.0):
    """Mix Multiply: Factor = Alpha, A = the image colour, B = white (Cycles: X * 1 -> A)."""
    m, out = _mix(nt, 'MULTIPLY', (0, 0, 0), (white,) * 3)
    nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'A_Color').socket)
    return out


def multiply_near_white(nt, tex):
    """Control: B = 0.999 folds nothing; Cycles divides by alpha too."""
    return multiply_white(nt, tex, 0.999)


def alpha_x1(nt, tex):
    """Control: Alpha x 1 folds to the Alpha link itself, still a Mix factor: divided."""
    mth = nt.nodes.new('ShaderNodeMath')
    mth.operation, mth.inputs[1].default_value = 'MULTIPLY', 1.0
    nt.links.new(tex.outputs['Alpha'], mth.inputs[0])
    m, out = _mix(nt, 'MIX', (0, 0, 0), (0.2, 0.3, 0.4))
    nt.links.new(mth.outputs[0], m.inputs['Factor'])
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'A_Color').socket)
    return out


def factor1_clamped(nt, tex):
    """Mix at factor 1, result clamped: A = Alpha + 0.5 (Math), B = the image colour. Cycles
    keeps B's link and, for the clamp, cuts every other input."""
    mth = nt.nodes.new('ShaderNodeMath')
    nt.links.new(tex.outputs['Alpha'], mth.inputs[0])
    m, out = _mix(nt, 'MIX', (0, 0, 0), (0, 0, 0))
    m.clamp_result, m.inputs['Factor'].default_value = True, 1.0
    nt.links.new(mth.outputs[0], nodegraph.input_by_id(m, 'A_Color').socket)
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'B_Color').socket)
    return out


def power0_factor(nt, tex):
    """Mix: Factor = Alpha ^ 0 (folded to 1), A = red, B = the image colour."""
    mth = nt.nodes.new('ShaderNodeMath')
    mth.operation, mth.inputs[1].default_value = 'POWER', 0.0
    nt.links.new(tex.outputs['Alpha'], mth.inputs[0])
    m, out = _mix(nt, 'MIX', (1, 0, 0), (0, 0, 0))
    nt.links.new(mth.outputs[0], m.inputs['Factor'])
    nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'B_Color').socket)
    return out


def mixrgb_white(nt, tex):
    """The legacy MixRGB node, Multiply by white with Fac = Alpha (fold_mix: X * 1 -> Color1)."""
    m = nt.nodes.new('ShaderNodeMixRGB')
    m.blend_type, m.inputs['Color2'].default_value = 'MULTIPLY', (1, 1, 1, 1)
    nt.links.new(tex.outputs['Alpha'], m.inputs['Fac'])
    nt.links.new(tex.outputs['Color'], m.inputs['Color1'])
    return m.outputs[0]


def _render(tmp_path, path, chain):
    def wire(nt, tex, diffuse):
        tex.image = bpy.data.images.load(path)
        tex.image.colorspace_settings.name = 'sRGB' if path.endswith('.png') else 'Linear Rec.709'
        tex.interpolation = 'Closest'
        nt.links.new(chain(nt, tex), diffuse.inputs['Color'])
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, SAMPLES)
    n = SIZE // BLOCK
    return {e: sunplane.render_rgb(e, tmp_path).reshape(n, BLOCK, n, BLOCK, 3).mean((1, 3))
            for e in ('DACRT', 'CYCLES')}


@pytest.mark.parametrize('kind', ['exr', 'png'])
@pytest.mark.parametrize('chain', [alpha_x0, multiply_white, multiply_near_white, alpha_x1,
                                   factor1_clamped, power0_factor, mixrgb_white])
def test_alpha_folded_away_as_cycles(tmp_path, said, kind, chain):
    got = _render(tmp_path, _image(tmp_path, kind), chain)
    d, c = got['DACRT'], got['CYCLES']
    assert c.max() > 0.05
    err = np.abs(d - c) / np.maximum(c, 0.05)
    assert err.max() < 0.005, (float(err.max()), d.mean((0, 1)).round(4).tolist(),
                               c.mean((0, 1)).round(4).tolist())


def _tree():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    mat, nt, out = scenes._material('F')
    em = nt.nodes.new('ShaderNodeEmission')
    tex = nt.nodes.new('ShaderNodeTexImage')
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return nt, tex, em


def _alpha_used(nt, tex):
    return nodegraph.output_key(tex, tex.outputs['Alpha'].identifier) in nodegraph.used_outputs(nt)


def test_folded_rules_without_rendering():
    """The folder's other rules, on used_outputs alone (what Cycles keeps, constant_fold.cpp)."""
    nt, tex, em = _tree()
    # Mix at factor 1 -> B: the Alpha in A goes; a clamped result keeps B's link, cuts the rest
    for clamp in (False, True):
        m, out = _mix(nt, 'MIX', (0, 0, 0), (0, 0, 0))
        m.clamp_result = clamp
        m.inputs['Factor'].default_value = 1.0
        nt.links.new(tex.outputs['Alpha'], nodegraph.input_by_id(m, 'A_Color').socket)
        nt.links.new(tex.outputs['Color'], nodegraph.input_by_id(m, 'B_Color').socket)
        nt.links.new(out, em.inputs['Color'])
        assert not _alpha_used(nt, tex), clamp
        assert nodegraph.output_key(tex, tex.outputs['Color'].identifier) in nodegraph.used_outputs(nt)
        m.inputs['Factor'].default_value = 0.5       # no longer folds
        assert _alpha_used(nt, tex)
        nt.nodes.remove(m)
    # a Value node of 0 into the Math: folded to a constant, then 0 * Alpha -> 0
    val = nt.nodes.new('ShaderNodeValue')
    val.outputs[0].default_value = 0.0
    mth = nt.nodes.new('ShaderNodeMath')
    mth.operation = 'MULTIPLY'
    nt.links.new(val.outputs[0], mth.inputs[0])
    nt.links.new(tex.outputs['Alpha'], mth.inputs[1])
    nt.links.new(mth.outputs[0], em.inputs['Strength'])
    assert not _alpha_used(nt, tex)
    val.outputs[0].default_value = 0.5
    assert _alpha_used(nt, tex)
    # Alpha + 0 -> Alpha: still used; Power x ^ 0 -> 1: not
    mth.operation = 'ADD'
    assert _alpha_used(nt, tex)
    mth.operation = 'POWER'
    nt.links.remove(mth.inputs[1].links[0])
    nt.links.new(tex.outputs['Alpha'], mth.inputs[0])
    mth.inputs[1].default_value = 0.0
    assert not _alpha_used(nt, tex)
