"""The viewport (Rendered shading) against the final render and Cycles' viewport: the view's
own clip range, updates that hide objects or change collection flags, hair at the display
steps, the scene camera rendered in camera view (panorama, depth of field, broken settings),
the Render Region, and what the viewport reports. Driven without a GPU through the stand-ins
of test_viewport.py."""
import math

import numpy as np
import pytest

import bpy
import mathutils

from addon import export

from . import scenes
from .test_viewport import _Engine, _finished, _lit_box


@pytest.fixture(autouse=True)
def _no_gpu(monkeypatch):
    """view_draw's drawing needs Blender's GPU, which background mode lacks."""
    from addon import display
    monkeypatch.setattr(display.Display, 'draw', lambda *args: None)


class _Obj:
    def __init__(self, **kw):
        self.__dict__.update(kw)


def _f32(m):
    """A matrix as Blender hands it over (float32)."""
    return mathutils.Matrix(np.array(m, np.float32).astype(np.float64).tolist())


class _Context:
    """The region, its 3D view data and the 3D view space, as view_update / view_draw read them."""
    def __init__(self, view, window, w, h, space=None, perspective=None):
        window = np.array(window, np.float64)
        self.region = _Obj(width=w, height=h)
        self.region_data = _Obj(view_matrix=_f32(view), window_matrix=_f32(window),
                                view_perspective=perspective or ('PERSP' if window[3, 3] == 0.0 else 'ORTHO'))
        self.space_data = space


def _space(clip_start=0.01, clip_end=1000.0, **kw):
    return _Obj(clip_start=clip_start, clip_end=clip_end, use_render_border=False, render_border_min_x=0.0,
                render_border_max_x=1.0, render_border_min_y=0.0, render_border_max_y=1.0,
                use_local_camera=False, camera=None, **kw)


def _persp_window(lens, w, h, n, f, sensor=36.0, zoom=2.0):
    """Blender's free perspective view's projection (BKE_camera_params_from_view3d, sensor fit
    AUTO over the region, CAMERA_PARAM_ZOOM_INIT_PERSP = 2)."""
    pix = sensor * n / lens * zoom / max(w, h)
    r, t = 0.5 * w * pix, 0.5 * h * pix
    return np.array([[n / r, 0, 0, 0], [0, n / t, 0, 0],
                     [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0]])


def _ortho_window(scale, w, h, clip_end):
    """Blender's free orthographic view: from -clip_end / 2 to clip_end / 2 around the eye."""
    f = 0.5 * clip_end
    r, t = 0.5 * scale, 0.5 * scale * h / w
    return np.array([[1 / r, 0, 0, 0], [0, 1 / t, 0, 0], [0, 0, -1 / f, 0], [0, 0, 0, 1]])


def _wall_ahead(distance):
    """An emissive wall (strength 1, white) `distance` ahead of an eye at the origin looking
    along +Y, a black world; the view matrix of that eye."""
    wall = scenes.plane("Wall", size=4.0 * distance, location=(0, distance, 0),
                        materials=[scenes.emission("e", (1, 1, 1), 1.0)])
    wall.rotation_euler = (math.pi / 2, 0, 0)
    scenes.world((0, 0, 0))
    return np.array(mathutils.Matrix.Rotation(math.pi / 2, 4, 'X').inverted())


def _viewport(engine, context):
    engine.view_update(context, bpy.context.evaluated_depsgraph_get())
    assert engine._viewport is not None, engine.status[-1:]
    return _finished(engine._viewport)


# --- 1. the far clip is the view's clip end ----------------------------------------------------

def test_free_view_clips_at_the_views_clip_end_not_the_float32_matrixs(scene):
    # a wall 9000 units ahead: Cycles' viewport (and a camera with the same clip range) shows it
    # for a clip end of 10000 whatever the clip start; read back from the float32 projection the
    # far plane had been 9869 (clip start 0.01), 8389 (0.001: the wall gone), 998.65 for
    # Blender's default 0.01 .. 1000, and 0.001 .. 100000 failed as a singular matrix
    scene.dacrt.samples = scene.dacrt.preview_samples = 1
    view = _wall_ahead(9000.0)
    for start, end, visible in ((0.01, 10000.0, True), (0.001, 10000.0, True), (0.001, 100000.0, True),
                                (0.01, 1000.0, False), (0.01, 8999.0, False)):
        engine = _Engine()
        image = _viewport(engine, _Context(view, _persp_window(50.0, 16, 12, start, end), 16, 12,
                                           _space(start, end)))
        cam = engine._viewport.scene_data.camera
        assert (cam.clip_start, cam.clip_end) == (start, end)
        np.testing.assert_allclose(image[..., :3].mean(), 1.0 if visible else 0.0, atol=1e-4)
        engine._viewport.stop()
    # Blender's default range, a closed form: the far plane is 1000 (not 998.65)
    cam = export.viewport_camera(_f32(view), _f32(_persp_window(50.0, 16, 12, 0.01, 1000.0)), 16, 12,
                                 clip=(0.01, 1000.0))
    assert cam.clip_end == 1000.0


def test_free_orthographic_view_spans_half_the_clip_end_either_side_of_its_eye(scene):
    # Blender's and Cycles' orthographic view: from -clip_end / 2 to clip_end / 2 along the view
    scene.dacrt.samples = scene.dacrt.preview_samples = 1
    view = _wall_ahead(9000.0)
    for end, visible in ((100000.0, True), (17000.0, False)):
        engine = _Engine()
        image = _viewport(engine, _Context(view, _ortho_window(30.0, 16, 12, end), 16, 12, _space(0.01, end)))
        cam = engine._viewport.scene_data.camera
        np.testing.assert_allclose(cam.matrix[:3, 3], (0.0, -0.5 * end, 0.0), atol=1e-6 * end)
        assert (cam.clip_start, cam.clip_end) == (0.0, end)
        np.testing.assert_allclose(image[..., :3].mean(), 1.0 if visible else 0.0, atol=1e-4)
        engine._viewport.stop()


# --- 2. hiding an object, a collection's Holdout / Indirect Only re-export ---------------------

def _cam_context(cam_ob, w=32, h=24, space=None, perspective='CAMERA'):
    dg = bpy.context.evaluated_depsgraph_get()
    return _Context(cam_ob.matrix_world.inverted(), cam_ob.calc_matrix_camera(dg, x=w, y=h), w, h,
                    space, perspective)


def test_hiding_an_object_or_a_collections_holdout_re_exports_the_viewport(scene):
    # these come as updates of the scene alone, which the viewport had taken for a selection:
    # the hidden box stayed (red excess 0.489, a fresh export 0.000), no holdout (alpha 1.00,
    # fresh 0.33), and undoing them did not restart either
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 4
    box = bpy.data.objects['Box']
    coll = bpy.data.collections.new("C")
    scene.collection.children.link(coll)
    coll.objects.link(box)
    scene.collection.objects.unlink(box)
    lc = bpy.context.view_layer.layer_collection.children['C']
    engine, ctx = _Engine(), _cam_context(cam, perspective='PERSP')

    def handler(sc, dg):            # as Blender calls view_update with the update's depsgraph
        engine.view_update(ctx, dg)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    shown = _finished(engine._viewport).copy()

    def fresh():
        other = _Engine()
        image = _viewport(other, ctx)
        other._viewport.stop()
        return image
    red = lambda im: float((im[..., 0] - im[..., 1])[8:20, 10:22].mean())   # noqa: E731
    assert red(shown) > 0.3
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        for do, undo in ((lambda: box.hide_set(True), lambda: box.hide_set(False)),
                         (lambda: setattr(lc, 'holdout', True), lambda: setattr(lc, 'holdout', False)),
                         (lambda: setattr(lc, 'indirect_only', True), lambda: setattr(lc, 'indirect_only', False))):
            session = engine._viewport
            do()
            dg.update()
            assert engine._viewport is not session
            np.testing.assert_array_equal(_finished(engine._viewport), fresh())
            session = engine._viewport
            undo()
            dg.update()
            assert engine._viewport is not session
            np.testing.assert_array_equal(_finished(engine._viewport), shown)
        box.hide_set(True)
        dg.update()
        hidden_box = _finished(engine._viewport)
        assert abs(red(hidden_box)) < 0.02
        box.hide_set(False)
        lc.holdout = True
        dg.update()
        assert float(_finished(engine._viewport)[8:20, 10:22, 3].mean()) < 0.5
        lc.holdout = False
        dg.update()
        # a selection still keeps the running samples
        session = engine._viewport
        box.select_set(True)
        dg.update()
        assert engine._viewport is session
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        engine._viewport.stop()


# --- 3. hair particles at the viewport's display steps ------------------------------------------

def test_viewport_hair_reads_the_display_steps_of_its_path_cache(scene):
    # the viewport depsgraph caches 2^display_step + 1 points a strand; 2^render_step + 1 had
    # been read, co_hair giving (0, 0, 0) past the cache: 6912 hair vertices at the world origin,
    # 194 red pixels where the final render has 97, mean |diff| 0.0146
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    scenes.plane("Floor", size=8.0, materials=[scenes.diffuse("grey", (0.6, 0.6, 0.6))])
    em = scenes.plane("Emitter", size=1.0, location=(1.5, 1.0, 0.02), materials=[scenes.diffuse("hair", (0.9, 0.1, 0.1))])
    scenes.light('SUN', 3.0, rotation=(0.3, 0.2, 0))
    scenes.world((0.05, 0.05, 0.08))
    cam = scenes.camera(location=(0.0, -6.0, 3.0), rotation=(1.1, 0.0, 0.0))
    scene.dacrt.samples = scene.dacrt.preview_samples = 4
    s = em.modifiers.new("hair", 'PARTICLE_SYSTEM').particle_system.settings
    s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 40, 0.4, 0.06
    s.display_step, s.render_step = 2, 3
    final = scenes.rgba(scenes.read_exr(_render_exr(scene)))
    engine = _Engine()
    image = _viewport(engine, _cam_context(cam, 48, 36, perspective='PERSP'))
    engine._viewport.stop()
    v = engine._viewport.scene_data.geometry.vertices
    assert np.linalg.norm(v, axis=1).min() > 0.5     # (the floor's corners are 5.7 out, the emitter's 1.1)
    hair = v[np.abs(v[:, 2]) > 0.03]        # (the floor and the emitter lie at z 0 and 0.02)
    assert len(hair) > 0
    # every hair vertex lies over the emitter, within the hair's length (and its tube's radius)
    assert hair[:, 0].min() > 1.0 - 0.45 and hair[:, 0].max() < 2.0 + 0.45
    assert hair[:, 1].min() > 0.5 - 0.45 and hair[:, 1].max() < 1.5 + 0.45
    assert hair[:, 2].max() < 0.02 + 0.45
    red = lambda im: int((im[..., 0] - im[..., 1] > 0.1).sum())   # noqa: E731
    assert red(final) > 20 and abs(red(image) - red(final)) <= 0.1 * red(final), (red(image), red(final))
    assert np.abs(image - final)[..., :3].mean() < 2e-3


def _render_exr(scene):
    import os
    import tempfile
    path = os.path.join(tempfile.mkdtemp(), 'final.exr')
    scenes.render_exr(path, scene)
    return path


# --- 4. camera view renders the scene camera: panorama, depth of field, zoom and offset ----------

def test_camera_view_renders_the_scene_cameras_panorama_and_depth_of_field(scene):
    # Blender draws a camera view through a perspective projection whatever the camera; the
    # viewport had rendered that (an equirectangular camera in perspective, a camera's depth
    # of field at aperture 0), saying nothing. At zoom 1 and no offset it now draws the final
    # render's image
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 8
    for setup in ('PANO', 'DOF'):
        cam.data.type, cam.data.dof.use_dof = 'PERSP', False
        if setup == 'PANO':
            cam.data.type, cam.data.panorama_type = 'PANO', 'EQUIRECTANGULAR'
        else:
            cam.data.dof.use_dof, cam.data.dof.aperture_fstop, cam.data.dof.focus_distance = True, 0.1, 1.0
        final = scenes.rgba(scenes.read_exr(_render_exr(scene)))
        engine = _Engine()
        image = _viewport(engine, _cam_context(cam))
        engine._viewport.stop()
        c = engine._viewport.scene_data.camera
        ref = export.export_camera(bpy.context.evaluated_depsgraph_get().scene_eval, [])
        assert c.kind == ref.kind and c.panorama_type == ref.panorama_type
        assert c.aperture == ref.aperture and (c.aperture > 0.2) == (setup == 'DOF')
        assert final[..., :3].mean() > 0.02
        diff = np.abs(image - final)[..., :3]
        assert diff.mean() < 1e-3 * final[..., :3].mean(), (setup, diff.mean(), final[..., :3].mean())


def _zoomed(frame, u, v):
    """A camera view's projection showing the frame's fractions u = (u0, u1) across the region
    and v = (v0, v1) up it (Blender's zoom and offset), from the frame's projection."""
    W = np.array(frame, np.float64)
    for axis, (a, b) in ((0, u), (1, v)):
        col = 2 if W[3, 3] == 0.0 else 3
        s = 1.0 if col == 2 else -1.0
        e0, e1 = (-1 + s * W[axis, col]) / W[axis, axis], (1 + s * W[axis, col]) / W[axis, axis]
        w0, w1 = e0 + a * (e1 - e0), e0 + b * (e1 - e0)
        W[axis, axis] = 2.0 / (w1 - w0)
        W[axis, col] = s * (w1 + w0) / (w1 - w0)
    return W


def test_camera_view_zoom_and_offset_place_the_final_renders_rays(scene):
    # a region of 64 x 24 showing the 32 x 24 frame in its middle (16 pixels of passepartout
    # either side): each region pixel over the frame has the final render's ray of that pixel,
    # for a perspective, an orthographic and a panoramic camera (whose frame Blender draws as a
    # perspective camera's)
    from addon.camera import CameraModel
    cam = _lit_box(scene)
    for kind in ('PERSP', 'ORTHO', 'PANO'):
        cam.data.type = kind
        cam.data.panorama_type = 'FISHEYE_EQUISOLID'
        cam.data.shift_x = 0.1
        dg = bpy.context.evaluated_depsgraph_get()
        frame = np.array(cam.calc_matrix_camera(dg, x=32, y=24))
        ctx = _Context(cam.matrix_world.inverted(), _zoomed(frame, (-0.5, 1.5), (0.0, 1.0)), 64, 24,
                       _space(), 'CAMERA')
        from addon.engine import _region_camera
        said = []
        view = _region_camera(ctx, dg, said)
        ref = export.export_camera(dg.scene_eval, [])
        assert (view.width, view.height, view.border) == (64, 24, (0, 0, 64, 24))
        rx, ry = np.meshgrid(np.arange(32) + 0.5, np.arange(24) + 0.5)
        oa, da, ta = CameraModel(ref).rays(rx.ravel(), ry.ravel())
        ob, db, tb = CameraModel(view).rays(rx.ravel() + 16, ry.ravel())
        np.testing.assert_allclose(db, da, atol=1e-5)
        np.testing.assert_allclose(ob, oa, atol=1e-4)
        np.testing.assert_allclose(tb, ta, rtol=1e-4, atol=1e-5)


# --- 5. the Render Region ------------------------------------------------------------------------

def test_viewport_renders_only_inside_the_render_region(scene):
    # the view's Render Region in a free view, the scene's in camera view (as Cycles' viewport):
    # the whole region had been rendered (768 of 768 pixels where the border holds 48)
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    scene.render.use_border = True
    scene.render.border_min_x, scene.render.border_max_x = 0.25, 0.5
    scene.render.border_min_y, scene.render.border_max_y = 0.25, 0.5
    full = _Engine()
    whole = _viewport(full, _cam_context(cam, space=_space(), perspective='PERSP'))
    full._viewport.stop()
    assert (whole[..., 3] > 0).all()
    # a free view: its own border (the scene's is the camera view's), 8 x 6 pixels of 32 x 24
    space = _space()
    space.use_render_border = True
    space.render_border_min_x, space.render_border_max_x = 0.25, 0.5
    space.render_border_min_y, space.render_border_max_y = 0.5, 0.75
    engine = _Engine()
    image = _viewport(engine, _cam_context(cam, space=space, perspective='PERSP'))
    engine._viewport.stop()
    assert engine._viewport.scene_data.camera.border == (8, 12, 16, 18)
    inside = np.zeros(image.shape[:2], bool)
    inside[12:18, 8:16] = True
    assert (image[~inside] == 0).all() and (image[inside][:, 3] > 0).all()
    np.testing.assert_array_equal(image[inside], whole[inside])    # (the same paths)
    # camera view: the scene's border, through the zoom and offset (the frame in the middle of
    # a 64-pixel region: frame pixels 8 .. 16 are region pixels 24 .. 32)
    dg = bpy.context.evaluated_depsgraph_get()
    frame = np.array(cam.calc_matrix_camera(dg, x=32, y=24))
    ctx = _Context(cam.matrix_world.inverted(), _zoomed(frame, (-0.5, 1.5), (0.0, 1.0)), 64, 24, _space(), 'CAMERA')
    engine = _Engine()
    image = _viewport(engine, ctx)
    engine._viewport.stop()
    assert engine._viewport.scene_data.camera.border == (24, 6, 32, 12)
    assert int((image[..., 3] > 0).sum()) == 48 and (image[6:12, 24:32, 3] > 0).all()
    # a border changed in the view restarts the samples through the new border
    space.render_border_max_x = 1.0
    engine = _Engine()
    ctx = _cam_context(cam, space=space, perspective='PERSP')
    engine.view_update(ctx, dg)
    first = engine._viewport.scene_data.camera.border
    space.render_border_min_x = 0.5
    engine.view_draw(ctx, dg)
    assert first == (8, 12, 32, 18) and engine._viewport.scene_data.camera.border == (16, 12, 32, 18)
    engine._viewport.stop()


def test_a_large_regions_coarse_first_sample_keeps_the_render_region():
    # the preview at a quarter of the pixels: the border scaled with it
    from addon.viewport import preview_camera
    cam = export.viewport_camera(np.eye(4), _persp_window(50.0, 512, 512, 0.1, 100.0), 512, 512)
    cam.border = (128, 256, 384, 512)
    small = preview_camera(cam)
    assert (small.width, small.height) == (256, 256) and small.border == (64, 128, 192, 256)


# --- 6. a NaN camera setting in camera view: the world, and the setting named -------------------

def test_camera_view_of_a_nan_camera_setting_renders_the_world_and_names_it(scene):
    # Blender's camera-view projection is then NaN: the viewport had failed with "the viewport's
    # view or projection matrix is not finite"; the final render names the setting and renders
    # the world (as Cycles), and so does the viewport now
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    for attr, said, good in (('lens', "Focal Length is nan", 50.0), ('shift_x', "Shift X is nan", 0.0),
                             ('clip_start', "clip range is nan .. 100", 0.1),
                             ('clip_end', "clip range is 0.1 .. nan", 100.0)):
        cam.data.clip_start, cam.data.clip_end = 0.1, 100.0
        setattr(cam.data, attr, float('nan'))
        engine = _Engine()
        ctx = _cam_context(cam)
        image = _viewport(engine, ctx)
        assert engine.reports == [f"DACRT: camera 'Camera': {said}, so only the world is rendered (as in Cycles)"]
        np.testing.assert_allclose(image[..., :3], np.broadcast_to((0.05, 0.05, 0.08), image[..., :3].shape),
                                   atol=1e-5)
        # (the NaN projection is the same view at every redraw: no restart, said once)
        session, done = engine._viewport, engine._viewport.samples_done
        dg = bpy.context.evaluated_depsgraph_get()
        engine.view_draw(ctx, dg)
        engine.view_draw(ctx, dg)
        assert engine._viewport is session and session.samples_done == done == 2 and session.error is None
        assert len(engine.reports) == 1
        session.stop()
        setattr(cam.data, attr, good)


# --- 7. adaptive subdivision: the viewport names the levels it evaluates -------------------------

def test_viewport_names_the_subdivision_levels_it_evaluates(scene):
    # the viewport evaluates the modifier at its Levels Viewport; it had said "the Subdivision
    # modifier's Render Levels (3) are used" over a box of level 1 (48 triangles, not 768)
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 1
    m = bpy.data.objects['Box'].modifiers.new("Sub", 'SUBSURF')
    m.levels, m.render_levels, m.use_adaptive_subdivision = 1, 3, True
    text = ("DACRT: 'Box': adaptive subdivision is not rendered (Cycles dices by the dicing rate); "
            "the Subdivision modifier's {} ({}) are used")
    for simplify, levels, box_triangles in ((False, 1, 48), (True, 0, 12)):
        scene.render.use_simplify, scene.render.simplify_subdivision = simplify, 0
        engine = _Engine()
        _viewport(engine, _cam_context(cam))
        engine._viewport.stop()
        assert len(engine._viewport.scene_data.geometry.triangles) == 2 + box_triangles
        assert engine.reports == [text.format("Levels Viewport", levels)]
    # shown in renders only: the viewport does not evaluate it, and says nothing
    scene.render.use_simplify = False
    m.show_viewport = False
    engine = _Engine()
    _viewport(engine, _cam_context(cam))
    engine._viewport.stop()
    assert len(engine._viewport.scene_data.geometry.triangles) == 2 + 12 and engine.reports == []
    # the final render still names its Render Levels
    m.show_viewport = True
    data = export.export_scene(bpy.context.evaluated_depsgraph_get())
    assert any(t == text.format("Render Levels", 3)[len("DACRT: "):] for _, t in data.messages), data.messages


# --- a re-export keeps the last image up; an integrator set-up error is reported ---------------

def test_a_re_export_keeps_drawing_the_last_image_until_its_first_block(scene, monkeypatch):
    # a new session had no image: view_draw drew nothing until its first block (Cycles keeps
    # the last frame up)
    from addon import display, viewport
    drawn = []
    monkeypatch.setattr(display.Display, 'draw', lambda self, engine, sc, image, version, w, h:
                        drawn.append((image, version)))
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    engine, ctx = _Engine(), _cam_context(cam)
    last = _viewport(engine, ctx).copy()
    version = engine._viewport.image()[0]
    monkeypatch.setattr(viewport.ViewportSession, '_run', lambda self: None)    # (no block comes)
    dg = bpy.context.evaluated_depsgraph_get()
    old = engine._viewport
    monkeypatch.setattr('addon.engine._renders_differently', lambda *args: True)     # (an edit)
    engine.view_update(ctx, dg)
    assert engine._viewport is not old
    engine.view_draw(ctx, dg)
    assert len(drawn) == 1
    np.testing.assert_array_equal(drawn[0][0], last)
    assert drawn[0][1] == version
    engine._viewport.stop()


def test_an_integrator_set_up_error_in_the_viewport_is_reported_once(scene, monkeypatch):
    # it had been in the status line alone; export errors are reported (once) too
    from addon import viewport

    def failing(*args, **kwargs):
        raise ValueError("the scene has no usable lights")
    monkeypatch.setattr(viewport, 'Integrator', failing)
    cam = _lit_box(scene)
    engine, ctx = _Engine(), _cam_context(cam)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    engine._viewport._thread.join(60)
    for _ in range(3):
        engine.view_draw(ctx, dg)
    assert engine.status[-1] == "DACRT | Error: the scene has no usable lights"
    assert engine.reports == ["DACRT: viewport: the scene has no usable lights"]
