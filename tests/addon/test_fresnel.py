"""View-dependent factors as averages over view directions (addon/fresnel.py), against
independent references: Fresnel's equations from Snell's law (s and p polarisations), brute
force integration, the known hemispherical reflectance of glass (~0.092 for n = 1.5), the
reciprocity of the internal and external averages (1 - F_int = (1 - F_ext) / n^2), and the
closed form of the Facing output.
Also how the export reads a Mix Shader whose factor such a node drives (bpy)."""
import math

import bpy
import numpy as np
import pytest

from addon import export, fresnel

from . import scenes

MU = np.linspace(0.0, 1.0, 400_001)


def _snell_fresnel(mu, n):
    """Unpolarised reflectance from n1 = 1 into n (n < 1: from inside), by Snell's law."""
    sin_t2 = (1.0 - mu * mu) / (n * n)
    out = np.ones_like(mu)
    ok = sin_t2 < 1.0
    ct = np.sqrt(1.0 - sin_t2[ok])
    ci = mu[ok]
    rs = ((ci - n * ct) / (ci + n * ct)) ** 2
    rp = ((n * ci - ct) / (n * ci + ct)) ** 2
    out[ok] = 0.5 * (rs + rp)
    return out


def _average(f):
    """2 int_0^1 f(mu) mu dmu by the trapezoid rule on a fine grid."""
    return float(np.trapz(2.0 * f * MU, MU))


@pytest.mark.parametrize('eta', [1.2, 1.45, 2.0, 1 / 1.5, 0.9])
def test_cycles_fresnel_is_fresnels_equations(eta):
    mu = np.linspace(1e-3, 1.0, 1001)
    np.testing.assert_allclose(fresnel.fresnel_dielectric_cos(mu, eta), _snell_fresnel(mu, eta), atol=1e-12)


@pytest.mark.parametrize('ior', [1.01, 1.33, 1.45, 1.5, 2.5, 0.75])
def test_fresnel_average_matches_brute_force(ior):
    assert fresnel.fresnel_node_average(ior) == pytest.approx(_average(_snell_fresnel(MU, ior)), abs=2e-6)


def test_fresnel_average_known_values():
    glass = fresnel.fresnel_node_average(1.5)
    assert glass == pytest.approx(0.0918, abs=5e-4)
    assert fresnel.fresnel_node_average(1.0) == pytest.approx(0.0, abs=1e-12)
    inner = fresnel.fresnel_node_average(1 / 1.5)          # from inside: total internal reflection
    assert 1.0 - inner == pytest.approx((1.0 - glass) / 1.5 ** 2, abs=1e-9)
    assert fresnel.fresnel_node_average(1e6) > 0.99


def test_layer_weight_outputs():
    # Fresnel: eta = 1 / (1 - blend)
    assert fresnel.layer_weight_average(0.5, 'Fresnel') == pytest.approx(fresnel.fresnel_node_average(2.0))
    assert fresnel.layer_weight_average(0.0, 'Fresnel') == pytest.approx(0.0, abs=1e-12)
    # Facing: 1 - mu^p, p = 2 blend (< 0.5) or 0.5 / (1 - blend)
    for blend, p in ((0.5, 1.0), (0.25, 0.5), (0.75, 2.0), (0.1, 0.2)):
        expected = _average(1.0 - MU ** p)
        assert fresnel.layer_weight_average(blend, 'Facing') == pytest.approx(expected, abs=1e-6)
        assert fresnel.layer_weight_average(blend, 'Facing') == pytest.approx(p / (p + 2), abs=1e-12)
    assert fresnel.layer_weight_average(0.0, 'Facing') == 0.0


def test_per_texel_values_keep_their_shape():
    ior = np.array([[[1.5], [2.0]], [[1.5], [1.0]]])
    out = fresnel.fresnel_node_average(ior)
    assert out.shape == ior.shape
    assert out[0, 0, 0] == out[1, 0, 0] == fresnel.fresnel_node_average(1.5)
    assert out[1, 1, 0] == 0.0


def test_many_distinct_values_are_interpolated_closely():
    """A float image feeding the IOR has a value per texel: past _MAX_DISTINCT distinct values
    the averages come from a table over their range, within 1e-5 of each computed alone."""
    ior = np.random.default_rng(3).uniform(1.0, 3.0, (300, 300))
    out = fresnel.fresnel_node_average(ior)
    assert out.shape == ior.shape
    pick = ior.ravel()[:50]
    np.testing.assert_allclose(out.ravel()[:50], [fresnel.fresnel_node_average(v) for v in pick], atol=1e-5)


def test_export_mixes_per_point_by_the_view(scene, exported):
    """A clear coat over a paint, Mix Shader factor from Layer Weight: the albedo mixes per
    point by the factor Cycles computes from the view and the normal (a texture of the view,
    procedural.VIEW), nothing said; its stand-in where one is needed (mean) is the factor's
    average over view directions. (It had mixed by the average everywhere, said.)"""
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    mat, nt, mix, paint, coat = scenes.mix_shader_material("Paint", 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfGlossy')
    lw = nt.nodes.new('ShaderNodeLayerWeight')
    lw.inputs['Blend'].default_value = 0.5
    nt.links.new(lw.outputs['Fresnel'], mix.inputs['Fac'])
    paint.inputs['Color'].default_value = (0.8, 0.1, 0.05, 1)
    coat.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1)
    scenes.plane("Car", materials=(mat,))
    m = next(x for x in exported().materials if x.name == "Paint")
    tex = m.texture
    assert tex.needs >= {'incoming', 'normal', 'backfacing'}, tex.needs
    paint, coat = np.array([0.8, 0.1, 0.05]), export.reflectors.reflector_albedo(coat, [])   # (its stand-in)
    mu = np.array([1.0, 0.5, 0.1], np.float32)           # viewing cosines, front faces
    up = np.tile(np.array([0, 0, 1], np.float32), (3, 1))
    incoming = np.stack([np.sqrt(1 - mu * mu), np.zeros(3), mu], axis=1).astype(np.float32)
    rgb = tex.evaluate({'incoming': incoming, 'normal': up, 'backfacing': np.zeros((3, 1), np.float32)}).T
    f = _snell_fresnel(mu.astype(np.float64), 2.0)[:, None]
    np.testing.assert_allclose(m.base_color * rgb, (1 - f) * paint + f * coat, rtol=1e-5)
    avg = fresnel.fresnel_node_average(2.0)
    np.testing.assert_allclose(m.base_color * tex.mean(), (1 - avg) * paint + avg * coat, rtol=0.02)
    assert "view-dependent" not in m.approximated and "own value" not in m.approximated


def test_world_mix_factor_keeps_its_own_value(scene):
    """The world has no surface to view: a Layer Weight there is not averaged (its own value,
    reported, as before)."""
    _, nt, out = scenes.world_tree(scene)
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.25
    lw = nt.nodes.new('ShaderNodeLayerWeight')
    nt.links.new(lw.outputs['Facing'], mix.inputs['Fac'])
    for slot, colour in ((1, (1.0, 0.0, 0.0, 1.0)), (2, (0.0, 0.0, 1.0, 1.0))):
        bg = nt.nodes.new('ShaderNodeBackground')
        bg.inputs['Color'].default_value = colour
        nt.links.new(bg.outputs[0], mix.inputs[slot])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    uniform, env, reason = export.export_world(scene)
    np.testing.assert_allclose(uniform, (0.75, 0.0, 0.25))
    assert env is None and ("world Mix Shader factor not computed ('Layer Weight Facing' (view-dependent)); "
                            "its own value 0.25 used") in reason
