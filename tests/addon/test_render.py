"""Rendering through Blender (bpy.ops.render.render) with the DACRT engine: images, passes,
border, view layers, reports, memory, cancel, write_still and the headless CLI."""
import ctypes
import math
import os
import re
import subprocess
import sys
import time

import bpy
import numpy as np
import pytest

import addon
from addon import engine as engine_module
from addon.demo import build_demo_scene

from . import conftest, scenes


def lit_plane_scene(scene, albedo=(0.2, 0.4, 0.6), size=(16, 12)):
    """A camera 5 m above a large diffuse plane lit by a sun."""
    scene.render.resolution_x, scene.render.resolution_y = size
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=100, materials=(scenes.diffuse("Ground", albedo),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 4


def textured_plane_scene(scene):
    """lit_plane_scene with a plane above the ground whose diffuse colour is a 64x64 image."""
    lit_plane_scene(scene)
    mat, nt, out = scenes._material("Textured")
    d, tex = nt.nodes.new('ShaderNodeBsdfDiffuse'), nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Tex", np.full((64, 64, 4), 0.5, np.float32))
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Textured", size=2.0, location=(0, 0, 0.5), materials=(mat,)).data.uv_layers.new(name="UVMap")


def rss_mb():
    """Resident memory in MB after glibc returns its free heap pages (malloc_trim): what the
    process still holds, not what the allocator keeps cached. Without the trim, glibc's dynamic
    mmap threshold can keep a freed large block's pages once, a one-time step of ~17 MB that
    failed the memory test once in CI while nothing had leaked."""
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def test_demo_scene_renders_a_plausible_image(scene, tmp_path):
    build_demo_scene(scene, resolution=64, samples=16)
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "demo.exr")))
    assert img.shape == (64, 64, 4)
    assert np.isfinite(img).all()
    assert np.allclose(img[..., 3], 1.0)
    rgb = img[..., :3]
    assert 0.05 < rgb.mean() < 5.0
    # the camera sees the box's red wall on the left and green wall on the right
    left, right = rgb[16:48, 2:10].mean(axis=(0, 1)), rgb[16:48, -10:-2].mean(axis=(0, 1))
    assert left[0] > 2 * left[1] and right[1] > 1.5 * right[0]
    # light falls off from the ceiling area light: upper half of the back wall is not black
    assert rgb[40:56, 28:36].mean() > 0.05


def test_passes_present_when_enabled(scene, tmp_path):
    lit_plane_scene(scene)
    exr = scenes.read_exr(scenes.render_exr(tmp_path / "plain.exr", multilayer=True))
    assert not any(".Depth." in c or ".Normal." in c or ".Diffuse Color." in c or ".Mist." in c for c in exr)
    layer = bpy.context.view_layer
    layer.use_pass_z = layer.use_pass_normal = layer.use_pass_diffuse_color = layer.use_pass_mist = True
    scenes.world((0, 0, 0), 0.0)
    mist = scene.world.mist_settings
    mist.start, mist.depth, mist.falloff = 4.0, 2.0, 'LINEAR'
    exr = scenes.read_exr(scenes.render_exr(tmp_path / "passes.exr", multilayer=True))
    name = layer.name
    depth = exr[f"{name}.Depth.Z"]
    normal = np.stack([exr[f"{name}.Normal.{c}"] for c in "XYZ"], axis=-1)
    albedo = np.stack([exr[f"{name}.{engine_module.RESULT_PASS_NAME['DiffCol']}.{c}"] for c in "RGB"],
                      axis=-1)
    assert depth.shape == (12, 16)
    assert np.allclose(depth, 5.0, rtol=1e-4)                # z-depth of the plane
    assert np.allclose(normal, (0, 0, 1), atol=1e-5)
    assert np.allclose(albedo, (0.2, 0.4, 0.6), atol=1e-5)
    # Mist: (distance - 4) / 2 from the camera 5 m above the plane, 5 to 5.5 m away in this view
    mist = exr[f"{name}.Mist.Z"]
    assert mist.shape == (12, 16) and np.all((mist > 0.5 - 1e-4) & (mist < 0.75))
    assert mist[0, 0] > mist[5:7, 7:9].max() + 0.1 and mist[5:7, 7:9].max() < 0.52
    combined = scenes.rgba(exr, f"{name}.Combined.")
    assert combined[..., :3].mean() > 0


def test_position_uv_and_index_passes(scene, tmp_path, capfd):
    """Position, UV, Object Index and Material Index, with Blender's names in the result: the
    object's and the material's pass index, world positions on the plane, the UV map's
    coordinates with A = 1; none of them reported as missing."""
    lit_plane_scene(scene)
    ground = bpy.data.objects["Ground"]
    ground.location = (30.0, -20.0, 0.0)
    scene.camera.location = (30.0, -20.0, 5.0)
    ground.pass_index = 4
    ground.material_slots[0].material.pass_index = 6
    uv = ground.data.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", [0, 0, 1, 0, 1, 1, 0, 1])
    layer = bpy.context.view_layer
    layer.use_pass_position = layer.use_pass_uv = True
    layer.use_pass_object_index = layer.use_pass_material_index = True
    exr = scenes.read_exr(scenes.render_exr(tmp_path / "data.exr", multilayer=True))
    name = layer.name
    assert "not in the result" not in capfd.readouterr().err
    ob = exr[f"{name}.{engine_module.RESULT_PASS_NAME['IndexOB']}.X"]
    ma = exr[f"{name}.{engine_module.RESULT_PASS_NAME['IndexMA']}.X"]
    assert ob.shape == (12, 16) and np.all(ob == 4.0) and np.all(ma == 6.0)
    pos = np.stack([exr[f"{name}.Position.{c}"] for c in "XYZ"], axis=-1)
    assert np.allclose(pos[..., 2], 0.0, atol=1e-4)
    assert np.all(np.abs(pos[..., 0] - 30.0) < 3) and np.all(np.abs(pos[..., 1] + 20.0) < 3)
    # x grows to the right, y upwards (sample 0's points jitter over the filter's 1.5 pixels)
    col, row = np.meshgrid(np.arange(16), np.arange(12))
    assert np.corrcoef(col.ravel(), pos[..., 0].ravel())[0, 1] > 0.95
    assert np.corrcoef(row.ravel(), pos[..., 1].ravel())[0, 1] > 0.95
    uva = np.stack([exr[f"{name}.UV.{c}"] for c in "UVA"], axis=-1)
    # the 100 m plane's UV is (x - x0) / 100 + 0.5 on its local axes
    assert np.allclose(uva[..., 0], (pos[..., 0] - 30.0) / 100 + 0.5, atol=0.02)
    assert np.allclose(uva[..., 1], (pos[..., 1] + 20.0) / 100 + 0.5, atol=0.02)
    assert np.allclose(uva[..., 2], 1.0)


def test_border_render_with_and_without_crop(scene, tmp_path):
    lit_plane_scene(scene, size=(40, 20))
    r = scene.render
    r.use_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.75, 0.5, 1.0
    r.use_crop_to_border = True
    cropped = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "crop.exr")))
    assert cropped.shape[:2] == (10, 20)
    assert (cropped[..., :3] > 0).all()
    r.use_crop_to_border = False
    full = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "full.exr")))
    assert full.shape[:2] == (20, 40)
    inside = np.zeros((20, 40), bool)
    inside[10:20, 10:30] = True
    assert (full[inside][:, :3] > 0).all() and np.all(full[~inside] == 0)
    assert np.allclose(full[10:20, 10:30], cropped, rtol=1e-6)


@pytest.mark.parametrize("crop", [False, True])
def test_border_edges_round_in_float32_as_blender(scene, tmp_path, crop):
    """0.7 x 100 is 69.99... in float64 but 70 in float32, Blender's arithmetic for the result
    it allocates; 0.01 x 100 likewise 1, not 0. The border must cover exactly those pixels."""
    lit_plane_scene(scene, size=(100, 50))
    r = scene.render
    r.use_border, r.use_crop_to_border = True, crop
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.01, 0.7, 0.1, 0.7
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "edges.exr")))
    inside = np.zeros((50, 100), bool)
    inside[5:35, 1:70] = True      # rows from the bottom: Blender's y runs upwards
    if crop:
        assert img.shape[:2] == (30, 69) and (img[..., 3] > 0).all()
    else:
        assert img.shape[:2] == (50, 100)
        assert (img[inside][:, 3] > 0).all() and np.all(img[~inside] == 0)


def test_one_render_per_view_layer(scene, tmp_path, capfd):
    lit_plane_scene(scene)
    first = bpy.context.view_layer
    second = scene.view_layers.new("Second")
    third = scene.view_layers.new("Unused")
    third.use = False
    exr = scenes.read_exr(scenes.render_exr(tmp_path / "layers.exr", multilayer=True))
    for layer in (first, second):
        img = scenes.rgba(exr, f"{layer.name}.Combined.")
        assert img[..., :3].mean() > 0, layer.name
    assert not any(c.startswith("Unused.") for c in exr)
    summaries = [l for l in capfd.readouterr().out.splitlines() if "triangles," in l and "lights" in l]
    assert len(summaries) == 2, "rendered exactly once per enabled view layer"


def test_empty_scene_renders_and_reports(scene, tmp_path, capfd):
    scenes.camera()
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "empty.exr")))
    assert np.isfinite(img).all() and np.all(img[..., :3] == 0)
    out = capfd.readouterr().out
    assert "no renderable geometry" in out and "no lights" in out


def test_scene_without_lights_renders_black_and_reports(scene, tmp_path, capfd):
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=100)
    scenes.black_world()
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "dark.exr")))
    assert np.isfinite(img).all() and np.all(img[..., :3] == 0) and np.allclose(img[..., 3], 1)
    assert "no lights, no emissive materials and a black world" in capfd.readouterr().out


def test_running_out_of_memory_says_what_fills_it(scene, capfd, monkeypatch):
    """Memory running out mid-export (a helper's 800 instances of a 20K-triangle ball, flattened
    into 16M triangles) is reported as that, with what DACRT holds per frame: numpy's own
    'Unable to allocate 563. MiB for an array with shape (9, 16384002)' had been the message."""
    from addon import export

    def full(*_args, **_kw):
        raise MemoryError("Unable to allocate 563. MiB for an array with shape (9, 16384002)")
    monkeypatch.setattr(export, 'export_scene', full)
    scenes.camera()
    with pytest.raises(RuntimeError, match=r"DACRT render failed: out of memory \(Unable to allocate .*each "
                                           r"instance's copied out"):
        bpy.ops.render.render()


def test_nan_vertices_are_skipped_and_the_rest_renders(scene, tmp_path, capfd):
    lit_plane_scene(scene)
    scenes.mesh("Broken", [(0, 0, 1), (1, 0, 1), (0, 1, float('nan'))], [(0, 1, 2)])
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "nan.exr")))
    assert np.isfinite(img).all()
    # sun 3 W/m^2 straight down on albedo 0.2/0.4/0.6: rho * E / pi
    assert np.allclose(img[..., :3].mean(axis=(0, 1)), np.array([0.2, 0.4, 0.6]) * 3 / math.pi, rtol=1e-3)
    out = capfd.readouterr().out
    assert "Broken" in out and "NaN" in out


def test_triangles_beyond_float32s_reach_are_skipped_and_the_rest_renders(scene, tmp_path, capfd):
    """A triangle of finite coordinates near float32's largest (2e38) has edges and hit points
    float32 cannot hold: skipped and named (it failed the render with an infinite ray origin)."""
    lit_plane_scene(scene)
    scenes.mesh("Huge", [(-2e38, -2e38, 1), (2e38, -2e38, 1), (0, 2e38, 1)], [(0, 1, 2)])
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "huge.exr")))
    assert np.isfinite(img).all()
    assert np.allclose(img[..., :3].mean(axis=(0, 1)), np.array([0.2, 0.4, 0.6]) * 3 / math.pi, rtol=1e-3)
    out = capfd.readouterr().out
    assert "'Huge'" in out and "out-of-range" in out


def test_meshes_without_faces_do_not_stop_the_render(scene, tmp_path):
    """A placeholder from meshes.new() has not even a position attribute, nor has an empty
    metaball's mesh; they add nothing and the rest of the scene renders."""
    lit_plane_scene(scene)
    for ob in (bpy.data.objects.new("Placeholder", bpy.data.meshes.new("Placeholder")),
               bpy.data.objects.new("Meta", bpy.data.metaballs.new("Meta"))):
        scene.collection.objects.link(ob)
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "faceless.exr")))
    assert np.allclose(img[..., :3].mean(axis=(0, 1)), np.array([0.2, 0.4, 0.6]) * 3 / math.pi, rtol=1e-3)



def test_inverted_clip_range_shows_only_the_world(scene, tmp_path, capfd):
    """Clip end before clip start leaves Cycles' camera rays empty: the world alone shows (it
    used to fail the render). Said in a warning naming the camera."""
    lit_plane_scene(scene)
    scenes.world((0.2, 0.3, 0.4))
    scene.camera.data.clip_start, scene.camera.data.clip_end = 10.0, 1.0
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "clip.exr")))
    assert np.allclose(img[..., :3], (0.2, 0.3, 0.4), rtol=1e-6) and np.allclose(img[..., 3], 1)
    out = capfd.readouterr().out
    assert "'Camera'" in out and "clip end" in out


@pytest.mark.parametrize('scale', [(1, -1, 1), (-1, -1, -1)])
def test_mirrored_objects_are_lit_like_unmirrored(scene, tmp_path, scale):
    """A plane with a negative scale under a sun: rho E / pi as unmirrored (it rendered black:
    its shading normals faced away from its reversed winding)."""
    lit_plane_scene(scene)
    bpy.data.objects["Ground"].scale = scale
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "mirrored.exr")))
    assert np.allclose(img[..., :3].mean(axis=(0, 1)), np.array([0.2, 0.4, 0.6]) * 3 / math.pi, rtol=1e-3)

def test_approximated_materials_reported_once(scene, capfd):
    lit_plane_scene(scene)
    glass = bpy.data.materials.new("Glassy")
    nt = glass.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    nt.links.new(nt.nodes.new('ShaderNodeBsdfGlass').outputs[0], out.inputs['Surface'])
    scenes.plane("A", location=(0, 0, 1), materials=(glass,))
    scenes.plane("B", location=(3, 0, 1), materials=(glass,))
    bpy.ops.render.render()
    lines = [l for l in capfd.readouterr().out.splitlines() if "material(s) approximated" in l]
    assert len(lines) == 1 and "'Glassy'" in lines[0] and lines[0].startswith("Warning")


def test_failed_render_reports_the_reason(scene):
    lit_plane_scene(scene)
    scene.camera.data.type = 'CUSTOM'       # (a custom OSL camera: not rendered)
    with pytest.raises(RuntimeError, match="is custom; DACRT renders"):
        bpy.ops.render.render()


def test_a_stereo_frames_stats_count_both_views(scene):
    """A stereo render's stats and summary are the frame's: rays and times of both views (they
    had described the last eye alone, the same rays as a mono render)."""
    lit_plane_scene(scene)
    bpy.ops.render.render()
    mono = addon.last_render_stats()[bpy.context.view_layer.name]
    scene.render.use_multiview = True
    bpy.ops.render.render()
    stereo = addon.last_render_stats()[bpy.context.view_layer.name]
    assert mono['views'] == 1 and stereo['views'] == 2
    assert stereo['rays']['camera'] == 2 * mono['rays']['camera']
    assert stereo['rays_total'] == sum(stereo['rays'].values())
    assert stereo['mrays_per_s'] == pytest.approx(stereo['rays_total'] / stereo['trace_seconds'] * 1e-6)


def test_render_stats_hold_the_latest_frame_only(scene):
    """addon.last_render_stats() is the latest frame's: a view layer of an earlier render is
    gone, and a frame that failed leaves no stats (a script can tell it failed)."""
    lit_plane_scene(scene)
    scene.view_layers.new("Second")
    bpy.ops.render.render()
    assert set(addon.last_render_stats()) == {v.name for v in scene.view_layers}
    scene.view_layers["Second"].use = False
    bpy.ops.render.render()
    assert set(addon.last_render_stats()) == {bpy.context.view_layer.name}
    scene.camera.data.type = 'CUSTOM'
    with pytest.raises(RuntimeError):
        bpy.ops.render.render()
    assert addon.last_render_stats() == {}


def test_rerendering_keeps_memory_flat(scene):
    build_demo_scene(scene, resolution=96, samples=2)
    # ~125k triangles: each render allocates tens of MB, so keeping any of it would show
    bpy.data.objects["Suzanne"].modifiers["Subdivision"].render_levels = 3
    usage = []
    for _ in range(10):
        bpy.ops.render.render()
        usage.append(rss_mb())
    growth = min(usage[-3:]) - min(usage[:3])       # robust to the allocator's transient peaks
    assert growth < 10.0, f"RSS grew {growth:.1f} MB over 10 renders: {np.round(usage, 1)}"


def _patched_break(monkeypatch, after_seconds):
    """Make the engine's cancel check report Esc `after_seconds` after its first poll.

    Blender's own test_break() cannot be made True headless (it reads the UI's break flag) and
    RNA functions cannot be overridden from Python, so the patch sits on the engine's single
    wrapper around it, `cancel_requested`, which every poll in export and render goes through."""
    state = {'first': None, 'tripped': None, 'calls': 0}

    def test_break(self):
        now = time.perf_counter()
        state['calls'] += 1
        state['first'] = state['first'] or now
        if now - state['first'] >= after_seconds:
            state['tripped'] = state['tripped'] or now
            return True
        return False
    monkeypatch.setattr(engine_module.DACRTRenderEngine, 'cancel_requested', test_break)
    return state


def test_cancel_stops_a_long_render_within_a_second(scene, tmp_path, monkeypatch, capfd):
    build_demo_scene(scene, resolution=96, samples=1_000_000)       # would take hours
    state = _patched_break(monkeypatch, after_seconds=2.0)
    bpy.ops.render.render()
    stopped = time.perf_counter()
    assert state['tripped'] is not None, "the engine polled for cancel during the render"
    # from the moment Esc is down (not from the poll that first saw it: a long gap between polls
    # is exactly the latency this measures)
    pressed = state['first'] + 2.0
    assert stopped - pressed < 1.0, f"stopped {stopped - pressed:.2f} s after Esc"
    monkeypatch.undo()
    path = tmp_path / "cancelled.exr"
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '32'
    bpy.data.images['Render Result'].save_render(filepath=str(path), scene=scene)
    img = scenes.rgba(scenes.read_exr(path))
    assert img[..., :3].mean() > 0.01, "the partial image is kept"
    out = capfd.readouterr().out
    assert "1000000 samples" not in out and "render cancelled;" in out     # said, not a finished render's summary


def test_cancel_during_export(scene, monkeypatch, capfd):
    build_demo_scene(scene, resolution=32, samples=64)
    state = _patched_break(monkeypatch, after_seconds=0.0)
    bpy.ops.render.render()
    assert state['calls'] >= 1
    assert "cancelled" in capfd.readouterr().out


def test_cancel_during_setup_stops_before_tracing(scene, monkeypatch, capfd):
    """Preparing tens of millions of triangles takes seconds: Esc pressed after the export is
    answered between the set-up's steps, before any tracer scene is built or pass traced."""
    from addon import integrator, surfacetables
    build_demo_scene(scene, resolution=32, samples=64)
    state = {'setup': False, 'polls': 0, 'scenes': 0}
    real_tri, real_scene = surfacetables.Triangles.__init__, integrator.Integrator._tracer_scene

    def tri_init(self, *a, **k):
        state['setup'] = True          # the export is done: Esc from now on
        real_tri(self, *a, **k)

    def cancel(self):
        state['polls'] += state['setup']
        return state['setup']

    def tracer_scene(self, *a, **k):
        state['scenes'] += 1
        return real_scene(self, *a, **k)
    monkeypatch.setattr(surfacetables.Triangles, '__init__', tri_init)
    monkeypatch.setattr(integrator.Integrator, '_tracer_scene', tracer_scene)
    monkeypatch.setattr(engine_module.DACRTRenderEngine, 'cancel_requested', cancel)
    bpy.ops.render.render()
    out = capfd.readouterr().out
    assert state['polls'] >= 1, "the set-up polled for cancel"
    assert state['scenes'] == 0, "no tracer scene is built after Esc"
    assert "cancelled while preparing the scene" in out
    assert "samples," not in out, "no render summary: nothing was traced"


def test_write_still_like_blender_b(scene, tmp_path):
    lit_plane_scene(scene, size=(24, 16))
    scene.render.filepath = str(tmp_path / "frame_")
    scene.render.image_settings.file_format = 'PNG'
    bpy.ops.render.render(write_still=True)
    written = sorted(tmp_path.glob("frame_*.png"))
    assert len(written) == 1
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(str(written[0]))
    assert (buf.spec().width, buf.spec().height) == (24, 16)
    assert buf.get_pixels().mean() > 0


def test_spherical_stereo_panorama_is_reported(scene, capfd):
    """Cycles offsets each ray's eye around a stereo panorama's centre (Spherical Stereo); DACRT
    renders each eye as a plain panorama from the eye's position and says so, per view."""
    lit_plane_scene(scene, size=(32, 16))
    cam = scene.camera
    cam.data.type, cam.data.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'
    cam.data.stereo.use_spherical_stereo = False
    bpy.ops.render.render()
    assert "Spherical Stereo" not in capfd.readouterr().out
    cam.data.stereo.use_spherical_stereo = True
    bpy.ops.render.render()
    out = capfd.readouterr().out
    assert "view 'left': Spherical Stereo is not rendered" in out and "view 'right'" in out
    # Cycles applies it to perspective cameras too (said now; it was not), and only in Stereo 3D
    # (in the Multi-View format Blender applies none: it had been said there)
    cam.data.type = 'PERSP'
    bpy.ops.render.render()
    assert "view 'left': Spherical Stereo is not rendered" in capfd.readouterr().out
    scene.render.views_format = 'MULTIVIEW'
    bpy.ops.render.render()
    assert "Spherical Stereo" not in capfd.readouterr().out


def _stereo_scene(scene):
    """The lit plane with a box, seen in Stereo 3D with parallel eyes 0.8 apart about the
    centre, its views written as EXR files of their own; returns the camera."""
    lit_plane_scene(scene, size=(32, 24))
    scenes.cube("Box", size=1.0, location=(0.0, 0.0, 0.5))
    cam = scene.camera
    cam.data.stereo.convergence_mode, cam.data.stereo.pivot = 'PARALLEL', 'CENTER'
    cam.data.stereo.interocular_distance = 0.8
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth, settings.views_format = 'OPEN_EXR', '32', 'INDIVIDUAL'
    return cam


def test_stereo_views_render_from_their_eye_cameras(scene, tmp_path, monkeypatch):
    """Stereo 3D with parallel eyes about the centre: each view is the mono render of the camera
    moved half the interocular distance along its own x axis (Blender's eye cameras, which the
    engine asks for per view), and both views are written, with one integrator each (none for
    the mono camera)."""
    from addon import integrator
    made = []
    real_init = integrator.Integrator.__init__

    def counting_init(self, *args, **kw):
        made.append(1)
        real_init(self, *args, **kw)
    monkeypatch.setattr(integrator.Integrator, '__init__', counting_init)
    cam = _stereo_scene(scene)
    scene.render.filepath = str(tmp_path / "eye")
    bpy.ops.render.render(write_still=True)
    assert len(made) == 2
    eyes = {side: scenes.rgba(scenes.read_exr(next(tmp_path.glob(f"eye*_{side}.exr")))) for side in "LR"}
    scene.render.use_multiview = False
    for side, dx in (("L", -0.4), ("R", 0.4)):
        cam.location = (dx, 0.0, 5.0)
        mono = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"mono_{side}.exr")))
        assert np.allclose(eyes[side], mono, atol=1e-5), side
    assert not np.allclose(eyes["L"], eyes["R"], atol=1e-2)


def test_a_single_view_and_a_non_camera_are_rendered_as_cycles_renders_them(scene, tmp_path):
    """Stereo with one view enabled renders that eye (it had rendered the mono camera, a helper's
    left eye identical to the centre view); a light looked through as the scene camera is the
    same for every view, as in Cycles (Blender's eye calls read its spot size as a shift: the
    frame had moved sideways by a whole width)."""
    _stereo_scene(scene)

    def views(name):
        scene.render.filepath = str(tmp_path / name)
        bpy.ops.render.render(write_still=True)
        return {p.stem[-1]: scenes.rgba(scenes.read_exr(p)) for p in tmp_path.glob(f"{name}*_?.exr")}

    scene.render.views['right'].use = False
    left_only = views("one")
    assert set(left_only) == {"L"}
    scene.render.views['right'].use = True
    both = views("two")
    assert np.allclose(left_only["L"], both["L"], atol=1e-5)
    scene.render.use_multiview = False
    centre = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "c.exr")))
    assert not np.allclose(left_only["L"], centre, atol=1e-2)
    spot = scenes.light('SPOT', 100.0, (0.0, 0.0, 5.0), name="Looking")
    spot.data.spot_size = 1.2
    scene.camera = spot
    mono = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "spot.exr")))
    scene.render.use_multiview = True
    for side, img in views("spot_stereo").items():
        assert np.allclose(img, mono, atol=1e-5), side


def test_holdout_shader_is_an_object_holdout_of_a_black_surface(scene, tmp_path):
    """A Holdout material: camera rays see through it (alpha 0, as Cycles), other rays meet an
    opaque black surface; so the image equals that of a black object marked holdout."""
    lit_plane_scene(scene, size=(32, 24))
    mat, nt, out = scenes._material("Hold")
    nt.links.new(nt.nodes.new('ShaderNodeHoldout').outputs[0], out.inputs['Surface'])
    box = scenes.cube("Box", size=1.5, location=(0.0, 0.0, 0.75), materials=(mat,))
    shader = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "shader.exr")))
    box.data.materials[0] = scenes.diffuse("Black", (0.0, 0.0, 0.0))
    box.is_holdout = True
    held = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "object.exr")))
    assert np.array_equal(shader, held)
    assert (shader[..., 3] == 0).sum() > 20 and (shader[..., 3] == 1).sum() > 20


def run_cli(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(conftest.ROOT))
    return subprocess.run([sys.executable, "-m", "addon.cli", "render", *args], cwd=str(cwd),
                          capture_output=True, text=True, timeout=600, env=env)


def test_cli_renders_the_demo_to_png_and_exr(tmp_path):
    out = run_cli(["--samples", "2", "--out", str(tmp_path / "shot.png")], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert (tmp_path / "shot.png").is_file()
    img = scenes.rgba(scenes.read_exr(tmp_path / "shot.exr"))
    assert img.shape == (256, 256, 4) and np.isfinite(img).all() and img[..., :3].mean() > 0.05


def test_cli_renders_a_blend_file_and_explains_failures(scene, tmp_path):
    lit_plane_scene(scene, size=(20, 10))
    blend = tmp_path / "plane.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = run_cli([str(blend), "--samples", "1"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    img = scenes.rgba(scenes.read_exr(tmp_path / "render" / "plane.exr"))
    assert img.shape == (10, 20, 4) and img[..., :3].mean() > 0
    assert (tmp_path / "render" / "plane.png").is_file()
    missing = run_cli([str(tmp_path / "nope.blend")], tmp_path)
    assert missing.returncode != 0 and "no such .blend file" in missing.stderr
    # no view layer to render: Blender renders nothing without a word, and saving the empty
    # result used to end the CLI in a traceback
    scene.view_layers[0].use = False
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    off = run_cli([str(blend), "--samples", "1", "--out", str(tmp_path / "off.png")], tmp_path)
    assert off.returncode != 0 and "no view layer enabled for rendering" in off.stderr
    assert "Traceback" not in off.stderr and not (tmp_path / "off.png").exists()
    # an output that cannot be written (its folder would be a file) is refused before the
    # render, not after it
    scene.view_layers[0].use = True
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    (tmp_path / "file").write_text("")
    denied = run_cli([str(blend), "--samples", "1", "--out", str(tmp_path / "file" / "x.png")], tmp_path)
    assert denied.returncode != 0 and "cannot write" in denied.stderr, denied.stderr
    assert "Traceback" not in denied.stderr and "Info: DACRT:" not in denied.stdout + denied.stderr   # not rendered


def test_cli_writes_every_layer_and_pass_to_a_multilayer_exr(scene, tmp_path):
    """Two view layers, one with a Depth pass: the EXR holds both layers' Combined and the
    pass (a plain EXR kept the first layer's Combined alone); with Render Single Layer too."""
    lit_plane_scene(scene, size=(20, 10))
    second = scene.view_layers.new("Second")
    second.use_pass_z = True
    blend = tmp_path / "layers.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = run_cli([str(blend), "--samples", "1"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    channels = scenes.read_exr(tmp_path / "render" / "layers.exr")
    first = scene.view_layers[0].name
    for name in (f"{first}.Combined.R", "Second.Combined.A", "Second.Depth.Z"):
        assert name in channels, sorted(channels)
    assert channels["Second.Combined.R"].shape == (10, 20) and channels["Second.Combined.R"].mean() > 0
    # Render Single Layer is a window's setting: headless, both layers still render, and
    # both are written (the CLI had written a plain EXR of the first alone)
    scene.render.use_single_layer, second.use_pass_z = True, False
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = run_cli([str(blend), "--samples", "1"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    channels = scenes.read_exr(tmp_path / "render" / "layers.exr")
    assert f"{first}.Combined.R" in channels and "Second.Combined.R" in channels, sorted(channels)


def test_cli_output_names_and_stereo(scene, tmp_path):
    """--out as a directory (existing or ending in a separator) writes <name> inside it, not a
    file beside it or a hidden '.png'; a stereo render writes one file per view and succeeds
    (it ended in 'could not be saved' after Blender had written them); an absurd sample count
    or a file that is not a .blend gives a message, not a traceback."""
    from addon.cli import output_paths
    d = tmp_path / "outdir"
    d.mkdir()
    assert output_paths(str(d), "a/shot.blend") == (str(d / "shot.png"), str(d / "shot.exr"))
    assert output_paths(str(tmp_path / "new") + os.sep, None)[0] == str(tmp_path / "new" / "demo.png")
    assert output_paths("", None) == (os.path.join(".", "demo.png"), os.path.join(".", "demo.exr"))
    assert output_paths(str(tmp_path / "x.jpg"), None) == (str(tmp_path / "x.png"), str(tmp_path / "x.exr"))
    lit_plane_scene(scene, size=(16, 8))
    scene.render.use_multiview = True
    blend = tmp_path / "stereo.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = run_cli([str(blend), "--samples", "1", "--out", str(d) + os.sep], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    for suffix in ("_L", "_R"):
        for ext in (".png", ".exr"):
            assert (d / f"stereo{suffix}{ext}").is_file(), (suffix, ext, out.stdout)
    many = run_cli([str(blend), "--samples", "99999999999"], tmp_path)
    assert many.returncode != 0 and "at most" in many.stderr and "Traceback" not in many.stderr
    fake = tmp_path / "fake.blend"
    fake.write_text("not a blend file")
    bad = run_cli([str(fake)], tmp_path)
    assert bad.returncode != 0 and "could not open" in bad.stderr and "Traceback" not in bad.stderr


def test_cli_reads_blender_paths_every_layers_samples_and_writes_lossless_exr(scene, tmp_path):
    """--out in Blender's syntax ('//' the .blend's folder, '#' the frame: they were taken
    literally, '//x' writing under the filesystem root), --samples for every layer (a layer's
    Samples override had set the count without a word) and a lossless EXR whatever codec the
    .blend's output uses (a DWAA one was inherited: up to 7.6% off per pixel)."""
    import OpenImageIO as oiio
    from addon.cli import blender_path, output_paths
    assert blender_path("//shots/f_###.png", 3, "/a/b.blend") == "/a/shots/f_003.png"
    assert blender_path("x_#_##", 12, None) == "x_#_12"
    # negative frames padded as Blender pads them (%.*d: '-003', was '-03'); '#' in a folder
    # name is not the frame (was: 'take_07/beauty')
    assert blender_path("f_###", -3, None) == "f_-003"
    assert blender_path("f_####", -12, None) == "f_-0012"
    assert blender_path("take_##/beauty_#", 7, None) == "take_##/beauty_7"
    assert output_paths("//r/", "/a/b.blend", 1) == ("/a/r/b.png", "/a/r/b.exr")
    lit_plane_scene(scene, size=(16, 8))
    scene.view_layers[0].samples = 1
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.exr_codec = 'DWAA'
    (tmp_path / "proj").mkdir()
    blend = tmp_path / "proj" / "paths.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = run_cli([str(blend), "--samples", "3", "--frame", "7", "--out", "//shots/f_###"], tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "replaces view layer" in out.stdout and re.search(r"\b3 samples\b", out.stdout), out.stdout
    exr = tmp_path / "proj" / "shots" / "f_007.exr"
    assert exr.is_file() and (tmp_path / "proj" / "shots" / "f_007.png").is_file(), out.stdout
    inp = oiio.ImageInput.open(str(exr))
    try:
        assert inp.spec().getattribute("compression") == "zip"
    finally:
        inp.close()


# The CLI with a Ctrl-C right after the render's first pass (the integrator's passes wrapped
# before the add-on registers: a signal timed from outside would race the start-up)
_CTRL_C_CLI = """
import os, signal, sys
from addon import integrator
passes = integrator.Integrator.passes
def interrupted_passes(self):
    for i, progress in enumerate(passes(self)):
        yield progress
        if i == 0:      # Ctrl-C once the first pass is done (a timer raced it on a loaded machine)
            os.kill(os.getpid(), signal.SIGINT)
integrator.Integrator.passes = interrupted_passes
from addon.cli import main
main(sys.argv[1:])
"""


def test_cli_ctrl_c_cancels_and_keeps_the_samples_done(tmp_path):
    """Ctrl-C in a headless render cancels it as Esc does: the samples done are written, the
    CLI says so and exits 130. Python's KeyboardInterrupt had ended the render inside the
    engine with a traceback and 'Python script error in DACRT.render', then exited 0."""
    env = dict(os.environ, PYTHONPATH=str(conftest.ROOT))
    out = subprocess.run([sys.executable, "-c", _CTRL_C_CLI, "render", "--samples", "100000", "--out",
                          str(tmp_path / "cut.png")], cwd=str(tmp_path), capture_output=True, text=True,
                         timeout=600, env=env)
    assert out.returncode == 130, out.stdout + out.stderr
    assert "Traceback" not in out.stderr and "script error" not in out.stdout + out.stderr
    done = re.search(r"interrupted after (\d+) samples; wrote the partial image", out.stdout)
    assert done and 0 < int(done.group(1)) < 100000, out.stdout
    img = scenes.rgba(scenes.read_exr(tmp_path / "cut.exr"))
    assert img.shape == (256, 256, 4) and np.isfinite(img).all() and img[..., :3].mean() > 0.05
    assert (tmp_path / "cut.png").is_file()


def test_adaptive_sampling_and_skip_stats_for_scripts(scene, capfd, monkeypatch):
    import addon.integrator
    monkeypatch.setattr(addon.integrator, '_ADAPTIVE_MIN_BATCH', 0)   # a tiny image: Cycles' cadence
    lit_plane_scene(scene, size=(24, 16))
    scenes.plane("Hidden", location=(0, 0, 1)).hide_render = True
    scene.dacrt.samples = 200
    scene.dacrt.use_adaptive_sampling = True
    scene.dacrt.adaptive_threshold = 0.01
    bpy.ops.render.render()
    stats = addon.last_render_stats()[bpy.context.view_layer.name]
    # a sunlit plane is noise-free: every pixel stops at the first check after 64 samples
    assert stats['samples_done'] == 200 and stats['adaptive_min_samples'] == 64
    assert stats['samples_skipped'] == 24 * 16 * (200 - 80) == stats['skipped']['samples']
    assert stats['skipped']['objects'] == 1
    assert stats['export_seconds'] > 0 and stats['trace_seconds'] > 0
    assert 0 < stats['filter_seconds'] + stats['partition_seconds'] + stats['leaf_seconds']
    out = capfd.readouterr().out
    assert "skipped 1 object," in out and "samples" in out


def test_progressive_redraws_take_at_most_a_fifth_of_the_time(monkeypatch):
    """A redraw of a big frame costs about a second (8K); redrawing after every pass made a
    render quadratic in its pixels (a tester's 8K frame: 38.9 s, 10.5 s without the redraws).
    With a clock where each pass takes 0.3 s and each redraw 1 s, redraws happen only once
    four times their cost has passed, and the final image is always drawn."""
    import types
    from addon import engine as engine_module
    clock = [0.0]
    monkeypatch.setattr(engine_module.time, 'perf_counter', lambda: clock[0])
    draws = []

    class Fake:
        def _write(self, film, result, scene_data, view, final):
            clock[0] += 1.0
            draws.append(final)

        update_result = update_progress = update_stats = update_memory_stats = lambda self, *a, **k: None
        _status = staticmethod(lambda p, elapsed: "")
        cancel_requested = lambda self: False

    def passes(n):
        for i in range(1, n + 1):
            clock[0] += 0.3
            yield types.SimpleNamespace(samples_done=i, samples_total=n, fraction=i / n)

    integ = types.SimpleNamespace(film=None)
    engine_module.DACRTRenderEngine._steps(Fake(), passes(100), integ, None, None, 0.0, engine_module._Memory(0, None),
                                           None)
    assert draws[-1] is True and draws.count(True) == 1
    assert 5 <= len(draws) <= 10, len(draws)        # every ~4 s of a 30 s render (was: every pass)


def test_memory_stats_count_every_image_and_its_stored_texels():
    """The memory the render reports counts the geometry, every image a material reads (colour,
    opacity, emission, normal map) and the copy kept as Cycles stores it (an 8-bit image's
    bytes beside its linear texels)."""
    import types
    from addon import engine as engine_module
    from addon.texture import EncodedTexels, ImageTexels
    g = types.SimpleNamespace(**{k: np.zeros(10, np.float32) for k in
                                 ('vertices', 'triangles', 'material', 'normals', 'visibility', 'object_index')},
                              uvs=None, tangents=np.zeros((10, 3, 4), np.float32))
    linear = np.zeros((4, 4, 4), np.float32)
    encoded = ImageTexels(linear, EncodedTexels(np.zeros((4, 4, 4), np.uint8), srgb=True, scale=1 / 255))
    mats = [types.SimpleNamespace(texture=encoded, opacity=None, emission_texture=linear.copy(),
                                  normal_texture=None)]
    got = engine_module._scene_bytes(types.SimpleNamespace(geometry=g, materials=mats))
    assert got == 6 * 40 + 480 + 256 + 64 + 256


def test_sequencer_strip_renders_through_its_camera(scene, tmp_path):
    """A scene strip with its own camera (RenderEngine.camera_override) renders through that
    camera, as in Cycles: the edit's frame equals a direct render through it."""
    scene.render.resolution_x, scene.render.resolution_y = 24, 16
    a = scenes.camera((0, -6, 3), (math.radians(65), 0, 0), name="A")
    b = scenes.camera((1, -4, 6), (math.radians(30), 0, 0.3), name="B")
    scenes.plane("Ground", size=20, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    scenes.cube("Cube", size=1.5, location=(0, 0, 0.75), materials=(scenes.diffuse("Red", (0.8, 0.1, 0.1)),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 4
    scene.camera = b
    direct = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "direct.exr", scene)))
    scene.camera = a
    through_a = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "a.exr", scene)))
    edit = bpy.data.scenes.new("Edit")
    edit.render.engine = 'DACRT'
    edit.render.resolution_x, edit.render.resolution_y = 24, 16
    edit.render.resolution_percentage = 100
    strip = edit.sequence_editor_create().strips.new_scene("shot", scene, 1, 1)
    strip.scene_camera = b
    edit.frame_start = edit.frame_end = 1
    edit.render.use_sequencer = True
    bpy.ops.render.render(scene="Edit")
    s = edit.render.image_settings
    s.file_format, s.color_depth, s.color_mode = 'OPEN_EXR', '32', 'RGBA'
    bpy.data.images['Render Result'].save_render(filepath=str(tmp_path / "edit.exr"), scene=edit)
    seq = scenes.rgba(scenes.read_exr(tmp_path / "edit.exr"))
    assert np.abs(direct - through_a).max() > 0.05          # the cameras see different images
    assert np.allclose(seq, direct, atol=1e-4), np.abs(seq - direct).max()


def test_a_vast_emitter_beyond_float_lengths_renders(scene, tmp_path):
    """An emissive triangle 2e19 across (a tester's): distances to points sampled on it
    overflow float32's dot product (|d| > 1.8e19), which left a shadow ray with a zero
    direction and failed the render ('rays[i].dir is the zero vector'). Lengths are now
    scaled, and the image is that of the scene without it (its emission is negligible)."""
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    scenes.camera((0, -8, 4), (math.radians(65), 0, 0))
    scenes.plane("Floor", 10, materials=(scenes.diffuse("Grey", (0.8, 0.8, 0.8)),))
    scenes.cube("Cube", 2, location=(0, 0, 1), materials=(scenes.diffuse("Red", (0.8, 0.2, 0.2)),))
    scenes.world((0.05, 0.05, 0.05), 1.0)
    scenes.light('AREA', 500, location=(2, -2, 5), size=2)
    scene.dacrt.samples = 16
    ref = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "ref.exr", scene)))
    size = 1e19
    scenes.mesh("Vast", [(-size, -size, 50), (size, -size, 50), (0, size, 50)], [(0, 2, 1)],
                materials=(scenes.emission("Faint", (1, 1, 1), 1e-30),))
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "vast.exr", scene)))   # (raised)
    assert np.isfinite(img).all()
    assert img[..., :3].mean() == pytest.approx(ref[..., :3].mean(), rel=0.1)


def test_long_reports_arrive_whole(scene, capfd):
    """Blender cuts a report at ~1,024 bytes; the list of approximated materials of a big scene
    (a tester's bmw27 lost 8 of 18) is sent in parts instead, every material named."""
    from addon.engine import REPORT_LIMIT, _report_chunks
    lit_plane_scene(scene)
    names = [f"GlossyPaintMaterialNumber{i:02d}" for i in range(40)]
    for i, name in enumerate(names):
        mat, nt, out = scenes._material(name)
        nt.links.new(nt.nodes.new('ShaderNodeBsdfGlossy').outputs[0], out.inputs['Surface'])
        scenes.plane(name, size=0.1, location=(i * 0.2, 10, 0), materials=(mat,))
    capfd.readouterr()
    bpy.ops.render.render()
    out = capfd.readouterr().out
    assert "truncated" not in out and "DACRT (continued):" in out
    assert all(f"'{n}'" in out for n in names)
    text = "; ".join(f"item {i} " + "x" * 50 for i in range(60))
    parts = _report_chunks(text)
    assert len(parts) > 1 and all(len(p.encode()) <= REPORT_LIMIT for p in parts)
    assert " ".join(parts) == text                     # cut after '; ', nothing lost


def test_materials_of_one_reason_are_named_together(scene, said):
    """Materials approximated for the same reason are named in one list before it: a scene of
    default Principled materials said the same words once per material (500: 56 report lines)."""
    lit_plane_scene(scene)
    names = []
    for i in range(30):
        mat = bpy.data.materials.new(f"Paint{i:02d}")
        if i % 3 == 0:
            mat.node_tree.nodes['Principled BSDF'].inputs['Metallic'].default_value = 1.0
        scenes.plane(mat.name, size=0.1, location=(i * 0.2, 10, 0), materials=(mat,))
        names.append(mat.name)
    scenes.render_rgba(scene)
    text = " ".join(t for t in said if "material(s) approximated" in t)
    assert text.startswith("30 material(s) approximated"), text
    assert all(text.count(f"'{n}'") == 1 for n in names)
    metal = ", ".join(f"'{n}'" for n in names[::3]) + " (Principled metal as diffuse"
    plastic = ", ".join(f"'{n}'" for i, n in enumerate(names) if i % 3) + " (Principled specular layer as diffuse"
    assert metal in text and plastic in text, text
    assert text.count("as diffuse: its albedo averaged") == 2, text


def test_memory_stats_count_what_the_render_holds(scene):
    """The memory Blender shows (status line, memory stats, the Memory stamp) is the C heap's
    growth over the frame: a 1-triangle-pair scene at 640x480 holds its film, path state and
    result buffers (tens of MB), where the figure had counted the exported scene's arrays
    alone (a few hundred bytes here; a helper's 160K-triangle scene: 12 MB against 56-96 MB of
    growth)."""
    lit_plane_scene(scene, size=(640, 480))
    scene.dacrt.samples = 1
    bpy.ops.render.render()
    stats = next(iter(addon.last_render_stats().values()))
    film = 640 * 480 * 4 * 4 / 2 ** 20          # one float32 RGBA image: 4.7 MB
    assert stats['memory_peak_mb'] > film, stats['memory_peak_mb']


def test_fixed_threads_cap_every_native_pass_of_the_frame(scene, monkeypatch):
    """Render > Performance > Threads: Fixed 1 holds the render thread's thread limit at 1 for the
    frame (export, set-up and every kernel, not the tracer alone), and lifts it after; Auto
    sets none (tests/native/test_threads.py shows the limit keeps kernels on one thread)."""
    import dacrt
    seen = scenes.thread_limits_seen(monkeypatch)
    lit_plane_scene(scene)
    scene.render.threads_mode, scene.render.threads = 'FIXED', 1
    bpy.ops.render.render()
    scene.render.threads_mode = 'AUTO'
    bpy.ops.render.render()
    assert seen == [1, 0] and dacrt._core.thread_limit() == 0


def test_a_frames_export_is_freed_without_a_cyclic_collection(scene, monkeypatch):
    """After a render nothing of its export stays alive waiting for Python's cyclic garbage
    collector, which big numpy arrays never prompt: the exporter's tables referred back to it,
    and every re-render of a scene with a 4K texture kept that frame's texels (+576 MB each,
    a helper measured; Cycles stays flat)."""
    import gc
    import weakref
    from addon.export import scene as export_scene
    made = []
    init = export_scene.Exporter.__init__

    def recording(self, *args, **kwargs):
        made.append(weakref.ref(self))
        init(self, *args, **kwargs)
    monkeypatch.setattr(export_scene.Exporter, '__init__', recording)
    textured_plane_scene(scene)
    gc.collect()
    gc.disable()
    try:
        bpy.ops.render.render()
        bpy.ops.render.render()
        assert made and all(ref() is None for ref in made), "an export outlived its render"
    finally:
        gc.enable()


def test_memory_peak_counts_the_exports_temporaries(scene, monkeypatch):
    """The reported peak counts what the export held for a moment (an 8K image's conversion:
    4.4 GB where samples between the passes saw 1.6): 200 MB touched and freed in the export
    are in it."""
    from addon import export
    real = export.export_scene

    def heavy(*args, **kwargs):
        import mmap
        # pages of its own (not the heap's free blocks an earlier test left resident), touched
        block = mmap.mmap(-1, 200 * 2 ** 20)
        np.frombuffer(block, np.uint8)[::4096] = 1
        block.close()
        return real(*args, **kwargs)
    monkeypatch.setattr(export, 'export_scene', heavy)
    lit_plane_scene(scene)
    bpy.ops.render.render()
    peak = next(iter(addon.last_render_stats().values()))['memory_peak_mb']
    assert peak > 150, peak


def test_cancel_is_answered_inside_an_images_conversion(scene, monkeypatch, capfd):
    """An 8K image's conversion takes seconds (~11 s here): Esc pressed while it runs is
    answered between its steps, not after it (the export polled between objects only, and a
    helper's cancel came back 14-18 s after it was asked)."""
    from addon.export import images
    state = {'converting': False, 'finished': 0}
    real = images._linear_rgba

    def converting(*args, **kwargs):
        state['converting'] = True
        out = real(*args, **kwargs)
        state['finished'] += 1
        return out
    monkeypatch.setattr(images, '_linear_rgba', converting)
    monkeypatch.setattr(engine_module.DACRTRenderEngine, 'cancel_requested', lambda self: state['converting'])
    textured_plane_scene(scene)
    bpy.ops.render.render()
    assert state['converting'] and state['finished'] == 0
    assert "render cancelled during scene export" in capfd.readouterr().out


def test_the_image_has_the_size_of_the_render_being_made(scene):
    """Blender renders a scene a compositor's Render Layers node reads at the size of the render
    being made (RenderEngine.render), not at its own resolution, percentage and border, and a
    render_pre handler's edit of the percentage comes too late for the frame: both fill the
    whole frame, as in Cycles (the other scene at 50% had rendered a quarter-sized image in
    one corner; its border, half a frame; a crop border of the render alone failed the render
    with a size error)."""
    import addon
    lit_plane_scene(scene, size=(16, 12))
    other = scene.copy()
    other.name = "Other"
    other.render.resolution_percentage = 50
    other.render.use_border, other.render.border_min_x = True, 0.5
    ng = bpy.data.node_groups.new("Comp", 'CompositorNodeTree')
    scene.compositing_node_group = ng
    scene.render.use_compositing = True
    ng.interface.new_socket('Image', in_out='OUTPUT', socket_type='NodeSocketColor')
    node = ng.nodes.new('CompositorNodeRLayers')
    node.scene = other
    ng.links.new(node.outputs['Image'], ng.nodes.new('NodeGroupOutput').inputs[0])
    px = scenes.render_rgba(scene)
    assert px.shape == (12, 16, 4) and (px[..., 3] == 1.0).all(), px[..., 3]
    layer = f"Other / {scene.view_layers[0].name}"
    stats = addon.last_render_stats()[layer]
    assert stats['paths'] == stats['samples_done'] * 16 * 12, stats       # (the other scene's pixels)
    scene.render.use_border = scene.render.use_crop_to_border = True
    scene.render.border_min_x = scene.render.border_min_y = 0.25
    px = scenes.render_rgba(scene)
    assert px.shape == (9, 12, 4) and (px[..., 3] == 1.0).all()

    def halve(sc, *_):
        sc.render.resolution_percentage = 50
    scene.render.use_compositing = scene.render.use_border = False
    bpy.app.handlers.render_pre.append(halve)
    try:
        px = scenes.render_rgba(scene)
    finally:
        bpy.app.handlers.render_pre.remove(halve)
    assert px.shape == (12, 16, 4) and (px[..., 3] == 1.0).all()


def test_stats_of_a_scene_the_compositor_pulls_in_keep_their_own_key(scene):
    """A render whose compositor reads another scene's layer keeps both layers' stats: the
    other's under 'Scene / Layer' (both named 'ViewLayer', the other's had replaced the
    rendered scene's: 4 samples where 8 were rendered)."""
    def setup(s, samples):
        s.render.resolution_x, s.render.resolution_y = 16, 12
        s.render.engine = 'DACRT'
        s.dacrt.samples = samples
        scenes.camera(scene=s, name="Cam" + s.name)

    setup(scene, 8)
    other = bpy.data.scenes.new("Other")
    setup(other, 4)
    ng = bpy.data.node_groups.new("Comp", 'CompositorNodeTree')
    scene.compositing_node_group = ng
    scene.render.use_compositing = True
    ng.interface.new_socket('Image', in_out='OUTPUT', socket_type='NodeSocketColor')
    mine, theirs = ng.nodes.new('CompositorNodeRLayers'), ng.nodes.new('CompositorNodeRLayers')
    mine.scene, theirs.scene = scene, other
    mix = ng.nodes.new('ShaderNodeMix')
    mix.data_type, mix.blend_type = 'RGBA', 'ADD'
    ng.links.new(mine.outputs['Image'], mix.inputs[6])
    ng.links.new(theirs.outputs['Image'], mix.inputs[7])
    ng.links.new(mix.outputs[2], ng.nodes.new('NodeGroupOutput').inputs[0])
    layer = scene.view_layers[0].name
    assert other.view_layers[0].name == layer
    bpy.ops.render.render(scene=scene.name)
    stats = addon.last_render_stats()
    assert stats[layer]['samples_done'] == 8 and stats[f"Other / {layer}"]['samples_done'] == 4, stats
