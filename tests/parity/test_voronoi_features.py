"""The Voronoi Texture beyond one octave of F1 (addon/export/procedurals.py _voronoi,
procedural.voronoi_texture, the native dacrt.shading.voronoi_texture) against Cycles.

Pointwise, as tests/parity/test_procedural.py: Cycles renders the texture's output as emission
at the pixel centres of a 48x48 view (a box filter 0.01 px wide); the export compiles the same
emission colour's chain and evaluates it at those centres' object coordinates. Continuous
outputs (the distances, Smooth F1's every output) agree within 0.005 at every pixel; outputs
that jump at a cell border (a colour, a position, F2's, a radius) within 0.005 but on fewer than
0.5% of the pixels (a centre within the filter's jitter of a border). Before, the export did
not compile these chains (the node's own value stood in, reported): each case failed.

Rendered: a sun-lit plane whose Diffuse colour reads such a texture, both engines, 8x8 block
means within 2.5% of the brightest block (as test_procedural.py).
"""
import numpy as np
import pytest

from addon.export import procedurals
from tests.addon import scenes

from . import sunplane
from .test_procedural import RES, _blocks, _centres, _emission_plane, _relink_surface, _wire

pytestmark = pytest.mark.usefixtures('parity_addon')


def _w_from_x(nt, tc, tex):
    """W (1D and 4D) follows the object's x; a 4D Vector reads Object coordinates."""
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(tc.outputs['Object'], sep.inputs[0])
    nt.links.new(sep.outputs['X'], tex.inputs['W'])
    if tex.voronoi_dimensions == '4D':
        nt.links.new(tc.outputs['Object'], tex.inputs['Vector'])


V = 'ShaderNodeTexVoronoi'
# name: (output, settings, continuous): continuous outputs agree everywhere
CASES = {
    # fractal F1: Detail's octaves, its fraction, Roughness, Lacunarity, Normalize
    'fractal_f1_distance': ('Distance', {'Detail': 3.0, 'Roughness': 0.6, 'Scale': 3.0}, True),
    'fractal_f1_color_fractional': ('Color', {'Detail': 2.5, 'Roughness': 0.7, 'Lacunarity': 2.5, 'Scale': 2.0},
                                    False),
    'fractal_f1_position': ('Position', {'Detail': 2.0, 'Roughness': 0.5, 'Scale': 2.0}, False),
    'fractal_f1_2d_manhattan_normalized': ('Distance', {'voronoi_dimensions': '2D', 'distance': 'MANHATTAN',
                                                        'Detail': 1.5, 'normalize': True, 'Scale': 3.0}, True),
    'fractal_f1_color_normalized': ('Color', {'Detail': 2.0, 'Roughness': 0.8, 'normalize': True}, False),
    # F2
    'f2_distance': ('Distance', {'feature': 'F2', 'Scale': 3.0}, True),
    'f2_color_2d': ('Color', {'feature': 'F2', 'voronoi_dimensions': '2D', 'Scale': 4.0}, False),
    'f2_position': ('Position', {'feature': 'F2', 'Scale': 2.0, 'Randomness': 0.7}, False),
    'f2_fractal_chebychev_normalized': ('Distance', {'feature': 'F2', 'distance': 'CHEBYCHEV', 'Detail': 1.5,
                                                     'normalize': True, 'Scale': 2.0}, True),
    # Smooth F1
    'smooth_f1_distance': ('Distance', {'feature': 'SMOOTH_F1', 'Smoothness': 0.6, 'Scale': 3.0}, True),
    'smooth_f1_color_2d': ('Color', {'feature': 'SMOOTH_F1', 'voronoi_dimensions': '2D', 'Smoothness': 1.0,
                                     'Scale': 4.0}, True),
    'smooth_f1_position_fractal': ('Position', {'feature': 'SMOOTH_F1', 'Smoothness': 0.3, 'Detail': 1.0,
                                                'Scale': 2.0}, True),
    # Distance to Edge
    'edge_3d': ('Distance', {'feature': 'DISTANCE_TO_EDGE', 'Scale': 3.0}, True),
    'edge_2d_fractal_normalized': ('Distance', {'feature': 'DISTANCE_TO_EDGE', 'voronoi_dimensions': '2D',
                                                'Detail': 2.5, 'normalize': True, 'Randomness': 0.8,
                                                'Scale': 2.0}, True),
    # Minkowski
    'minkowski_distance': ('Distance', {'distance': 'MINKOWSKI', 'Exponent': 1.5, 'Scale': 3.0}, True),
    'minkowski_f2_2d_normalized': ('Distance', {'distance': 'MINKOWSKI', 'Exponent': 3.0, 'feature': 'F2',
                                                'voronoi_dimensions': '2D', 'normalize': True, 'Scale': 3.0}, True),
    'minkowski_color': ('Color', {'distance': 'MINKOWSKI', 'Exponent': 0.7, 'Scale': 2.0}, False),
    # N-Sphere Radius
    'n_sphere_radius_3d': ('Radius', {'feature': 'N_SPHERE_RADIUS', 'Scale': 3.0}, False),
    'n_sphere_radius_2d': ('Radius', {'feature': 'N_SPHERE_RADIUS', 'voronoi_dimensions': '2D', 'Randomness': 0.7,
                                      'Scale': 4.0}, False),
    # 1D (W alone, from the object's x) and 4D
    '1d_distance_fractal': ('Distance', {'voronoi_dimensions': '1D', 'Detail': 1.5, 'Scale': 3.0}, True),
    '1d_color_f2': ('Color', {'voronoi_dimensions': '1D', 'feature': 'F2', 'Scale': 3.0}, False),
    '1d_w_smooth': ('W', {'voronoi_dimensions': '1D', 'feature': 'SMOOTH_F1', 'Scale': 3.0}, True),
    '1d_edge': ('Distance', {'voronoi_dimensions': '1D', 'feature': 'DISTANCE_TO_EDGE', 'Scale': 4.0}, True),
    '1d_radius': ('Radius', {'voronoi_dimensions': '1D', 'feature': 'N_SPHERE_RADIUS', 'Scale': 4.0}, False),
    '4d_distance': ('Distance', {'voronoi_dimensions': '4D', 'Scale': 2.0}, True),
    '4d_color_smooth': ('Color', {'voronoi_dimensions': '4D', 'feature': 'SMOOTH_F1', 'Smoothness': 0.5,
                                  'Scale': 2.0}, True),
    '4d_w_f2': ('W', {'voronoi_dimensions': '4D', 'feature': 'F2', 'Scale': 2.0}, False),
    '4d_edge_fractal': ('Distance', {'voronoi_dimensions': '4D', 'feature': 'DISTANCE_TO_EDGE',
                                               'Detail': 1.0, 'Scale': 2.0}, True),
    '4d_radius': ('Radius', {'voronoi_dimensions': '4D', 'feature': 'N_SPHERE_RADIUS', 'Scale': 2.0}, False),
}


def _compiled(tex):
    """The export's function of the emission colour's chain (None: not compiled)."""
    em = next(n for n in tex.id_data.nodes if n.type == 'EMISSION')
    reasons = []
    found = procedurals.compile_socket(em.inputs['Color'], True, reasons)
    return found, reasons


@pytest.mark.parametrize('case', sorted(CASES))
def test_voronoi_feature_matches_cycles_pointwise(case, tmp_path):
    output, settings, continuous = CASES[case]
    settings = dict(settings)
    dims = settings.get('voronoi_dimensions', '3D')
    tex = _emission_plane(V, output, settings, wire=_w_from_x if dims in ('1D', '4D') else None)
    found, reasons = _compiled(tex)
    assert found is not None, (case, reasons)
    fn, needs, _ = found
    p = _centres()
    mine = np.broadcast_to(np.asarray(fn({'object': p, 'generated': p, 'uv': p}), np.float64), (len(p), 3))
    r = scenes.read_exr(scenes.render_exr(tmp_path / "cycles.exr"))
    cycles = np.stack([r['R'], r['G'], r['B']], -1).reshape(-1, 3)
    assert np.ptp(cycles) > 0.1, "the texture should vary over the view"
    err = np.abs(mine - cycles).max(axis=1)
    print(f"{case}: max {err.max():.2e}, mean {err.mean():.2e}, over 0.005 {np.mean(err > 0.005):.4f}")
    if continuous:
        assert err.max() < 0.005, (case, float(err.max()), float(err.mean()))
    else:
        assert np.mean(err > 0.005) < 0.005, (case, float(np.mean(err > 0.005)), float(np.median(err)))


# --- rendered through the add-on ------------------------------------------------------------------

def fractal_f1_color(nt, diffuse):
    tc = nt.nodes.new('ShaderNodeTexCoord')
    v = nt.nodes.new(V)
    v.inputs['Scale'].default_value, v.inputs['Detail'].default_value = 2.0, 2.5
    v.inputs['Roughness'].default_value = 0.7
    nt.links.new(tc.outputs['Object'], v.inputs['Vector'])
    nt.links.new(v.outputs['Color'], diffuse.inputs['Color'])


def fractal_f2_color(nt, diffuse):
    tc = nt.nodes.new('ShaderNodeTexCoord')
    v = nt.nodes.new(V)
    v.feature = 'F2'
    v.inputs['Scale'].default_value, v.inputs['Detail'].default_value = 2.0, 1.5
    nt.links.new(tc.outputs['Object'], v.inputs['Vector'])
    nt.links.new(v.outputs['Color'], diffuse.inputs['Color'])


def edges_ramp(nt, diffuse):
    """Distance to Edge through a Color Ramp: dark cell borders (Generated coordinates)."""
    v = nt.nodes.new(V)
    v.feature = 'DISTANCE_TO_EDGE'
    v.inputs['Scale'].default_value = 3.0
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (0.05, 0.05, 0.1, 1)
    ramp.color_ramp.elements[1].color = (0.9, 0.7, 0.3, 1)
    ramp.color_ramp.elements[1].position = 0.3
    nt.links.new(v.outputs['Distance'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], diffuse.inputs['Color'])


@pytest.mark.parametrize('chain', [fractal_f1_color, fractal_f2_color, edges_ramp], ids=lambda c: c.__name__)
def test_voronoi_feature_renders_as_cycles(chain, tmp_path):
    sunplane.build(np.ones((1, 1, 4), np.float32), _wire(chain), RES, 16)
    _relink_surface()
    dacrt, cycles = _blocks('DACRT', tmp_path), _blocks('CYCLES', tmp_path)
    assert np.ptp(cycles[..., 0]) > 0.1 * cycles.max(), "the pattern should show"
    err = np.abs(dacrt - cycles).max() / cycles.max()
    print(f"{chain.__name__}: {err:.4f} of the brightest block")
    assert err < 0.025, (err, dacrt[..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())
