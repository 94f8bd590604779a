"""Cycles' transparent roulette (integrator_intersect_terminate) at emissive and holdout surfaces: a camera
path that meets an emitter after more than min_transparent_bounces + 1 transparent passes is
rouletted there too. shade_surface adds the emission at the throughput before the roulette, then
ends the path before film_write_data_passes, so fewer samples write Normal there (unweighted);
Combined stays unbiased. DACRT had skipped emissive surfaces: an emissive floor seen through a
Transparent BSDF sphere of colour 0.6 had Normal Z 1.0 where Cycles' is 0.6 = sqrt(0.6^2), the
continuation probability (fuzz 9481: 1.0 against 0.953).
A holdout surface without emission is rouletted too, and ended unshaded: it writes no holdout,
and a path that goes on writes it at the throughput before the division (integrate_surface_holdout
runs before integrate_surface_terminate), so Cycles' transparency behind it is q of the true one:
alpha 0.784 = 1 - 0.6 x 0.36 where DACRT had 0.64; an emissive one is shaded either way."""
import bpy
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

GREY = 0.6            # the sphere's Transparent colour: throughput 0.36 past both its sides


def _scene(min_transparent, emitter_fac, holdout=False):
    """An emissive floor (strength 2) under a Transparent BSDF ico sphere, seen from above
    (orthographic), black world; emitter_fac: None for a plain Emission floor, else the factor
    of a Mix Shader of Emission and Transparent BSDF (the floor transparent itself), or 'diffuse'
    (a grey Diffuse floor); holdout: the floor a holdout object, the film transparent."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, 0, 8), kind='ORTHO', ortho_scale=6.0)
    if emitter_fac is None:
        floor = scenes.emission('Floor', (1.0, 1.0, 1.0), 2.0)
    elif emitter_fac == 'diffuse':
        floor = scenes.diffuse('Floor', (0.8, 0.8, 0.8))
    else:
        floor, nt, mix, a, b = scenes.mix_shader_material('Floor', 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent',
                                                          emitter_fac)
        a.inputs['Strength'].default_value = 2.0
    scenes.plane('Floor', size=10.0, materials=[floor]).is_holdout = holdout
    sc.render.film_transparent = holdout
    mat, nt, out = scenes._material('Glassy')
    node = nt.nodes.new('ShaderNodeBsdfTransparent')
    node.inputs['Color'].default_value = (GREY, GREY, GREY, 1.0)
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.5, location=(0, 0, 2))
    bpy.context.object.data.materials.append(mat)
    scenes.black_world()
    sc.view_layers[0].use_pass_normal = True
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.min_transparent_bounces = sc.dacrt.min_transparent_bounces = min_transparent
    return sc


@pytest.mark.parametrize('min_transparent, emitter_fac', [(0, None), (1, None), (0, 0.3)])
def test_transparent_roulette_at_emitters_matches_cycles(min_transparent, emitter_fac, tmp_path):
    """Over the floor seen through the sphere's middle: Normal Z (the share of samples writing
    it) near its closed form, 0.6 with the default min_transparent_bounces 0 and 1.0 with 1
    (no roulette at the third surface), and within 0.03 of Cycles'; Combined near
    2 x 0.36 (x 0.7 the emission's share of a Mix floor) and within 3% of Cycles'."""
    sc = _scene(min_transparent, emitter_fac)
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    c, d = out['CYCLES'], out['DACRT']
    mid = (slice(9, 15), slice(13, 19))               # inside the sphere's silhouette
    share = GREY if min_transparent == 0 else 1.0
    emit = 2.0 * GREY * GREY * (1.0 if emitter_fac is None else 1.0 - emitter_fac)
    nz = {e: float(v[f'{name}.Normal.Z'][mid].mean()) for e, v in (('c', c), ('d', d))}
    if emitter_fac is None:
        assert nz['c'] == pytest.approx(share, abs=0.03), nz
    assert nz['d'] == pytest.approx(nz['c'], abs=0.03), nz
    for key in ('Combined.R', 'Combined.G'):
        a, b = float(c[f'{name}.{key}'][mid].mean()), float(d[f'{name}.{key}'][mid].mean())
        assert a == pytest.approx(emit, rel=0.03), (key, a)
        assert b == pytest.approx(a, rel=0.03), (key, a, b)


@pytest.mark.parametrize('min_transparent, emitter_fac, alpha', [(0, 'diffuse', 1.0 - GREY ** 3),
                                                                 (1, 'diffuse', 1.0 - GREY ** 2),
                                                                 (0, None, 1.0 - GREY ** 2)])
def test_transparent_roulette_at_holdouts_matches_cycles(min_transparent, emitter_fac, alpha, tmp_path):
    """A holdout floor seen through the sphere, transparent film: alpha over the sphere's middle
    near Cycles' closed form (1 - q x 0.36 with the roulette's survival q = 0.6 at a holdout
    without emission; 1 - 0.36 without the roulette (min_transparent_bounces 1) or at an
    emissive one) and within 0.015 of Cycles'; Combined black."""
    sc = _scene(min_transparent, emitter_fac, holdout=True)
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    mid = (slice(9, 15), slice(13, 19))
    a = {e: float(v[f'{name}.Combined.A'][mid].mean()) for e, v in out.items()}
    assert a['CYCLES'] == pytest.approx(alpha, abs=0.015), a
    assert a['DACRT'] == pytest.approx(a['CYCLES'], abs=0.015), a
    assert float(out['DACRT'][f'{name}.Combined.R'][mid].max()) == 0.0
