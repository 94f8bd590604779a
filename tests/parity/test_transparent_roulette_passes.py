"""Cycles' Russian roulette on camera paths behind transparent surfaces: at a surface met after
more than min_transparent_bounces + 1 transparent passes (Cycles stores the setting + 1;
integrator_intersect_terminate, path_state_continuation_probability), a path goes on with
probability min(sqrt(max throughput), 1) or ends there unshaded. Normal, UV, shader AOVs and
sample 0's Depth are not weighted by the throughput, so behind two semi-transparent sheets
fewer samples write them; Combined and alpha stay unbiased. DACRT had no such roulette: the
floor's share of the Normal pass was 0.62 where Cycles' is 0.47."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _material(name, color, transparent=None):
    """Diffuse of `color` writing 1 to the VALUE AOV 'av'; with `transparent`, a Mix Shader of
    it and a Transparent BSDF at that factor."""
    if transparent is None:
        mat = scenes.diffuse(name, color)
        nt = mat.node_tree
    else:
        mat, nt, mix, a, b = scenes.mix_shader_material(name, 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent',
                                                        transparent)
        a.inputs['Color'].default_value = (*color, 1.0)
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'av'
    aov.inputs['Value'].default_value = 1.0
    return mat


def _scene(min_transparent):
    """A floor (2 x 2) under two sheets (3 x 3, alpha 0.4, below the Pass Alpha Threshold 0.5)
    seen from straight above, transparent film (the sheets' rim shows the background)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    sc.render.film_transparent = True
    scenes.camera(location=(0, 0, 8), kind='PERSP')
    scenes.plane("Floor", size=2.0, materials=[_material("Floor", (0.8, 0.8, 0.8))])
    for z, color in ((1.5, (0.2, 0.2, 0.8)), (0.75, (0.8, 0.2, 0.2))):
        scenes.plane(f"Sheet{z}", size=3.0, location=(0, 0, z), materials=[_material(f"Sheet{z}", color, 0.6)])
    scenes.light('SUN', 3.0)
    scenes.world((0.3, 0.4, 0.5), 1.0)
    vl = sc.view_layers[0]
    a = vl.aovs.add()
    a.name, a.type = 'av', 'VALUE'
    vl.pass_alpha_threshold = 0.5
    vl.use_pass_normal = vl.use_pass_z = True
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.min_transparent_bounces = sc.dacrt.min_transparent_bounces = min_transparent
    return sc


@pytest.mark.parametrize('min_transparent, share', [(0, 0.474), (1, 0.623)])
def test_transparent_roulette_passes_match_cycles(min_transparent, share, tmp_path):
    """Over the floor seen through both sheets: the share of samples writing Normal (its Z)
    near its closed form (0.789^2 through the sheets, x 0.76 the roulette's survival with the
    default 0; no roulette there with 1) and within 0.03 of Cycles'; the AOV (1 per surface
    written) within 0.05; sample 0's Depth at the floor / lower / upper sheet within 0.08 of
    Cycles' shares; Combined and alpha, also where the sheets show the background, within 2%."""
    sc = _scene(min_transparent)
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    c, d = out['CYCLES'], out['DACRT']
    floor = (slice(16, 32), slice(24, 40))            # the floor under both sheets
    for eng in (c, d):                                # (the floor's normal is (0, 0, 1))
        assert eng[f'{name}.Normal.Z'][floor].mean() == pytest.approx(share, abs=0.03)
    assert d[f'{name}.Normal.Z'][floor].mean() == pytest.approx(c[f'{name}.Normal.Z'][floor].mean(), abs=0.03)
    assert d[f'{name}.av.X'][floor].mean() == pytest.approx(c[f'{name}.av.X'][floor].mean(), abs=0.05)
    inside = (slice(14, 34), slice(22, 42))           # (sample 0: one sample a pixel)
    for z in (8.0, 7.25, 6.5):
        shares = [(np.abs(e[f'{name}.Depth.Z'][inside] - z) < 0.2).mean() for e in (c, d)]
        assert shares[1] == pytest.approx(shares[0], abs=0.08), (z, shares)
    rim = np.zeros((48, 64), bool)                    # the sheets over the background
    rim[7:41, 15:49] = True
    rim[11:37, 19:45] = False
    for key in ('Combined.R', 'Combined.B', 'Combined.A'):
        for region in (floor, rim):
            a, b = c[f'{name}.{key}'][region].mean(), d[f'{name}.{key}'][region].mean()
            assert b == pytest.approx(a, rel=0.02, abs=0.005), (key, a, b)
