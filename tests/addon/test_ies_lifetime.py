"""A render's IES tables go with it: 20 renders of a scene whose lamp's IES profile text changes
each time (a user editing it, an animation cycling profiles) leave the native registry
(dacrt.lamps.ies_live) where it started; the profile still lights each render. The viewport's
sessions alike: each holds its table while it renders, none after."""
import gc

import bpy
import dacrt

from . import scenes


def _text(k):
    # one vertical fan (0, 45, 90 degrees), intensities that change with k
    return ("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 50\n0 45 90\n0\n"
            f"{1000 + 100 * k} {500 + 10 * k} 0\n")


def _profiled_scene(scene):
    """A plane under a point lamp whose Strength is an IES Texture of an Internal text."""
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    scene.dacrt.samples = scene.dacrt.preview_samples = 2
    cam = scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=20, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    lamp = scenes.light('POINT', 100.0, location=(0, 0, 2), name='Profiled')
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    ies = nt.nodes.new('ShaderNodeTexIES')
    text = bpy.data.texts.new('profile.ies')
    ies.mode, ies.ies = 'INTERNAL', text
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    return cam, text


def test_renders_of_a_changing_profile_leave_no_tables(scene):
    _, text = _profiled_scene(scene)
    gc.collect()
    start = dacrt.lamps.ies_live()
    means = []
    for k in range(20):
        text.from_string(_text(k))
        img = scenes.render_rgba(scene)
        means.append(float(img[..., :3].mean()))
        gc.collect()
        assert dacrt.lamps.ies_live() == start, f"render {k} left {dacrt.lamps.ies_live() - start} IES table(s)"
    assert all(m > 0 for m in means) and means[-1] > means[0]


def test_viewport_sessions_hold_their_table_while_they_render(scene):
    from addon import export
    from addon.viewport import ViewportSession
    from .test_viewport import _finished, _view_of
    cam, text = _profiled_scene(scene)
    gc.collect()
    start = dacrt.lamps.ies_live()
    for k in range(5):
        text.from_string(_text(k))
        data = export.export_scene(bpy.context.evaluated_depsgraph_get(), view_camera=_view_of(cam, 16, 12))
        during = []
        session = ViewportSession(data, lambda: during.append(dacrt.lamps.ies_live()))
        session.start(_view_of(cam, 16, 12))
        assert _finished(session).mean() > 0
        # each block's update while the integrator lived, then the one after the run
        assert during and during[0] == start + 1, during
        del session, data
        gc.collect()
        assert dacrt.lamps.ies_live() == start
