"""Headless bpy set-up for the add-on tests: register the add-on once per session, start every
test from a factory-empty scene with DACRT as its engine, and capture what the engine exports."""
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402  (needs the repository root on sys.path first for `addon`)

import addon  # noqa: E402
from addon import export  # noqa: E402
from tests.reports import recorded_reports  # noqa: E402


@pytest.fixture(scope='session', autouse=True)
def dacrt_addon():
    """Registered once; left alone if another test folder registered it in this session."""
    mine = not hasattr(bpy.types.Scene, 'dacrt')
    if mine:
        addon.register()
    yield addon
    if mine and hasattr(bpy.types.Scene, 'dacrt'):
        addon.unregister()


@pytest.fixture(autouse=True)
def scene(dacrt_addon):
    """A factory-empty scene (registration survives the reset) rendering with DACRT."""
    # the factory startup file, the preferences kept: read_factory_settings also resets them,
    # 0.07 s CPU a test against 0.015 s (no test changes a preference in process)
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.engine = 'DACRT'
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    return sc


@pytest.fixture
def exported(monkeypatch):
    """`exported()` renders the context scene through the engine but stops right after the
    export (cancelled), returning the SceneData the engine built from the render depsgraph."""
    captured = []
    real = export.export_scene

    def capture(depsgraph, check_break=None, camera=None, **kw):
        captured.append(real(depsgraph, check_break, camera, **kw))
        raise export.ExportCancelled()

    monkeypatch.setattr(export, 'export_scene', capture)

    def run(animation=False):
        """animation: as Ctrl-F12 or `blender -a` (the frame range; originals not updated)."""
        captured.clear()
        bpy.ops.render.render(animation=animation)
        assert len(captured) == 1, "the engine did not export exactly once"
        return captured[0]
    return run


@pytest.fixture
def said(monkeypatch):
    """The texts the engine reports (RenderEngine.report) during the test's renders."""
    return recorded_reports(monkeypatch)


@pytest.fixture
def calls_to(monkeypatch):
    """calls_to(module, name): a list that gets `name` appended at each call of module.name
    (the call itself goes through), to count builds and reads."""
    def watch(module, name):
        calls = []
        real = getattr(module, name)

        def counted(*a, **k):
            calls.append(name)
            return real(*a, **k)
        monkeypatch.setattr(module, name, counted)
        return calls
    return watch
