"""The viewport re-exports when the view layer's Filter (Environment, Surfaces) or Cycles'
Transparent Glass (shown in DACRT's panel) changes: these come as updates of the scene alone,
which the viewport had taken for a selection, keeping the stale image (a hunt: Environment off
makes the final render's RGB 0.048 -> 0.000, the viewport kept 0.048)."""
import bpy
import numpy as np

from .test_viewport import _Engine, _finished, _lit_box
from .test_viewport_fixes import _cam_context, _viewport


def test_view_layer_filters_and_transparent_glass_re_export_the_viewport(scene):
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 4
    engine, ctx = _Engine(), _cam_context(cam, perspective='PERSP')

    def handler(sc, dg):            # as Blender calls view_update with the update's depsgraph
        engine.view_update(ctx, dg)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    _finished(engine._viewport)
    layer = bpy.context.view_layer

    def fresh():
        other = _Engine()
        image = _viewport(other, ctx)
        other._viewport.stop()
        return image
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        for owner, prop in ((layer, "use_sky"), (layer, "use_solid")):
            session = engine._viewport
            setattr(owner, prop, not getattr(owner, prop))
            dg.update()
            assert engine._viewport is not session, prop
            np.testing.assert_array_equal(_finished(engine._viewport), fresh())
            setattr(owner, prop, not getattr(owner, prop))
            dg.update()
        session = engine._viewport
        bpy.data.objects['Box'].select_set(True)        # a selection still keeps the samples
        dg.update()
        assert engine._viewport is session
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        engine._viewport.stop()


def test_transparent_glass_is_part_of_the_viewports_settings_key(scene):
    """An edit of Cycles' Transparent Glass or its Roughness Threshold (drawn in DACRT's Film
    panel) changes the key the viewport compares on a scene update (an add-on property's edit is
    not tagged from a script, so the key is checked directly)."""
    from addon.engine import _settings_key
    before = _settings_key(scene)
    scene.cycles.film_transparent_glass = not scene.cycles.film_transparent_glass
    assert _settings_key(scene) != before
    before = _settings_key(scene)
    scene.cycles.film_transparent_roughness = 0.37
    assert _settings_key(scene) != before


def test_a_selection_keeps_the_samples_with_a_nan_setting(scene):
    """A script's NaN in a stored setting (here Clamp Indirect, which the render reads as its
    default, said) or a NaN subframe made the viewport's settings key differ from itself (NaN !=
    NaN): every selection restarted the render, its samples thrown away."""
    from addon.engine import _settings_key
    cam = _lit_box(scene)
    scene.dacrt.samples = scene.dacrt.preview_samples = 4
    scene.dacrt.sample_clamp_indirect = float('nan')
    scene.frame_set(1, subframe=float('nan'))
    assert _settings_key(scene) == _settings_key(scene)
    engine, ctx = _Engine(), _cam_context(cam, perspective='PERSP')

    def handler(sc, dg):
        engine.view_update(ctx, dg)
    dg = bpy.context.evaluated_depsgraph_get()
    engine.view_update(ctx, dg)
    _finished(engine._viewport)
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        session = engine._viewport
        bpy.data.objects['Box'].select_set(True)
        dg.update()
        assert engine._viewport is session
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
        engine._viewport.stop()
