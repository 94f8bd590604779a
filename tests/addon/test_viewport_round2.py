"""The viewport (Rendered shading), second round: camera view with the scene's Render Region
panned or zoomed off the region, the integrator's messages, hair at a Viewport Display Amount
below 100%, Cycles' Viewport Denoise, and settings only the final render reads. Driven without
a GPU through the stand-ins of test_viewport.py and test_viewport_fixes.py."""
import numpy as np
import pytest

import bpy

from . import scenes
from .test_viewport import _Engine, _finished, _lit_box
from .test_viewport_fixes import _Context, _cam_context, _space, _zoomed

DRAWN = []


@pytest.fixture(autouse=True)
def _no_gpu(monkeypatch):
    """view_draw's drawing (Blender's GPU) recorded instead: (image, version, width, height)."""
    from addon import display
    DRAWN.clear()
    monkeypatch.setattr(display.Display, 'draw', lambda self, engine, sc, image, version, w, h:
                        DRAWN.append((image, version, w, h)))


# --- 3. camera view, the Render Region off the region ------------------------------------------

def _camera_view(cam, frame, u, v, w=32, h=24):
    """The camera view zoomed and offset to show the frame's fractions u across, v up."""
    return _Context(cam.matrix_world.inverted(), _zoomed(frame, u, v), w, h, _space(), 'CAMERA')


def test_camera_view_with_the_render_region_off_the_region_renders_nothing_without_an_error(scene):
    # the scene's Render Region at 0.1 .. 0.3 of the frame, the view zoomed onto its top-right
    # quarter: reported as an ERROR ("the viewport's render region is empty"), the status line
    # an error, the last view's image (30 lit pixels) drawn on over the new view, and a re-export
    # at that zoom gave no session at all. Cycles renders nothing there (its border clipped)
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 4
    r = scene.render
    r.use_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.1, 0.3, 0.1, 0.3
    dg = bpy.context.evaluated_depsgraph_get()
    frame = np.array(cam.calc_matrix_camera(dg, x=32, y=24))
    whole = _camera_view(cam, frame, (0.0, 1.0), (0.0, 1.0))
    off = _camera_view(cam, frame, (0.5, 1.0), (0.5, 1.0))
    engine = _Engine()
    engine.view_update(whole, dg)
    _finished(engine._viewport)
    engine.view_draw(whole, dg)
    assert (DRAWN[-1][0][..., 3] > 0).sum() == 30
    for _ in range(2):
        engine.view_draw(off, dg)
    image, _, w, h = DRAWN[-1]
    assert image.shape == (24, 32, 4) and (w, h) == (32, 24) and not image.any()
    assert not engine.reports and "Error" not in engine.status[-1]
    # a re-export at that zoom: a session with nothing to render
    fresh = _Engine()
    fresh.view_update(off, dg)
    assert fresh._viewport is not None and not fresh.reports
    fresh.view_draw(off, dg)
    assert not DRAWN[-1][0].any() and "Error" not in fresh.status[-1]
    # back over the Render Region: it renders again
    engine.view_draw(whole, dg)
    assert (_finished(engine._viewport)[..., 3] > 0).sum() == 30
    engine._viewport.stop()
    fresh._viewport.stop()


def test_a_view_that_cannot_be_rendered_draws_nothing_of_the_last_view(scene):
    # a restart that fails (here a region of no width) had kept drawing the last view's image,
    # stretched over the new one
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    dg = bpy.context.evaluated_depsgraph_get()
    engine = _Engine()
    engine.view_update(_cam_context(cam, space=_space(), perspective='PERSP'), dg)
    _finished(engine._viewport)
    engine.view_draw(_cam_context(cam, space=_space(), perspective='PERSP'), dg)
    drawn = len(DRAWN)
    engine.view_draw(_cam_context(cam, w=0, space=_space(), perspective='PERSP'), dg)
    assert len(DRAWN) == drawn and engine._viewport.image()[1] is None
    assert "Error" in engine.status[-1] and any("less than one pixel" in t for t in engine.reports)


# --- 4. the integrator's messages reach the user --------------------------------------------

def _drive(engine, context, dg, until, moves=None, timeout=60.0):
    """Blender's loop: one view_draw for each redraw the worker asks for (tag_redraw), no other;
    moves(): a new view before each draw (navigation). Until until() or the worker ends."""
    import threading
    import time
    asked = threading.Event()
    engine.tag_redraw = asked.set
    engine.view_update(context, dg)
    end = time.time() + timeout
    while time.time() < end and not until():
        if asked.wait(0.2):
            asked.clear()
            engine.view_draw(moves() if moves else context, dg)
        elif not engine._viewport.running:
            break


ZERO = "skipped 1 light(s) with zero strength: Off"


@pytest.mark.parametrize("samples,navigate", [(16, False), (64, True), (1 << 24, False)])
def test_the_integrators_messages_are_reported_at_the_draws_the_render_asks_for(scene, samples, navigate):
    # a lamp of strength 0, which the integrator's set-up skips and says so: the viewport had
    # reported it only by luck (16 samples: 2 of 3 runs said nothing, the last redraw finding
    # the worker alive), never with navigation (each new view emptied the messages) nor with
    # Cycles' unlimited samples (nothing after 26k samples: said only once the render ended)
    cam = _lit_box(scene)
    scenes.light('POINT', 0.0, location=(1, 1, 2), name='Off')
    scene.dacrt.preview_samples = samples
    dg = bpy.context.evaluated_depsgraph_get()
    engine = _Engine()
    said = lambda: any(ZERO in t for t in engine.reports)     # noqa: E731
    views = iter(range(1000))

    def moved():
        cam.location.x += 0.01 * (next(views) < 3)
        return _cam_context(cam, space=_space(), perspective='PERSP')
    try:
        _drive(engine, _cam_context(cam, space=_space(), perspective='PERSP'), dg,
               until=said if samples > 1000 else (lambda: False), moves=moved if navigate else None)
        assert said(), (engine.reports, engine._viewport.messages)
        assert sum(ZERO in t for t in engine.reports) == 1          # (once)
    finally:
        engine._viewport.stop()


# --- 5. hair at a Viewport Display Amount below 100% -----------------------------------------

def _hair_scene(scene, children, percentage):
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("grey", (0.6, 0.6, 0.6))])
    em = scenes.plane("Emitter", size=1.0, location=(1.5, 1.0, 0.02),
                      materials=[scenes.diffuse("hair", (0.9, 0.1, 0.1))])
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    scenes.world((0.05, 0.05, 0.08))
    cam = scenes.camera(location=(0.0, -6.0, 3.0), rotation=(1.1, 0.0, 0.0))
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    s = em.modifiers.new("hair", 'PARTICLE_SYSTEM').particle_system.settings
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 40, 0.4, 0.06
    s.display_step, s.render_step = 2, 3
    s.display_percentage = percentage
    if children:
        s.child_type = 'INTERPOLATED'
        s.child_percent, s.rendered_child_count = 4, 4
    return cam


@pytest.mark.parametrize("children", [False, True])
def test_hair_at_half_the_display_amount_takes_cycles_strands_and_warns_of_nothing(scene, monkeypatch, children):
    # the viewport's path cache holds the displayed strands alone, co_hair gives the others as
    # one repeated point: their tubes of no area were dropped by the tracer and reported
    # ("5888 degenerate (zero-area) triangles skipped", 20480 with children), and about 74% of
    # the children were taken where Cycles' viewport takes children x amount / 100
    from addon.export import scene as scene_export
    strands = []
    real = scene_export.tessellate

    def spy(src, *args, **kw):
        strands.append(len(src.offsets) - 1)
        return real(src, *args, **kw)
    monkeypatch.setattr(scene_export, 'tessellate', spy)
    cam = _hair_scene(scene, children, 50)
    engine = _Engine()
    engine.view_update(_cam_context(cam, 48, 36, space=_space(), perspective='PERSP'),
                       bpy.context.evaluated_depsgraph_get())
    _finished(engine._viewport)
    engine.view_draw(_cam_context(cam, 48, 36, space=_space(), perspective='PERSP'),
                     bpy.context.evaluated_depsgraph_get())
    engine._viewport.stop()
    assert not any("degenerate" in t for t in engine.reports), engine.reports
    ps = bpy.data.objects['Emitter'].evaluated_get(bpy.context.evaluated_depsgraph_get()).particle_systems[0]
    shown = len(ps.particles)
    if children:
        assert strands == [len(ps.child_particles) // 2] and strands[0] == 80
    else:                       # the displayed parents (half of them: the others are one point)
        assert 0 < strands[0] < shown and abs(strands[0] - shown / 2) <= 0.25 * shown


# --- 6. Cycles' Viewport Denoise, 7. settings the viewport does not read ---------------------

def test_cycles_viewport_denoise_is_said_in_the_viewport(scene):
    # a scene made for Cycles may keep Viewport > Denoise on: the viewport showed the noisy
    # image and said nothing (the final render says its Render > Denoise is not applied)
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = 2
    for on in (False, True):
        scene.cycles.use_preview_denoising = on
        scene.update_tag()              # (the evaluated scene's copy of the add-on's property)
        engine = _Engine()
        engine.view_update(_cam_context(cam, space=_space(), perspective='PERSP'),
                           bpy.context.evaluated_depsgraph_get())
        _finished(engine._viewport)
        engine._viewport.stop()
        said = [t for t in engine.reports if "Viewport > Denoise" in t]
        assert said == (["DACRT: Cycles' Sampling > Viewport > Denoise is not applied: DACRT does not denoise, "
                         "so the viewport shows the undenoised image"] if on else [])


def _scene_update(scene):
    """The update Blender sends for an edit of an add-on's scene property in the interface (the
    scene alone: rna_property_update tags the scene; a script's assignment tags nothing), made
    by re-setting a scene property that tags it so."""
    scene.render.use_stamp_date = scene.render.use_stamp_date


def test_a_setting_only_the_final_render_reads_keeps_the_viewports_samples(scene):
    # Render > Samples (scene.dacrt.samples) had re-exported the viewport, throwing away its
    # samples (425 of them, restarted from 0); the viewport's own samples still re-export
    cam = _lit_box(scene)
    scene.dacrt.preview_samples = 1 << 20
    ctx = _cam_context(cam, space=_space(), perspective='PERSP')
    engine = _Engine()
    exports = []

    def handler(sc, dg):
        before = engine._viewport
        engine.view_update(ctx, dg)
        exports.append(engine._viewport is not before)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        scene.dacrt.samples = 128
        _scene_update(scene)
        dg.update()
        assert exports == [False]
        scene.dacrt.preview_samples = 1 << 19
        _scene_update(scene)
        dg.update()
        assert exports == [False, True]
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        engine._viewport.stop()
