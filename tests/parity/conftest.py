"""Headless bpy set-up for the parity tests: the repository root on sys.path and the DACRT
add-on registered (`import addon; addon.register()`) while a test module that asks for
`parity_addon` runs. stats tests need no Blender and do not ask for it.

Other test folders may have registered the add-on already in the same pytest session; then it
is left as it is (registering twice fails) for whoever registered it to unregister. Ours is
unregistered when the module ends, so a folder collected after this one can register it again.
"""
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def _registered(bpy):
    return hasattr(bpy.types.Scene, 'dacrt')      # set by addon.register(), removed by unregister()


@pytest.fixture(scope='module')
def parity_addon():
    import bpy
    import addon
    mine = not _registered(bpy)
    if mine:
        addon.register()
    yield addon
    if mine and _registered(bpy):
        addon.unregister()


@pytest.fixture
def said(monkeypatch):
    """The texts the engine reports (RenderEngine.report) during the test's renders."""
    from tests.reports import recorded_reports
    return recorded_reports(monkeypatch)
