"""The viewport in the 3D view's Local View: the objects it does not show are left out of the
export, as Cycles' viewport sync leaves them (`b_ob.visible_in_viewport_get(b_v3d)`); entering
and leaving it re-export. Driven through the factory startup's real 3D view (the local-view
operator runs headless) and test_viewport's GPU-less engine."""
import numpy as np
import pytest

import bpy

from .test_viewport import _Engine, _finished, _lit_box
from .test_viewport_fixes import _cam_context


@pytest.fixture(autouse=True)
def _no_gpu(monkeypatch):
    from addon import display
    monkeypatch.setattr(display.Display, 'draw', lambda *args: None)


def _view3d():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == 'VIEW_3D')
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return win, area, region, area.spaces.active


def _toggle_local_view(names):
    """View > Local View on the objects named (selected), or back out of it."""
    win, area, region, space = _view3d()
    for ob in bpy.context.scene.objects:
        ob.select_set(ob.name in names)
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.view3d.localview(frame_selected=False)
    return space


def _exported(engine):
    data = engine._viewport.scene_data
    return len(data.geometry.triangles), len(data.lights)


def test_local_view_renders_the_objects_it_shows_and_re_exports_on_entering_and_leaving(scene):
    # Local View on the box alone: the floor and the lamp had still been rendered (14 triangles
    # and 1 light, mean 0.5207 where the box alone gives 0.0552), nothing said
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 8
    space = _view3d()[3]
    engine = _Engine()
    ctx = _cam_context(cam, space=space, perspective='PERSP')

    def handler(sc, dg):            # as Blender calls view_update with the update's depsgraph
        engine.view_update(ctx, dg)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    whole = _finished(engine._viewport).copy()
    assert _exported(engine) == (14, 1)
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        before = engine._viewport
        _toggle_local_view({'Box'})
        assert space.local_view is not None
        dg.update()
        assert engine._viewport is not before           # entering re-exports
        local = _finished(engine._viewport).copy()
        assert _exported(engine) == (12, 0)
        before = engine._viewport
        _toggle_local_view(set())                       # leaving re-exports the whole scene
        assert space.local_view is None
        dg.update()
        assert engine._viewport is not before
        np.testing.assert_allclose(_finished(engine._viewport), whole, atol=1e-6)
        assert _exported(engine) == (14, 1)
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        engine._viewport.stop()
    # the local view's image is that of the box alone (the others hidden)
    for name in ('Floor', 'Area'):
        bpy.data.objects[name].hide_set(True)
    alone = _Engine()
    alone.view_update(_cam_context(cam, space=space, perspective='PERSP'), bpy.context.evaluated_depsgraph_get())
    np.testing.assert_allclose(local, _finished(alone._viewport), atol=1e-6)
    alone._viewport.stop()
    assert abs(float(whole[..., :3].mean()) - float(local[..., :3].mean())) > 0.1


def test_the_final_render_ignores_the_local_view(scene, exported):
    # Cycles' F12 renders every object whatever a 3D view shows
    _lit_box(scene)
    space = _toggle_local_view({'Box'})
    assert space.local_view is not None
    data = exported()
    assert len(data.geometry.triangles) == 14 and len(data.lights) == 1
