"""Emission driven by procedural textures against Cycles: an Emission's (or a Principled's, or a
surface Background's) Color and Strength computed by procedural chains per shading point, for
camera hits, BSDF hits and light samples (export/procedurals.compile_emission, the emission
texture the integrator reads per hit and per sampled point, _procedural_emission_power weighing
the light choice by the emission measured on the emitter).

Before, such an emission read the texture's own value, reported ("colour from 'Checker Texture'
node; its own value used"): a checker panel one flat white, a noise-driven emitter lit its
floor 2.0x as bright as Cycles, a colour linked into the Surface was black."""
import bpy
import numpy as np
import pytest

from addon import integrator
from tests.addon import scenes

from .test_procedural import _emission_plane

pytestmark = pytest.mark.usefixtures('parity_addon')


def _rgb(tmp_path, scene=None):
    """{engine: (H, W, 3) Combined}, row 0 at the bottom."""
    sc = scene or bpy.context.scene
    layer = sc.view_layers[0].name
    return {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}


def _settings(samples, bounces, box=True):
    sc = bpy.context.scene
    sc.cycles.device = 'CPU'
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = bounces
    sc.dacrt.total_max_bounces = bounces     # (Cycles' Total: translucent bounces count against it)
    sc.cycles.glossy_bounces = 0
    if box:
        sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
        sc.cycles.filter_width = sc.dacrt.filter_width = 1.0


def test_checker_emission_seen_by_the_camera(tmp_path, said):
    """(a) A plane emitting a two-colour Checker (Object coordinates, 4 x 4 unit cells), seen
    straight on: each cell's mean within 1% of Cycles' (measured 0.0%); it had been white."""
    _emission_plane('ShaderNodeTexChecker', 'Color', {'Scale': 1.0, 'Color1': (1.0, 0.3, 0.05, 1.0),
                                                      'Color2': (0.05, 0.2, 0.9, 1.0)})
    em = next(n for n in bpy.data.materials["Emitter"].node_tree.nodes if n.type == 'EMISSION')
    em.inputs['Strength'].default_value = 2.0
    _settings(4, 0)
    img = _rgb(tmp_path)
    d, c = img['DACRT'], img['CYCLES']
    cell = 48 // 4
    for i in range(4):
        for j in range(4):
            block = (slice(i * cell + 2, (i + 1) * cell - 2), slice(j * cell + 2, (j + 1) * cell - 2))
            cm, dm = c[block].mean((0, 1)), d[block].mean((0, 1))
            np.testing.assert_allclose(dm, cm, rtol=0.01, atol=1e-4, err_msg=f"cell {i},{j}")
    assert np.ptp(c[..., 0]) > 1.0, "the checker should show"
    assert not any("own value" in t or "not evaluated" in t for t in said), said


def _floor_and_emitter(make_material, camera_sees_emitter, emitter=None):
    """A 6 x 6 grey floor under an emitter 1.2 above it, facing down (a 2 x 2 plane unless
    emitter(material) makes one), of the material make_material() makes, seen from above at an
    angle; a black world."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    emitter_material = make_material()
    sc.render.resolution_x, sc.render.resolution_y = 48, 36
    scenes.plane("Floor", size=6.0, materials=(scenes.diffuse("Floor", (0.8, 0.8, 0.8)),))
    ob = emitter(emitter_material) if emitter is not None else \
        scenes.plane("Emitter", size=2.0, location=(0, 0, 1.2), materials=(emitter_material,))
    if emitter is None:
        ob.rotation_euler = (np.pi, 0.0, 0.0)            # facing the floor
    ob.visible_camera = camera_sees_emitter
    scenes.camera(location=(0, -6.5, 5.5), rotation=(np.radians(48), 0, 0))
    scenes.black_world()
    return sc, ob


def _noise_strength_material():
    """White emission whose Strength is a Noise Texture (Object coordinates, Scale 1.5) through
    a Map Range (0.35..0.65 -> 0..6): bright and dark patches over the emitter."""
    mat, nt, out = scenes._material("NoiseLight")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Strength'].default_value = 1.0           # (what it had read)
    tc = nt.nodes.new('ShaderNodeTexCoord')
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.inputs['Scale'].default_value = 1.5
    nz.inputs['Detail'].default_value = 2.0
    mr = nt.nodes.new('ShaderNodeMapRange')
    mr.inputs['From Min'].default_value, mr.inputs['From Max'].default_value = 0.35, 0.65
    mr.inputs['To Max'].default_value = 6.0
    nt.links.new(tc.outputs['Object'], nz.inputs['Vector'])
    nt.links.new(nz.outputs['Fac'], mr.inputs['Value'])
    nt.links.new(mr.outputs['Result'], em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('sampling', ['AUTO', 'NONE'])
def test_noise_strength_lights_the_floor(tmp_path, sampling):
    """(b) A Noise Texture into Emission Strength, the emitter hidden from the camera: the
    floor's mean within 2% of Cycles' (measured 0.3%), light-sampled (the sampled point reads
    the noise, the light choice weighed by its measured mean) or left to BSDF rays (Emission
    Sampling None); the halves of the floor under the emitter within 4% (0.15%, 0.4%). It had
    lit the floor with the Map Range of the noise node's own value: 2.0x Cycles'."""
    def material():
        mat = _noise_strength_material()
        mat.cycles.emission_sampling = sampling
        return mat
    _floor_and_emitter(material, False)
    _settings(256, 1, box=False)
    img = _rgb(tmp_path)
    d, c = img['DACRT'], img['CYCLES']
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02)
    for cols in (slice(8, 24), slice(24, 40)):
        np.testing.assert_allclose(d[6:30, cols].mean((0, 1)), c[6:30, cols].mean((0, 1)), rtol=0.04)


def _blocks(img, b=6):
    h, w = img.shape[:2]
    return img[:h // b * b, :w // b * b].reshape(h // b, b, w // b, b, 3).mean((1, 3))


def _compare_blocks(img, tol):
    d, c = _blocks(img['DACRT']), _blocks(img['CYCLES'])
    err = np.abs(d - c).max() / c.max()
    assert err < tol, (err, d[..., 0].round(3).tolist(), c[..., 0].round(3).tolist())
    np.testing.assert_allclose(img['DACRT'].mean((0, 1)), img['CYCLES'].mean((0, 1)), rtol=0.02)


def _wave_generated_material():
    """Wave bands (Generated coordinates: an unlinked Vector) through a Color Ramp, orange to
    blue, times Strength 3."""
    mat, nt, out = scenes._material("WaveLight")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Strength'].default_value = 3.0
    w = nt.nodes.new('ShaderNodeTexWave')
    w.inputs['Scale'].default_value = 1.2
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (1.0, 0.45, 0.05, 1)
    ramp.color_ramp.elements[1].color = (0.02, 0.1, 0.8, 1)
    nt.links.new(w.outputs['Fac'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _gradient_object_material():
    """A Linear Gradient on Object coordinates (x: -1..1 across the object, clamped) into a
    Principled-free Emission's Strength x 4, colour a warm white."""
    mat, nt, out = scenes._material("GradientLight")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (1.0, 0.8, 0.6, 1)
    tc = nt.nodes.new('ShaderNodeTexCoord')
    g = nt.nodes.new('ShaderNodeTexGradient')
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY'
    m.inputs[1].default_value = 4.0
    nt.links.new(tc.outputs['Object'], g.inputs['Vector'])
    nt.links.new(g.outputs['Fac'], m.inputs[0])
    nt.links.new(m.outputs[0], em.inputs['Strength'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


def _box(material):
    ob = scenes.cube("Emitter", size=1.0, location=(0, 0.3, 0.9), materials=(material,))
    ob.rotation_euler = (0.3, 0.2, 0.5)
    ob.scale = (1.6, 0.9, 1.0)
    return ob


def _slab(material):
    """A plane scaled (2, 0.8) and turned about z and x: Object coordinates differ from world."""
    ob = scenes.plane("Emitter", size=2.0, location=(0.2, 0.0, 1.2), materials=(material,))
    ob.rotation_euler = (np.pi - 0.35, 0.0, 0.6)
    ob.scale = (2.0, 0.8, 1.0)
    return ob


@pytest.mark.parametrize('case', ['wave_generated_box', 'gradient_object_scaled'])
def test_procedural_emitter_seen_and_lighting(tmp_path, case):
    """(c) A mesh emitter whose emission a Wave (Generated coordinates, a scaled and turned box)
    or a Gradient (Object coordinates, a scaled and turned plane) computes, seen by the camera
    and lighting the floor: 6 x 6-pixel blocks within 3% of the brightest block of Cycles'
    (measured 0.7% and 0.26%), the mean within 2% (0.07%, 0.04%); they had been 27% and 122% off,
    the plane's mean 2.5x."""
    if case == 'wave_generated_box':
        _floor_and_emitter(_wave_generated_material, True, _box)
    else:
        _floor_and_emitter(_gradient_object_material, True, _slab)
    _settings(256, 1)
    _compare_blocks(_rgb(tmp_path), 0.03)


def _principled_material(shader):
    """(d) A Principled BSDF (black base, no specular) emitting a Voronoi cell colour x 3
    ('principled'); the same Emission added to a constant one ('add'); a Mix Shader (0.4) of
    a grey diffuse and a Background shader of a Magic colour ('mix_background'); or a Checker's
    colour linked straight into the Surface (Cycles' Emission of strength 1 of it)."""
    mat, nt, out = scenes._material("ProcLight")
    tc = nt.nodes.new('ShaderNodeTexCoord')
    if shader == 'colour_into_surface':
        ck = nt.nodes.new('ShaderNodeTexChecker')
        ck.inputs['Scale'].default_value = 1.5
        ck.inputs['Color1'].default_value = (4.0, 2.0, 0.5, 1)
        ck.inputs['Color2'].default_value = (0.2, 0.5, 3.0, 1)
        nt.links.new(tc.outputs['Object'], ck.inputs['Vector'])
        nt.links.new(ck.outputs['Color'], out.inputs['Surface'])
        return mat
    if shader == 'mix_background':
        mg = nt.nodes.new('ShaderNodeTexMagic')
        mg.turbulence_depth = 2
        mg.inputs['Scale'].default_value = 2.0
        nt.links.new(tc.outputs['Object'], mg.inputs['Vector'])
        bg = nt.nodes.new('ShaderNodeBackground')
        bg.inputs['Strength'].default_value = 5.0
        nt.links.new(mg.outputs['Color'], bg.inputs['Color'])
        dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
        dif.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1)
        mix = nt.nodes.new('ShaderNodeMixShader')
        mix.inputs['Fac'].default_value = 0.4
        nt.links.new(dif.outputs[0], mix.inputs[1])
        nt.links.new(bg.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
        return mat
    vo = nt.nodes.new('ShaderNodeTexVoronoi')
    vo.inputs['Scale'].default_value = 2.0
    nt.links.new(tc.outputs['Object'], vo.inputs['Vector'])
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0, 0, 0, 1)
    p.inputs['Specular IOR Level'].default_value = 0.0
    p.inputs['Emission Strength'].default_value = 3.0
    nt.links.new(vo.outputs['Color'], p.inputs['Emission Color'])
    if shader == 'principled':
        nt.links.new(p.outputs[0], out.inputs['Surface'])
        return mat
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Color'].default_value = (0.2, 0.4, 0.1, 1)
    em.inputs['Strength'].default_value = 1.0
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(p.outputs[0], add.inputs[0])
    nt.links.new(em.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('shader', ['principled', 'add', 'mix_background', 'colour_into_surface'])
def test_principled_and_mixed_procedural_emission(tmp_path, shader, said):
    """(d) Principled Emission Color from a Voronoi colour, that plus a constant Emission (an Add
    Shader), a surface Background of a Magic colour mixed with a diffuse, a Checker colour into
    the Surface: seen by the camera and lighting the floor, 6 x 6 blocks within 3% of Cycles'
    brightest (measured 0.14-0.17%), the mean within 2% (0.2%); nothing said about them."""
    _floor_and_emitter(lambda: _principled_material(shader), True)
    _settings(256, 1)
    _compare_blocks(_rgb(tmp_path), 0.03)
    assert not any("own value" in t or "not evaluated" in t or "average" in t for t in said), said


def test_chain_the_export_cannot_follow_is_still_reported(tmp_path, said):
    """A noise on Geometry Tangent into an Emission's colour is not evaluated per point:
    the render says so, naming what it does not read, and reads the socket's own value."""
    def material():
        mat, nt, out = scenes._material("NormalNoise")
        em = nt.nodes.new('ShaderNodeEmission')
        tc = nt.nodes.new('ShaderNodeNewGeometry')
        nz = nt.nodes.new('ShaderNodeTexNoise')
        nt.links.new(tc.outputs['Tangent'], nz.inputs['Vector'])
        nt.links.new(nz.outputs['Color'], em.inputs['Color'])
        nt.links.new(em.outputs[0], out.inputs['Surface'])
        return mat
    _floor_and_emitter(material, True)
    _settings(1, 0)
    sc = bpy.context.scene
    sc.render.engine = 'DACRT'
    scenes.render_rgba(sc)
    assert any("procedural emission not evaluated per point (Geometry Tangent" in t for t in said), said


def _stripe_material():
    """Thin bright stripes: Wave bands (Generated) through a constant Color Ramp, about a tenth
    of the surface emitting at 40, the rest black."""
    mat, nt, out = scenes._material("Stripes")
    em = nt.nodes.new('ShaderNodeEmission')
    em.inputs['Strength'].default_value = 40.0
    w = nt.nodes.new('ShaderNodeTexWave')
    w.inputs['Scale'].default_value = 0.8
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.interpolation = 'CONSTANT'
    ramp.color_ramp.elements[0].color = (0, 0, 0, 1)
    ramp.color_ramp.elements[1].color = (1, 0.7, 0.3, 1)
    ramp.color_ramp.elements[1].position = 0.92
    nt.links.new(w.outputs['Fac'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('scale', [1.0, 1e-3, 1e3])
def test_light_choice_weight_moves_noise_only(tmp_path, monkeypatch, scale):
    """The weight a procedural emitter gets in the light choice (its emission measured on it)
    changes noise, never the expected image: mostly dark stripes beside a small constant
    emitter, both hidden from the camera, their weight as measured, x 1e-3 or x 1e3: the floor's
    mean within 2% of Cycles' each time (measured 0.05%, 0.5%, 0.04%)."""
    measured = integrator.Integrator._procedural_emission_power

    def scaled(self):
        measured(self)
        self._tri_emission[:, self._tri_emit_tex] *= scale
    monkeypatch.setattr(integrator.Integrator, '_procedural_emission_power', scaled)
    _floor_and_emitter(_stripe_material, False)
    lamp = scenes.plane("Lamp", size=0.5, location=(2.0, 1.5, 1.0), materials=(scenes.emission("L", (1, 1, 1), 6.0),))
    lamp.rotation_euler = (np.pi, 0.0, 0.0)
    lamp.visible_camera = False
    _settings(256, 1, box=False)
    img = _rgb(tmp_path)
    np.testing.assert_allclose(img['DACRT'].mean((0, 1)), img['CYCLES'].mean((0, 1)), rtol=0.02)
