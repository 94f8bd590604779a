"""White Noise, Magic and Gabor Textures (addon/procedural.py white_noise, magic, gabor; compiled
in addon/export/procedurals.py) against Cycles, as tests/parity/test_procedural.py checks the others.

Pointwise: Cycles renders the texture's output as emission at pixel centres (an orthographic
view of a 4x4 plane, one sample through a 0.01 px box filter), procedural.py computes it at the
same object coordinates; within 0.005 everywhere (Gabor's Phase: but where its phase wraps from
1 to 0 within the filter's jitter, < 0.2% of the pixels). White Noise hashes its input's float bits, so
a point's value changes with the last bit of its coordinates: it is compared where its Vector
(and W) come through a Mapping and a Floor, cells whose borders no pixel centre comes near, as
a scene uses it (a random value per tile, brick or object).

Rendered: a sun-lit plane whose Diffuse colour comes from each texture, both engines, 8x8 block
means within 2.5% of the brightest block. Before, the nodes' own values stood in (reported).
"""
import numpy as np
import pytest

from addon import procedural as pr
from tests.addon import scenes

from . import sunplane
from .test_procedural import BLOCK, RES, _blocks, _centres, _emission_plane, _wire

pytestmark = pytest.mark.usefixtures('parity_addon')

CELLS = np.array((3.0, 3.0, 1.0), np.float32), np.array((0.3, 0.3, 0.5), np.float32)


def _floored_cells(nt, tc):
    """Object coordinates x 3 (x, y) shifted by 0.3 (z by 0.5), floored: integer cells, pixel
    centres at least 0.075 cell from their borders."""
    m = nt.nodes.new('ShaderNodeMapping')
    m.inputs['Scale'].default_value, m.inputs['Location'].default_value = CELLS
    fl = nt.nodes.new('ShaderNodeVectorMath')
    fl.operation = 'FLOOR'
    nt.links.new(tc.outputs['Object'], m.inputs['Vector'])
    nt.links.new(m.outputs[0], fl.inputs[0])
    return fl.outputs[0]


def _white_noise_wire(nt, tc, tex):
    cells = _floored_cells(nt, tc)
    if tex.noise_dimensions != '1D':              # (1D reads W only: its Vector is unavailable)
        nt.links.new(cells, tex.inputs['Vector'])
    if tex.noise_dimensions in ('1D', '4D'):      # W: the cell's x
        sep = nt.nodes.new('ShaderNodeSeparateXYZ')
        nt.links.new(cells, sep.inputs[0])
        nt.links.new(sep.outputs['X'], tex.inputs['W'])


def _object_wire(nt, tc, tex):
    nt.links.new(tc.outputs['Object'], tex.inputs['Vector'])


def _moved_wire(nt, tc, tex):
    """Far from the origin: Cycles wraps the Magic Texture's coordinates by 2 pi first."""
    m = nt.nodes.new('ShaderNodeMapping')
    m.inputs['Location'].default_value = (10.0, -7.0, 3.0)
    nt.links.new(tc.outputs['Object'], m.inputs['Vector'])
    nt.links.new(m.outputs[0], tex.inputs['Vector'])


def _white_noise(tex, p, output):
    cells = np.floor(p * CELLS[0] + CELLS[1]).astype(np.float32)
    value, color = pr.white_noise(cells, cells[:, 0], int(tex.noise_dimensions[0]))
    return color if output == 'Color' else np.repeat(value[:, None], 3, axis=1)


def _gabor(tex, p, output):
    g = {k: tex.inputs[k].default_value for k in ('Scale', 'Frequency', 'Anisotropy')}
    dims = int(tex.gabor_type[0])
    orientation = tex.inputs['Orientation 2D' if dims == 2 else 'Orientation 3D'].default_value
    found = pr.gabor(p, g['Scale'], g['Frequency'], g['Anisotropy'], np.array(orientation, np.float32), dims)
    return np.repeat(found[('Value', 'Phase', 'Intensity').index(output)][:, None], 3, axis=1)


def _magic(tex, p, output):
    color = pr.magic(p, tex.inputs['Scale'].default_value, tex.turbulence_depth,
                     tex.inputs['Distortion'].default_value)
    return color if output == 'Color' else np.repeat(color.mean(axis=1, keepdims=True), 3, axis=1)


POINTWISE = {
    'white_noise_1d': ('ShaderNodeTexWhiteNoise', 'Value', {'noise_dimensions': '1D'}, _white_noise_wire),
    'white_noise_1d_color': ('ShaderNodeTexWhiteNoise', 'Color', {'noise_dimensions': '1D'}, _white_noise_wire),
    'white_noise_2d_color': ('ShaderNodeTexWhiteNoise', 'Color', {'noise_dimensions': '2D'}, _white_noise_wire),
    'white_noise_3d': ('ShaderNodeTexWhiteNoise', 'Value', {'noise_dimensions': '3D'}, _white_noise_wire),
    'white_noise_3d_color': ('ShaderNodeTexWhiteNoise', 'Color', {'noise_dimensions': '3D'}, _white_noise_wire),
    'white_noise_4d_color': ('ShaderNodeTexWhiteNoise', 'Color', {'noise_dimensions': '4D'}, _white_noise_wire),
    'magic_default_depth': ('ShaderNodeTexMagic', 'Color', {'Scale': 1.0}, _object_wire),
    'magic_depth_0': ('ShaderNodeTexMagic', 'Color', {'Scale': 1.5, 'turbulence_depth': 0}, _object_wire),
    # (deep and distorted: the filter's jitter moves the colour up to ~3e-3; more distortion
    # makes the pattern chaotic at this resolution)
    'magic_depth_5_fac': ('ShaderNodeTexMagic', 'Fac', {'Scale': 0.3, 'turbulence_depth': 5,
                                                        'Distortion': 1.2}, _object_wire),
    'magic_depth_10': ('ShaderNodeTexMagic', 'Color', {'Scale': 0.2, 'turbulence_depth': 10,
                                                       'Distortion': 1.0}, _object_wire),
    'magic_far_wrapped': ('ShaderNodeTexMagic', 'Color', {'Scale': 1.0, 'turbulence_depth': 4}, _moved_wire),
    'gabor_2d_value': ('ShaderNodeTexGabor', 'Value', {'gabor_type': '2D', 'Scale': 1.5, 'Frequency': 1.5},
                       _object_wire),
    'gabor_2d_phase': ('ShaderNodeTexGabor', 'Phase', {'gabor_type': '2D', 'Frequency': 1.0, 'Scale': 1.0,
                                                       'Anisotropy': 0.3}, _object_wire),
    'gabor_2d_anisotropic_intensity': ('ShaderNodeTexGabor', 'Intensity', {
        'gabor_type': '2D', 'Scale': 1.2, 'Frequency': 1.0, 'Anisotropy': 1.0, 'Orientation 2D': 0.4}, _object_wire),
    'gabor_3d_value': ('ShaderNodeTexGabor', 'Value', {'gabor_type': '3D', 'Scale': 1.5, 'Frequency': 1.5},
                       _object_wire),
    'gabor_3d_oriented_intensity': ('ShaderNodeTexGabor', 'Intensity', {
        'gabor_type': '3D', 'Scale': 1.0, 'Frequency': 1.0, 'Anisotropy': 0.5, 'Orientation 3D': (0.3, -0.5, 0.8)},
        _moved_wire),
    'gabor_3d_anisotropic_value': ('ShaderNodeTexGabor', 'Value', {
        'gabor_type': '3D', 'Scale': 1.0, 'Frequency': 1.2, 'Anisotropy': 1.0, 'Orientation 3D': (0.3, -0.5, 0.8)},
        _object_wire),
}


@pytest.mark.parametrize('case', sorted(POINTWISE))
def test_texture_matches_cycles_pointwise(case, tmp_path):
    kind, output, settings, wire = POINTWISE[case]
    tex = _emission_plane(kind, output, dict(settings), wire)
    r = scenes.read_exr(scenes.render_exr(tmp_path / "cycles.exr"))
    cycles = np.stack([r['R'], r['G'], r['B']], -1).reshape(-1, 3)
    p = _centres() + (np.float32((10.0, -7.0, 3.0)) if wire is _moved_wire else np.float32(0.0))
    if kind == 'ShaderNodeTexWhiteNoise':
        mine = _white_noise(tex, p, output)
    elif kind == 'ShaderNodeTexGabor':
        mine = _gabor(tex, p, output)
    else:
        mine = _magic(tex, p, output)
    assert np.ptp(cycles) > 0.2, "the texture should vary over the view"
    err = np.abs(mine - cycles).max(axis=1)
    if output == 'Phase':           # (its wrap from 1 to 0 within the filter's jitter)
        assert np.mean(err > 0.005) < 0.002, (case, float(np.mean(err > 0.005)))
    else:
        assert err.max() < 0.005, (case, float(err.max()), float(err.mean()))


# --- rendered through the add-on ------------------------------------------------------------------

def white_noise_tiles(nt, diffuse):
    """A random colour per tile: Object coordinates x 4, floored (4x4 tiles on the 2x2 plane,
    their borders on the 8x8 blocks' ones)."""
    tc = nt.nodes.new('ShaderNodeTexCoord')
    m = nt.nodes.new('ShaderNodeMapping')
    m.inputs['Scale'].default_value, m.inputs['Location'].default_value = (4, 4, 1), (0, 0, 0.5)
    fl = nt.nodes.new('ShaderNodeVectorMath')
    fl.operation = 'FLOOR'
    wn = nt.nodes.new('ShaderNodeTexWhiteNoise')
    nt.links.new(tc.outputs['Object'], m.inputs['Vector'])
    nt.links.new(m.outputs[0], fl.inputs[0])
    nt.links.new(fl.outputs[0], wn.inputs['Vector'])
    nt.links.new(wn.outputs['Color'], diffuse.inputs['Color'])


def magic_generated(nt, diffuse):
    """Nothing in the Vector input: Generated coordinates."""
    mg = nt.nodes.new('ShaderNodeTexMagic')
    mg.turbulence_depth = 3
    mg.inputs['Scale'].default_value, mg.inputs['Distortion'].default_value = 1.5, 1.3
    nt.links.new(mg.outputs['Color'], diffuse.inputs['Color'])


def gabor_generated_ramp(nt, diffuse):
    """A 3D Gabor's Value (nothing in its Vector: Generated) through a Color Ramp."""
    gb = nt.nodes.new('ShaderNodeTexGabor')
    gb.inputs['Scale'].default_value, gb.inputs['Frequency'].default_value = 3.0, 1.0
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (0.9, 0.5, 0.1, 1)
    ramp.color_ramp.elements[1].color = (0.05, 0.2, 0.7, 1)
    nt.links.new(gb.outputs['Value'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], diffuse.inputs['Color'])


@pytest.mark.parametrize('chain', [white_noise_tiles, magic_generated, gabor_generated_ramp],
                         ids=lambda c: c.__name__)
def test_texture_colour_renders_as_cycles(chain, tmp_path):
    sunplane.build(np.ones((1, 1, 4), np.float32), _wire(chain), RES, 16)
    dacrt, cycles = _blocks('DACRT', tmp_path), _blocks('CYCLES', tmp_path)
    assert dacrt.shape == (RES // BLOCK, RES // BLOCK, 3)
    assert np.ptp(cycles[..., 0]) > 0.1 * cycles.max(), "the pattern should show"
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.025, (err, dacrt[..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())
