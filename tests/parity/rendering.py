"""Rendering a parity scene with Cycles or DACRT under the fair settings of reference
blender-cycles.md section 2.7, and reading the result back as linear float pixels.

Both engines go through `bpy.ops.render.render()`; the Combined result is saved as a 32-bit
float single-layer EXR (scene-linear, no view transform: Blender applies the view transform
only to display-referred formats) and read back with OpenImageIO. Per-seed images are stacked
as (seeds, H, W, 4) float32, row 0 at the bottom as Blender stores them.
"""
import os
import tempfile
from pathlib import Path
from types import SimpleNamespace

import bpy
import numpy as np
from mathutils import Vector

from tests.addon import scenes
from tests.parity import stats


def build(spec):
    """Reset to a factory-empty scene, build spec's scene and apply the shared settings."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    r = scene.render
    r.resolution_x, r.resolution_y = spec.resolution
    r.resolution_percentage = 100
    spec.build()
    fair_scene_settings(scene, terminator=spec.terminator)
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = 'Standard', 'None', 0.0, 1.0
    return scene


def fair_scene_settings(scene, terminator=False):
    """The render and object settings both engines share (reference section 2.7), for a built
    scene or one opened from a file. Both engines render Cycles' shadow terminator offsets, but
    they are zeroed unless `terminator`: the other scenes and the benchmarks test the rest."""
    r = scene.render
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_motion_blur = False
    r.use_compositing = False
    r.use_sequencer = False
    r.threads_mode = 'AUTO'
    for ob in bpy.data.objects if not terminator else ():
        ob.shadow_terminator_geometry_offset = 0.0
        ob.shadow_terminator_shading_offset = 0.0
        if hasattr(ob, 'cycles') and hasattr(ob.cycles, 'shadow_terminator_geometry_offset'):
            ob.cycles.shadow_terminator_geometry_offset = 0.0     # the older home of the setting


def matched(scene, samples, bounces=0, box=True):
    """fair_scene_settings, then both engines at `samples` and `bounces` on the CPU, without
    denoising or adaptive sampling, with a 1-pixel Box filter unless not `box` (small tests
    comparing block means)."""
    fair_scene_settings(scene)
    scene.cycles.device, scene.cycles.use_denoising, scene.cycles.use_adaptive_sampling = 'CPU', False, False
    scene.cycles.samples = scene.dacrt.samples = samples
    scene.cycles.max_bounces = scene.dacrt.max_bounces = bounces
    # (Cycles' max_bounces is its Total: glass passes and translucent bounces count against it too)
    scene.dacrt.total_max_bounces = bounces
    if box:
        scene.cycles.pixel_filter_type, scene.dacrt.filter_type = 'BOX', 'BOX'
        scene.cycles.filter_width = scene.dacrt.filter_width = 1.0


def room_file():
    """A fresh file for an interior test: 64 x 48 at 100%, the Standard view transform (no look)
    and a world of its own; (scene, world)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    s = bpy.context.scene
    s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = 64, 48, 100
    s.view_settings.view_transform, s.view_settings.look = 'Standard', 'None'
    w = bpy.data.worlds.new('w')
    s.world = w
    return s, w


def interior(scene, bounces=8):
    """An interior test's view and settings: a 16 mm camera in a room's corner at (0.3, 0.3, 1.5)
    looking at (3.5, 4, 1); matched at 64 spp (Cycles 128) and `bounces` of every kind, Tabulated
    Sobol, seed 0, light threshold 0."""
    cd = bpy.data.cameras.new('interior')
    cd.lens = 16
    c = bpy.data.objects.new('interior', cd)
    scene.collection.objects.link(c)
    c.location = (0.3, 0.3, 1.5)
    c.rotation_euler = (Vector((3.5, 4.0, 1.0)) - c.location).to_track_quat('-Z', 'Y').to_euler()
    scene.camera = c
    matched(scene, 64, bounces=bounces)
    cy = scene.cycles
    cy.samples, cy.diffuse_bounces, cy.glossy_bounces = 128, bounces, bounces
    cy.light_sampling_threshold = 0.0
    cy.sampling_pattern, cy.seed, scene.dacrt.seed = 'TABULATED_SOBOL', 0, 0


def mean_of(scene, engine, path):
    """The whole-image mean of `engine`'s Combined RGB (a linear EXR written to path)."""
    scene.render.engine = engine
    return float(render_combined(scene, str(path))[..., :3].mean())


def set_cycles(scene, spec, seed):
    scene.render.engine = 'CYCLES'
    c = scene.cycles
    c.device = 'CPU'
    c.samples = spec.cycles_samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = c.diffuse_bounces = spec.bounces     # K: up to K+1 diffuse reflections
    c.sample_clamp_direct, c.sample_clamp_indirect = spec.clamp
    c.light_sampling_threshold = 0.0
    c.caustics_reflective = c.caustics_refractive = True
    c.pixel_filter_type = spec.filter_type     # same identifiers as scene.dacrt.filter_type
    c.filter_width = spec.filter_width
    c.film_exposure = 1.0
    c.sampling_pattern = 'TABULATED_SOBOL'
    c.use_animated_seed = False
    c.seed = seed
    c.use_light_tree = True


def set_dacrt(scene, spec, seed):
    scene.render.engine = 'DACRT'
    d = scene.dacrt
    d.samples = spec.dacrt_samples
    d.max_bounces = spec.bounces
    d.filter_type = spec.filter_type
    d.filter_width = spec.filter_width
    d.seed = seed
    d.sample_clamp_direct, d.sample_clamp_indirect = spec.clamp      # as set_cycles (fair: 0, 0)


def engine_means(scene, directory, tag, samples=256, bounces=4):
    """{engine: Combined's RGB means (float64)} of the scene rendered by Cycles and DACRT with
    the fair settings at `samples` and `bounces`, EXRs named by tag in directory."""
    spec = SimpleNamespace(cycles_samples=samples, dacrt_samples=samples, bounces=bounces, clamp=(0.0, 0.0),
                           filter_type='BLACKMAN_HARRIS', filter_width=1.5)
    means = {}
    for engine, setup in (('CYCLES', set_cycles), ('DACRT', set_dacrt)):
        setup(scene, spec, 0)
        img = render_combined(scene, str(Path(directory) / f"{engine}-{tag}.exr"))
        means[engine] = img[..., :3].astype(np.float64).mean(axis=(0, 1))
    return means


def small_cornell(width=48, height=36):
    """A fresh file holding the parity Cornell box (scenes.build_cornell) at width x height with
    the fair settings; returns its scene."""
    from . import scenes as parity_scenes
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    parity_scenes.build_cornell()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = width, height
    fair_scene_settings(scene)
    return scene


def render_layers(scene, spec, directory):
    """{engine: {'<layer>.<pass>.<channel>': (H, W) float32}} of the scene rendered by Cycles
    and DACRT with spec's settings (seed 0), as multilayer EXRs in directory."""
    out = {}
    for engine, setup in (('CYCLES', set_cycles), ('DACRT', set_dacrt)):
        setup(scene, spec, 0)
        out[engine] = scenes.read_exr(scenes.render_exr(str(Path(directory) / f"{engine}.exr"), scene,
                                                        multilayer=True))
    return out


def render_combined(scene, path):
    """Render with the scene's engine, save Combined as float32 EXR at `path`, return it as
    (H, W, 4) float32 (row 0 at the bottom)."""
    bpy.ops.render.render()
    s = scene.render.image_settings
    if hasattr(s, 'media_type'):
        s.media_type = 'IMAGE'
    s.file_format = 'OPEN_EXR'
    s.color_mode = 'RGBA'
    s.color_depth = '32'
    s.exr_codec = 'ZIP'
    result = bpy.data.images['Render Result']
    if os.path.exists(path):
        os.remove(path)
    result.save_render(filepath=str(path), scene=scene)
    if not os.path.exists(path):
        raise RuntimeError(f"{scene.render.engine} produced no image (nothing saved to {path}); "
                           "see the render's error report above")
    return read_exr(path)


def read_exr(path):
    """(H, W, 4) float32 RGBA of a single-part EXR, row 0 at the bottom."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError(f"cannot open {path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        names = list(spec.channelnames)
        pixels = np.asarray(inp.read_image(0, 0, 0, spec.nchannels, 'float'))
    finally:
        inp.close()
    pixels = pixels.reshape(spec.height, spec.width, spec.nchannels)[::-1]
    missing = [c for c in 'RGBA' if c not in names]
    if missing:
        raise RuntimeError(f"{path} has channels {names}, missing {missing}")
    return np.stack([pixels[..., names.index(c)] for c in 'RGBA'], axis=-1).astype(np.float32)


def render_seeds(spec, engine, seeds, workdir=None):
    """Build spec's scene once and render it with `engine` ('CYCLES' or 'DACRT') for every
    seed; returns (len(seeds), H, W, 4) float32."""
    scene = build(spec)
    configure = set_cycles if engine == 'CYCLES' else set_dacrt
    images = []
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        for seed in seeds:
            configure(scene, spec, seed)
            images.append(render_combined(scene, os.path.join(tmp, f"{engine}-{seed}.exr")))
    shapes = {im.shape for im in images}
    if len(shapes) != 1:
        raise RuntimeError(f"{engine} images of {spec.name} differ in size between seeds: {shapes}")
    return np.stack(images)


def assert_agrees(scene, seeds=4, **compare):
    """Renders scene with Cycles and with DACRT once per seed 0..seeds-1 and asserts that the
    two agree by stats.compare (per channel mean, per pixel and per block; its keywords
    `compare`); returns the (seeds, H, W, 3) stacks (cycles, dacrt) for a test's own checks."""
    cycles, dacrt = scenes.seeded_rgb(scene, 'CYCLES', seeds), scenes.seeded_rgb(scene, 'DACRT', seeds)
    result = stats.compare(cycles, dacrt, **compare)
    assert result.passed, result.summary()
    return cycles, dacrt
