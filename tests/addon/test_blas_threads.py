"""numpy's OpenBLAS runs on the calling thread while a frame renders (addon/blasthreads.py): its
worker threads, woken even by the export's 3x3 inverses, spun on the second core beside the
tracer's (~13 ms CPU a 4-spp dragon render). Its own setting returns after the render, also
after one that failed, and the image is the same bits either way."""
import contextlib

import bpy
import numpy as np
import pytest

from addon import blasthreads, engine, export, integrator
from addon.viewport import ViewportSession

from . import scenes


def _numpy_uses_openblas():
    blas = np.show_config(mode='dicts').get('Build Dependencies', {}).get('blas', {})
    return 'openblas' in str(blas.get('name', '')).lower()


pytestmark = pytest.mark.skipif(not _numpy_uses_openblas(),
                                reason="this numpy is not built on OpenBLAS (nothing to keep on one thread)")


@pytest.fixture
def openblas_threads():
    """OpenBLAS's thread count set to 2 for the test (so that one thread is a change on any
    machine), its own restored after; returns the getter."""
    api = blasthreads.controls()
    assert api is not None, "numpy is built on OpenBLAS, but its thread controls were not found"
    get, put = api
    before = int(get())
    put(2)
    assert int(get()) == 2
    yield get
    put(before)


def _lit_smooth_sphere():
    """A smooth, scaled and turned sphere (the export inverts its matrix for the normals) on a
    plane under a sun."""
    scenes.camera(location=(0, -6, 3), rotation=(1.1, 0, 0))
    sphere = scenes.uv_sphere(materials=[scenes.diffuse("Grey", (0.7, 0.7, 0.7))])
    sphere.scale, sphere.rotation_euler = (1.0, 0.6, 1.3), (0.3, 0.2, 0.5)
    scenes.plane(size=8.0, location=(0, 0, -1.3))
    scenes.light('SUN', 3.0, rotation=(0.5, 0.2, 0.0))
    bpy.context.scene.dacrt.samples = 4


def test_a_render_keeps_openblas_on_one_thread(monkeypatch, openblas_threads):
    _lit_smooth_sphere()
    seen = []
    real_export, real_passes = export.export_scene, integrator.Integrator.passes

    def exporting(*a, **k):
        seen.append(('export', int(openblas_threads())))
        return real_export(*a, **k)

    def passes(self):
        seen.append(('passes', int(openblas_threads())))
        yield from real_passes(self)
    monkeypatch.setattr(export, 'export_scene', exporting)
    monkeypatch.setattr(integrator.Integrator, 'passes', passes)
    bpy.ops.render.render()
    assert seen == [('export', 1), ('passes', 1)]
    assert int(openblas_threads()) == 2           # its own setting again


def test_a_viewport_session_keeps_openblas_on_one_thread(monkeypatch, openblas_threads):
    """Its set-up and passes on the session's worker thread: the same, given back after."""
    _lit_smooth_sphere()
    bpy.context.scene.dacrt.preview_samples = 4
    seen = []
    real_init, real_passes = integrator.Integrator.__init__, integrator.Integrator.passes

    def init(self, *a, **k):
        seen.append(('set-up', int(openblas_threads())))
        real_init(self, *a, **k)

    def passes(self):
        seen.append(('passes', int(openblas_threads())))
        yield from real_passes(self)
    monkeypatch.setattr(integrator.Integrator, '__init__', init)
    monkeypatch.setattr(integrator.Integrator, 'passes', passes)
    cam = bpy.context.scene.camera
    dg = bpy.context.evaluated_depsgraph_get()
    view = export.viewport_camera(cam.matrix_world.inverted(), cam.calc_matrix_camera(dg, x=32, y=24), 32, 24)
    session = ViewportSession(export.export_scene(dg, view_camera=view))
    session.start(view)
    session._thread.join(120.0)
    assert not session.running and session.error is None, session.error
    assert seen and set(seen) == {('set-up', 1), ('passes', 1)}, seen
    assert int(openblas_threads()) == 2


def test_a_failed_render_gives_the_setting_back(monkeypatch, openblas_threads):
    _lit_smooth_sphere()

    def failing(*a, **k):
        raise RuntimeError("boom")
    monkeypatch.setattr(export, 'export_scene', failing)
    with pytest.raises(RuntimeError, match="boom"):      # (the engine's error report)
        bpy.ops.render.render()
    assert int(openblas_threads()) == 2


def test_nested_and_interleaved_uses_restore_once(openblas_threads):
    outer, inner = blasthreads.blas_on_caller(), blasthreads.blas_on_caller()
    outer.__enter__()
    inner.__enter__()
    assert int(openblas_threads()) == 1
    outer.__exit__(None, None, None)              # the outer one may end first (another thread's)
    assert int(openblas_threads()) == 1
    inner.__exit__(None, None, None)
    assert int(openblas_threads()) == 2


def test_image_does_not_depend_on_it(monkeypatch, openblas_threads):
    _lit_smooth_sphere()
    one = scenes.render_rgba()
    monkeypatch.setattr(engine, 'blas_on_caller', contextlib.nullcontext)
    two = scenes.render_rgba()
    assert one[..., 3].min() == 1.0 and one[..., :3].max() > 0.05     # a lit frame
    np.testing.assert_array_equal(one, two)
