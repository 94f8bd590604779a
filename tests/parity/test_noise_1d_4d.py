"""The Noise Texture in 1D (W alone) and 4D (Vector and W: animated noise, W keyed) against
Cycles: evaluated, not the node's own value standing in.

Pointwise: Cycles renders the texture's output as emission on a plane filling an orthographic
view at the pixel centres (tests/parity/test_procedural.py's scene), procedural.py computes the
same output there: within 0.005 everywhere, for every noise type, 4D at a few W values, 1D of
the object's x. Before, the kernel refused 1D and 4D points and the export the node.

Rendered through the add-on: a sun-lit plane whose Principled Base Color is a 4D noise (W from a
keyed Value, or a Math of Object Info Random) or a 1D noise of the object's x, both engines,
8x8-pixel block means within 2.5% of the brightest block (as test_procedural.py).
"""
import bpy
import numpy as np
import pytest

from addon import procedural as pr

from . import sunplane
from .test_procedural import _centres, _emission_plane, _own, _relink_surface

pytestmark = pytest.mark.usefixtures('parity_addon')

KINDS = ['FBM', 'MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN']
# per type: Detail (fractional), Roughness, Lacunarity, Distortion, Offset, Gain (the
# multifractals' values kept in the range a colour shows)
SETTINGS = {
    'FBM': {'Detail': 2.5, 'Distortion': 0.4, 'Roughness': 0.6, 'Lacunarity': 2.3},
    'MULTIFRACTAL': {'Detail': 1.5, 'Roughness': 0.4},
    'HYBRID_MULTIFRACTAL': {'Detail': 2.5, 'Offset': 0.3, 'Gain': 1.5},
    'RIDGED_MULTIFRACTAL': {'Detail': 2.0, 'Offset': 1.0, 'Gain': 1.2, 'Distortion': 0.3},
    'HETERO_TERRAIN': {'Detail': 1.5, 'Offset': 0.2, 'Roughness': 0.4},
}


# moves the plane's Object coordinates off z = 0 (where every point's z lattice cell is 0 and its
# gradients at z + 1 weigh nothing: hash_uint4's z had gone unchecked)
SHIFT = np.array([0.1, -0.2, 0.37], np.float32)


def _wire_w(dims):
    """Object coordinates + SHIFT into the Vector (4D), the object's x into W (1D: its only
    input, through Separate XYZ)."""
    def wire(nt, tc, tex):
        add = nt.nodes.new('ShaderNodeVectorMath')
        add.operation = 'ADD'
        add.inputs[1].default_value = tuple(SHIFT)
        nt.links.new(tc.outputs['Object'], add.inputs[0])
        # (by identifier: a 1D noise's Vector is unavailable, which inputs[name] does not find)
        nt.links.new(add.outputs[0], next(s for s in tex.inputs if s.identifier == 'Vector'))
        if dims == 1:
            sep = nt.nodes.new('ShaderNodeSeparateXYZ')
            nt.links.new(tc.outputs['Object'], sep.inputs[0])
            nt.links.new(sep.outputs['X'], tex.inputs['W'])
    return wire


# far W (one smooth octave: the filter's jitter moves nothing): wrapped as fmod wraps it every
# 100000, and past 1e6 half a cell further
FAR = {'Detail': 1.0, 'Distortion': 0.0}
CASES = [(kind, 4, w, 'Color' if kind in ('FBM', 'RIDGED_MULTIFRACTAL') else 'Fac', 3.0, SETTINGS[kind])
         for kind in KINDS for w in (0.0, 0.37, 5.6)] + \
        [(kind, 1, None, 'Color' if kind == 'FBM' else 'Fac', 2.0, SETTINGS[kind]) for kind in KINDS] + \
        [('FBM', 4, w, 'Color', 1.0, FAR) for w in (1.5e5 + 0.3, 2.5e6 + 0.25)]


@pytest.mark.parametrize('kind,dims,w,output,scale,inputs', CASES,
                         ids=[f'{k}-{d}d-{w}-{o}-{s:g}' for k, d, w, o, s, _ in CASES])
def test_noise_1d_4d_matches_cycles_pointwise(kind, dims, w, output, scale, inputs, tmp_path):
    from tests.addon import scenes
    # (the type and dimensions first: they make Offset, Gain and W available)
    settings = {'noise_dimensions': f'{dims}D', 'noise_type': kind, 'Scale': scale, **inputs}
    if w is not None:
        settings['W'] = w
    tex = _emission_plane('ShaderNodeTexNoise', output, settings, _wire_w(dims))
    r = scenes.read_exr(scenes.render_exr(tmp_path / "cycles.exr"))
    cycles = np.stack([r['R'], r['G'], r['B']], -1).reshape(-1, 3)
    p = _centres()
    ww = p[:, 0].copy() if dims == 1 else np.full(len(p), np.float32(w))
    p = (p + SHIFT).astype(np.float32)
    g = [_own(tex, k) for k in ('Scale', 'Detail', 'Roughness', 'Lacunarity', 'Distortion')]
    f, c = pr.noise_texture(p, *g, tex.normalize, dims, output == 'Color', kind, _own(tex, 'Offset'),
                            _own(tex, 'Gain'), ww)
    mine = c if output == 'Color' else np.repeat(f[:, None], 3, axis=1)
    assert np.ptp(cycles) > 0.1, "the texture should vary over the view"
    err = np.abs(mine - cycles).max(axis=1)
    assert err.max() < 0.005, (float(err.max()), float(err.mean()))


# --- rendered through the add-on ------------------------------------------------------------------

RES, BLOCK = 64, 8


def _principled(nt, diffuse, colour):
    """colour (a socket) into a Principled BSDF's Base Color, in place of the Diffuse."""
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Specular IOR Level'].default_value = 0.0
    p.inputs['Roughness'].default_value = 1.0
    nt.links.new(colour, p.inputs['Base Color'])
    p.name = "Surface"


def noise_4d_keyed_w(nt, diffuse):
    """W from a Value keyed 0.2 at frame 1 and 2.2 at frame 11, rendered at frame 6 (W 1.2)."""
    tc = nt.nodes.new('ShaderNodeTexCoord')
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.noise_dimensions = '4D'
    nz.inputs['Scale'].default_value, nz.inputs['Detail'].default_value = 3.0, 2.5
    v = nt.nodes.new('ShaderNodeValue')
    v.name = "Time"
    for frame, value in ((1, 0.2), (11, 2.2)):
        v.outputs[0].default_value = value
        v.outputs[0].keyframe_insert('default_value', frame=frame)
    bpy.context.scene.frame_set(6)
    nt.links.new(tc.outputs['Object'], nz.inputs['Vector'])
    nt.links.new(v.outputs[0], nz.inputs['W'])
    _principled(nt, diffuse, nz.outputs['Color'])


def noise_4d_random_w(nt, diffuse):
    """W a Math of Object Info Random (per object), a ridged multifractal's Fac."""
    oi = nt.nodes.new('ShaderNodeObjectInfo')
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY'
    m.inputs[1].default_value = 10.0
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.noise_dimensions, nz.noise_type = '4D', 'RIDGED_MULTIFRACTAL'
    nz.inputs['Scale'].default_value, nz.inputs['Detail'].default_value = 2.0, 1.5
    nz.inputs['Offset'].default_value, nz.inputs['Gain'].default_value = 1.0, 1.0
    nt.links.new(oi.outputs['Random'], m.inputs[0])
    nt.links.new(m.outputs[0], nz.inputs['W'])
    _principled(nt, diffuse, nz.outputs['Fac'])


def noise_1d_object_x(nt, diffuse):
    """1D: W the object's x (Separate XYZ), hybrid multifractal's Color, Generated Vector unread."""
    tc = nt.nodes.new('ShaderNodeTexCoord')
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.noise_dimensions, nz.noise_type = '1D', 'HYBRID_MULTIFRACTAL'
    nz.inputs['Scale'].default_value, nz.inputs['Detail'].default_value = 4.0, 2.5
    nz.inputs['Offset'].default_value, nz.inputs['Gain'].default_value = 0.5, 1.0
    nt.links.new(tc.outputs['Object'], sep.inputs[0])
    nt.links.new(sep.outputs['X'], nz.inputs['W'])
    _principled(nt, diffuse, nz.outputs['Color'])


def _blocks(engine, tmp_path):
    rgb = sunplane.render_rgb(engine, tmp_path)
    return rgb.reshape(RES // BLOCK, BLOCK, RES // BLOCK, BLOCK, 3).mean((1, 3))


@pytest.mark.parametrize('chain', [noise_4d_keyed_w, noise_4d_random_w, noise_1d_object_x],
                         ids=lambda c: c.__name__)
def test_noise_1d_4d_renders_as_cycles(chain, tmp_path):
    def wire(nt, tex, diffuse):
        nt.nodes.remove(tex)
        chain(nt, diffuse)
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, RES, 16)
    _relink_surface()
    dacrt, cycles = _blocks('DACRT', tmp_path), _blocks('CYCLES', tmp_path)
    assert np.ptp(cycles[..., 0]) > 0.1 * cycles.max(), "the pattern should show"
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.025, (err, dacrt[..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())


def test_noise_4d_emission_renders_as_cycles(tmp_path):
    """A 4D noise's Color as the plane's emission, seen straight on (procedural emission,
    compile_emission): 6x6 blocks of both engines within 2.5% of Cycles' brightest."""
    from tests.addon import scenes
    _emission_plane('ShaderNodeTexNoise', 'Color', {'noise_dimensions': '4D', 'W': 0.8, 'Scale': 2.0,
                                                     'Detail': 2.5}, _wire_w(4))
    sc = bpy.context.scene
    sc.cycles.samples = sc.dacrt.samples = 4
    sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
    out = {}
    for engine in ('DACRT', 'CYCLES'):
        sc.render.engine = engine
        r = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr"))
        rgb = np.stack([r['R'], r['G'], r['B']], -1)
        out[engine] = rgb.reshape(6, 8, 6, 8, 3).mean((1, 3))
    cycles = out['CYCLES']
    assert np.ptp(cycles[..., 0]) > 0.1 * cycles.max(), "the pattern should show"
    err = np.abs(out['DACRT'] - cycles).max() / cycles.max()
    assert err < 0.025, (err, out['DACRT'][..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())
