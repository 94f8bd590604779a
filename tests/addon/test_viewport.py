"""The 3D viewport's Rendered shading without a GPU: its camera (export.viewport_camera, from
the view and projection matrices Blender gives a region), its export (the viewport's samples,
Combined alone) and its progressive session (addon/viewport.py) against the final render. The
drawing itself (addon/display.py) needs Blender's GPU, which background mode does not have."""
import threading

import numpy as np
import pytest

import bpy
import mathutils

from addon import export
from addon.camera import CameraModel
from addon.viewport import ViewportSession

from . import scenes


def _corner_points(cam_model, w, h):
    """Where the rays through the region's four corners start and end."""
    rx = np.array([0.0, w, 0.0, w]); ry = np.array([0.0, 0.0, h, h])
    o, d, t = cam_model.rays(rx, ry)
    return (o.T.astype(np.float64), (o + d * t).T.astype(np.float64))


def _unproject(view, window, ndc_z):
    """The corners of the region at NDC depth ndc_z, back through Blender's matrices."""
    inv = np.linalg.inv(np.array(window, np.float64) @ np.array(view, np.float64))
    pts = np.array([[x, y, ndc_z, 1.0] for y in (-1, 1) for x in (-1, 1)])
    p = pts @ inv.T
    return p[:, :3] / p[:, 3:]


@pytest.mark.parametrize("kind", ['PERSP', 'ORTHO'])
def test_free_view_rays_span_the_region_between_its_clip_planes(kind):
    # a viewport's own projection (not a camera's): an orthographic view's near plane lies behind
    # its eye, which the ray camera (clip start >= 0) must still reproduce
    w, h = 40, 30
    rot = mathutils.Euler((0.9, 0.1, 0.6)).to_matrix().to_4x4()
    rot.translation = (3.0, -2.0, 1.5)
    view = np.array(rot.inverted())
    if kind == 'PERSP':
        n, f, r, t = 0.05, 400.0, 0.036, 0.027
        window = np.array([[n / r, 0, 0.1, 0], [0, n / t, -0.05, 0],
                           [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0]])
    else:
        n, f, r, t = -50.0, 50.0, 4.0, 3.0
        window = np.array([[1 / r, 0, 0, 0.2], [0, 1 / t, 0, -0.1],
                           [0, 0, -2 / (f - n), -(f + n) / (f - n)], [0, 0, 0, 1]])
    cam = export.viewport_camera(view, window, w, h)
    assert cam.kind == kind and cam.clip_start >= 0.0
    starts, ends = _corner_points(CameraModel(cam), w, h)
    np.testing.assert_allclose(starts, _unproject(view, window, -1.0), atol=1e-4 * max(1.0, abs(n)))
    np.testing.assert_allclose(ends, _unproject(view, window, 1.0), rtol=1e-4, atol=1e-3)


@pytest.mark.parametrize("kind,fit", [('PERSP', 'AUTO'), ('PERSP', 'VERTICAL'), ('ORTHO', 'AUTO')])
def test_camera_view_rays_are_the_render_cameras(scene, kind, fit):
    # the viewport looking through the scene camera (at zoom 1, no offset) draws what it renders
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    cam_ob = scenes.camera(location=(1.0, -6.0, 2.0), rotation=(1.3, 0.0, 0.2), kind=kind)
    cam_ob.data.shift_x, cam_ob.data.shift_y, cam_ob.data.sensor_fit = 0.1, -0.05, fit
    dg = bpy.context.evaluated_depsgraph_get()
    ref = export.export_camera(dg.scene_eval, [], camera=cam_ob.evaluated_get(dg))
    view = export.viewport_camera(cam_ob.matrix_world.inverted(), cam_ob.calc_matrix_camera(dg, x=48, y=36), 48, 36)
    a, b = CameraModel(ref), CameraModel(view)
    rx, ry = np.meshgrid(np.arange(48) + 0.5, np.arange(36) + 0.5)
    oa, da, ta = a.rays(rx.ravel(), ry.ravel())
    ob, db, tb = b.rays(rx.ravel(), ry.ravel())
    np.testing.assert_allclose(db, da, atol=1e-6)
    np.testing.assert_allclose(ob, oa, atol=1e-4)
    # the far plane comes from a float32 matrix's P22 + 1 (about -0.002 here): a rounding of
    # about 0.5% far away, as the viewport's own depth
    np.testing.assert_allclose(tb, ta, rtol=1e-2)


def test_viewport_camera_rejects_what_cannot_be_a_view():
    with pytest.raises(export.ExportError, match="less than one pixel"):
        export.viewport_camera(np.eye(4), np.eye(4), 0, 10)
    with pytest.raises(export.ExportError, match="not finite"):
        export.viewport_camera(np.full((4, 4), np.nan), np.eye(4), 10, 10)


def _lit_box(scene):
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    red = scenes.diffuse("red", (0.8, 0.2, 0.2))
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("grey", (0.6, 0.6, 0.6))])
    scenes.cube("Box", size=1.0, location=(0.0, 0.0, 0.5), materials=[red])
    scenes.light('AREA', 200.0, location=(0.0, 0.0, 3.0), size=2.0)
    scenes.world((0.05, 0.05, 0.08))
    cam = scenes.camera(location=(0.0, -5.0, 2.5), rotation=(1.15, 0.0, 0.0))
    scene.dacrt.samples, scene.dacrt.preview_samples = 64, 8
    return cam


def _view_of(cam_ob, w=32, h=24):
    dg = bpy.context.evaluated_depsgraph_get()
    return export.viewport_camera(cam_ob.matrix_world.inverted(), cam_ob.calc_matrix_camera(dg, x=w, y=h), w, h)


def _finished(session, timeout=120.0):
    session._thread.join(timeout)
    assert not session.running, "the viewport session did not finish"
    assert session.error is None, session.error
    return session.image()[1]


def test_viewport_export_takes_the_viewport_samples_and_no_passes(scene):
    cam = _lit_box(scene)
    bpy.context.view_layer.use_pass_normal = True
    bpy.context.view_layer.use_pass_mist = True
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam))
    assert data.settings.samples == 8
    assert data.settings.passes == ()
    assert data.camera.width == 32 and data.camera.border == (0, 0, 32, 24)
    # no scene camera is needed to look through a viewport
    scene.camera = None
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam))
    assert len(data.geometry.triangles) == 14


def test_viewport_session_draws_what_the_render_renders(scene, tmp_path):
    # the viewport through the scene camera, at the render's samples, converges to the final
    # render's Combined (same seed and sample sequence: the same paths, up to the float
    # rounding between the two cameras' matrices)
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = scene.dacrt.samples = 16
    path = tmp_path / "final.exr"
    scenes.render_exr(path, scene)
    final = scenes.rgba(scenes.read_exr(path))
    updates = []
    session = ViewportSession(export.export_scene(bpy.context.evaluated_depsgraph_get(),
                                                  view_camera=_view_of(cam)), lambda: updates.append(1))
    session.start(_view_of(cam))
    image = _finished(session)
    assert updates and session.samples_done == 16
    assert image.shape == (24, 32, 4)
    assert final.mean() > 0.05
    diff = np.abs(image - final)
    assert diff.mean() < 1e-3 * final.mean(), (diff.mean(), final.mean())


def test_viewport_session_restarts_on_a_new_view(scene):
    # a new view mid-render stops the old samples: the image is then the new view's alone
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = 64
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam))
    first = _view_of(cam)
    cam.location.x += 1.5
    second = _view_of(cam)
    ready = threading.Event()
    session = ViewportSession(data, ready.set)
    session.start(first)
    ready.wait(60)
    session.start(second)
    moved = _finished(session)
    alone = ViewportSession(data)
    alone.start(second)
    np.testing.assert_array_equal(moved, _finished(alone))
    session.start(first)
    session.stop()                      # waits for the worker: nothing runs after it
    assert not session.running


def test_viewport_restarts_for_what_changes_the_image_only(scene):
    # every edit sends the viewport an update: a selection must not restart its samples, a move,
    # a material or a render setting must
    from addon.engine import _renders_differently, _settings_key
    _lit_box(scene)
    box = bpy.data.objects['Box']
    key = [_settings_key(scene)]
    seen = []

    def handler(sc, dg):
        seen.append(_renders_differently(dg, key[0]))
    bpy.app.handlers.depsgraph_update_post.append(handler)
    dg = bpy.context.evaluated_depsgraph_get()
    try:
        def edit(change):
            seen.clear()
            change()
            dg.update()
            return any(seen)
        assert not edit(lambda: box.select_set(True))
        assert not edit(lambda: box.select_set(False))
        assert edit(lambda: setattr(box.location, 'x', box.location.x + 0.5))
        assert edit(lambda: box.active_material.node_tree.nodes['Diffuse BSDF'].inputs['Color']
                    .default_value.__setitem__(0, 0.1))
        # (an edit in the UI tags the scene; a script's assignment to an add-on's property does not)
        assert edit(lambda: (setattr(scene.dacrt, 'max_bounces', 2), scene.update_tag()))
        key[0] = _settings_key(scene)
        assert not edit(lambda: box.select_set(True))
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)


def test_a_large_region_shows_a_coarse_sample_first(scene, monkeypatch):
    # one sample at <= PREVIEW_PIXELS first, drawn stretched; then the region's own samples,
    # the same as without the preview
    from addon import integrator, viewport
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = 2
    w, h = 400, 300
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam, w, h))
    shapes = []
    session = ViewportSession(data, lambda: shapes.append((session.image()[1].shape, session.samples_done)))
    monkeypatch.setattr(integrator, '_FIRST_PATHS', 1 << 14)     # the first sample in runs of pixels
    session.start(_view_of(cam, w, h))
    image = _finished(session)
    (first, _), (last, _) = shapes[0], shapes[-1]
    assert first[0] * first[1] <= viewport.PREVIEW_PIXELS and first[2] == 4
    assert abs(first[1] / first[0] - w / h) < 0.02
    assert last == (h, w, 4) and session.samples_done == 2
    # the preview stays up until the region's first sample is whole: no half-empty frame
    assert all(done >= 1 for shape, done in shapes if shape == last)
    monkeypatch.setattr(viewport, 'PREVIEW_PIXELS', w * h)
    plain = ViewportSession(data)
    plain.start(_view_of(cam, w, h))
    np.testing.assert_array_equal(image, _finished(plain))


class _Region:
    def __init__(self, w, h, view, window):
        self.width, self.height = w, h
        self.view_matrix, self.window_matrix = view, window


class _Context:
    """What view_update / view_draw read of Blender's context: the region and its 3D view."""
    def __init__(self, cam_ob, w, h):
        dg = bpy.context.evaluated_depsgraph_get()
        self.region = _Region(w, h, None, None)
        self.region_data = _Region(w, h, cam_ob.matrix_world.inverted(), cam_ob.calc_matrix_camera(dg, x=w, y=h))


class _Engine:
    """The engine's own state and the RenderEngine calls its viewport methods make, so they run
    without Blender's viewport (a RenderEngine is only made by Blender)."""
    def __init__(self):
        from addon.engine import DACRTRenderEngine
        self._viewport = self._view_key = self._settings_key = self._display = None
        self._viewport_said = set()
        self.status, self.reports, self.redraws = [], [], 0
        for name in ('view_update', 'view_draw', '_viewport_report', '_report_messages'):
            setattr(self, name, getattr(DACRTRenderEngine, name).__get__(self))

    def update_stats(self, stats, info):
        self.status.append(info)

    def report(self, kind, text):
        self.reports.append(text)

    def tag_redraw(self):
        self.redraws += 1


def test_engine_viewport_methods_export_restart_and_draw(scene, monkeypatch):
    from addon import display
    drawn = []
    monkeypatch.setattr(display.Display, 'draw', lambda self, engine, sc, image, version, w, h:
                        drawn.append((image.shape, w, h)))
    cam = _lit_box(scene)
    engine = _Engine()
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(_Context(cam, 32, 24), dg)
    first = engine._viewport
    assert first is not None
    image = _finished(first)
    assert first.samples_done == 8 and image.shape == (24, 32, 4)
    engine.view_draw(_Context(cam, 32, 24), dg)
    assert drawn[-1] == ((24, 32, 4), 32, 24) and engine.status[-1].startswith("DACRT | Sample 8/8")
    assert engine.redraws > 0
    # an update that changes nothing keeps the session; the same view draws again without
    # restarting; a new view restarts the same session
    engine.view_update(_Context(cam, 32, 24), dg)
    engine.view_draw(_Context(cam, 32, 24), dg)
    assert engine._viewport is first and first.samples_done == 8
    cam.location.z += 0.5
    engine.view_draw(_Context(cam, 32, 24), dg)
    assert engine._viewport is first
    moved = _finished(first)
    assert first.samples_done == 8 and not np.array_equal(moved, image)
    # a scene without a camera still renders the view; an empty region is an error in the status
    scene.camera = None
    engine._viewport.stop()
    engine._viewport = None
    engine.view_update(_Context(cam, 32, 24), bpy.context.evaluated_depsgraph_get())
    assert _finished(engine._viewport).shape == (24, 32, 4)
    engine._viewport.stop()
    engine._viewport = None
    engine.view_update(_Context(cam, 0, 24), bpy.context.evaluated_depsgraph_get())
    assert engine._viewport is None and "less than one pixel" in engine.status[-1]
    assert any("less than one pixel" in r for r in engine.reports)


def test_fixed_threads_cap_the_viewports_own_passes(scene, monkeypatch):
    """Threads: Fixed 1 holds the thread limit at 1 on the viewport's worker thread (its shading
    kernels and set-up, as it does for a frame), while the thread that started it, which an F12
    render may run on meanwhile, keeps its own limit (the limit is per calling thread)."""
    import dacrt
    seen = scenes.thread_limits_seen(monkeypatch)
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = 4
    scene.render.threads_mode, scene.render.threads = 'FIXED', 1
    data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam))
    assert data.settings.threads == 1
    session = ViewportSession(data)
    with dacrt.thread_limit(2):         # (this thread's own, untouched by the worker's)
        session.start(_view_of(cam))
        _finished(session)
        assert dacrt._core.thread_limit() == 2
    assert seen and set(seen) == {1}, seen
    assert dacrt._core.thread_limit() == 0
