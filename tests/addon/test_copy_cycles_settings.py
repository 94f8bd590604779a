"""Copy Settings from Cycles (addon/operators.py): a scene made for Cycles takes its sampling,
bounces, seed, adaptive sampling, light tree, clamping, exposure and pixel filter into
scene.dacrt, and then renders as Cycles does; without it a Cycles Film > Exposure of 2 rendered
at half Cycles' brightness (the settings are separate groups, as Cycles' and EEVEE's)."""
import bpy
import numpy as np

from . import scenes


def _cycles_non_defaults(c):
    c.samples, c.preview_samples, c.seed, c.use_animated_seed = 37, 11, 5, True
    c.use_adaptive_sampling, c.adaptive_threshold, c.adaptive_min_samples = True, 0.05, 9
    c.use_light_tree = False
    c.sample_clamp_direct, c.sample_clamp_indirect = 3.0, 0.0
    c.film_exposure = 2.0
    c.max_bounces, c.diffuse_bounces, c.transmission_bounces, c.transparent_max_bounces = 3, 7, 2, 21
    c.pixel_filter_type, c.filter_width = 'GAUSSIAN', 2.5


def test_every_setting_is_copied_with_cycles_bounce_caps(scene):
    _cycles_non_defaults(scene.cycles)
    assert bpy.ops.dacrt.copy_cycles_settings() == {'FINISHED'}
    d = scene.dacrt
    assert (d.samples, d.preview_samples, d.seed, d.use_animated_seed) == (37, 11, 5, True)
    assert (d.use_adaptive_sampling, d.adaptive_min_samples) == (True, 9)
    assert np.isclose(d.adaptive_threshold, 0.05)
    assert d.use_light_tree is False
    assert (d.sample_clamp_direct, d.sample_clamp_indirect, d.film_exposure) == (3.0, 0.0, 2.0)
    # Cycles' Total (3) caps Diffuse (7) and Transmission (2); Transparent counts apart
    assert (d.max_bounces, d.transmission_max_bounces, d.transparent_max_bounces) == (3, 2, 21)
    assert d.total_max_bounces == 3     # and glass passes count against it (test_total_bounces.py)
    assert (d.filter_type, d.filter_width) == ('GAUSSIAN', 2.5)
    scene.cycles.diffuse_bounces = 1
    bpy.ops.dacrt.copy_cycles_settings()
    assert d.max_bounces == 1


def test_unlimited_viewport_samples_stay_unlimited(scene, capfd):
    """Cycles' Viewport Samples 0 means no limit; DACRT's minimum, 1, had stopped the viewport
    after one sample. Large counts are said as integers (it had printed 'Samples 1.23457e+07')."""
    scene.cycles.preview_samples, scene.cycles.samples = 0, 12345678
    bpy.ops.dacrt.copy_cycles_settings()
    assert scene.dacrt.preview_samples == scene.dacrt.bl_rna.properties['preview_samples'].hard_max
    assert scene.dacrt.samples == 12345678
    assert "Samples 12345678" in capfd.readouterr().out


def test_the_report_names_what_changed(scene, capfd):
    scene.cycles.film_exposure = 1.5
    bpy.ops.dacrt.copy_cycles_settings()
    out = capfd.readouterr().out          # Blender prints an operator's INFO report headless
    assert "DACRT settings copied from Cycles:" in out and "Exposure 1.5" in out, out
    bpy.ops.dacrt.copy_cycles_settings()
    assert "copied from Cycles: already the same" in capfd.readouterr().out


def test_copied_exposure_and_bounces_render_as_cycles(scene, tmp_path):
    """A lit box rendered by Cycles with exposure 2 and 1 bounce: DACRT with its defaults is half
    as bright (and bounces more); after the copy both agree in the mean."""
    scenes.camera((0, 0, 4.5))
    white = scenes.diffuse("White", (0.8, 0.8, 0.8))
    scenes.plane("Floor", size=6, materials=[white])
    scenes.cube("Block", size=1.0, location=(0.8, 0.3, 0.5), materials=[white])
    scenes.light('AREA', 200.0, location=(0, 0, 3), size=2.0)
    scenes.world((0.05, 0.05, 0.05))
    c = scene.cycles
    c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = 'CPU', 256, False, False
    c.film_exposure, c.max_bounces, c.diffuse_bounces = 2.0, 1, 1
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = 'Standard', 'None', 0.0, 1.0

    def mean(engine):
        scene.render.engine = engine
        img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", scene)))
        return float(img[..., :3].mean())

    cycles = mean('CYCLES')
    before = mean('DACRT')
    bpy.ops.dacrt.copy_cycles_settings()
    after = mean('DACRT')
    assert before / cycles < 0.6, (before, cycles)
    assert abs(after / cycles - 1.0) < 0.02, (after, cycles)
