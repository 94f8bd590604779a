"""The CLI's linear EXR of a stereo render is one file per eye whatever the .blend's Output >
Views Format: with Stereo 3D (Anaglyph, Side-by-Side, ...) it had been one EXR holding the
anaglyph (R of the left eye, G and B of the right) or the two eyes side by side, while the PNGs
were per eye."""
import os
import subprocess
import sys

import bpy
import numpy as np
import pytest

from addon.cli import save_render

from . import conftest, scenes


def _stereo_scene(scene, size=(16, 12)):
    """A lit box on a plane seen by a stereo camera whose eyes see different images."""
    scene.render.resolution_x, scene.render.resolution_y = size
    scenes.camera((4, -5, 3), rotation=(1.1, 0, 0.7))
    scene.camera.data.stereo.interocular_distance = 0.5
    scenes.plane("Ground", size=20, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    scenes.cube("Box", size=1.5, location=(0, 0, 0.75), materials=(scenes.diffuse("Red", (0.8, 0.1, 0.1)),))
    scenes.light('SUN', 3.0, rotation=(0.6, 0.2, 0.3))
    scene.dacrt.samples = 1
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'


def _saved(scene, folder):
    """{file name: channels} of what save_render writes to folder/shot.png and .exr."""
    written = save_render(scene, str(folder / "shot.png"), str(folder / "shot.exr"))
    assert sorted(os.listdir(folder)) == sorted(os.path.basename(w) for w in written)
    return {os.path.basename(w): scenes.read_exr(w) for w in written if w.endswith(".exr")}


@pytest.mark.parametrize("passes", [False, True], ids=["plain", "multilayer"])
def test_stereo_3d_output_still_writes_one_linear_exr_per_eye(scene, tmp_path, passes):
    _stereo_scene(scene)
    bpy.context.view_layer.use_pass_z = passes      # a multilayer EXR: one multi-view file before
    bpy.ops.render.render()
    settings = scene.render.image_settings
    (tmp_path / "individual").mkdir()
    reference = _saved(scene, tmp_path / "individual")
    assert sorted(reference) == ["shot_L.exr", "shot_R.exr"]
    prefix = f"{bpy.context.view_layer.name}.Combined." if passes else ""
    left, right = (scenes.rgba(reference[f"shot_{s}.exr"], prefix) for s in "LR")
    assert left.shape == (12, 16, 4) and np.abs(left - right).max() > 0.05   # the eyes differ
    for mode in ('ANAGLYPH', 'SIDEBYSIDE', 'TOPBOTTOM', 'INTERLACE'):
        settings.views_format = 'STEREO_3D'
        settings.stereo_3d_format.display_mode = mode
        folder = tmp_path / mode
        folder.mkdir()
        got = _saved(scene, folder)
        assert sorted(got) == ["shot_L.exr", "shot_R.exr"], (mode, sorted(got))
        for name, channels in got.items():      # the same render: bit for bit the per-eye files
            assert sorted(channels) == sorted(reference[name])
            for c, px in channels.items():
                assert np.array_equal(px, reference[name][c]), (mode, name, c)
        # the .blend's own output settings are left as they were
        assert settings.views_format == 'STEREO_3D' and settings.stereo_3d_format.display_mode == mode
        assert settings.file_format == 'PNG'


def test_cli_render_of_an_anaglyph_blend_writes_per_eye_exrs(scene, tmp_path):
    _stereo_scene(scene)
    settings = scene.render.image_settings
    settings.views_format = 'STEREO_3D'
    settings.stereo_3d_format.display_mode = 'ANAGLYPH'
    blend = tmp_path / "anaglyph.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    env = dict(os.environ, PYTHONPATH=str(conftest.ROOT))
    out = subprocess.run([sys.executable, "-m", "addon.cli", "render", str(blend), "--samples", "1",
                          "--out", str(tmp_path / "o" / "shot.png")], cwd=str(tmp_path),
                         capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 0, out.stdout + out.stderr
    assert sorted(os.listdir(tmp_path / "o")) == ["shot_L.exr", "shot_L.png", "shot_R.exr", "shot_R.png"]
    for side in "LR":
        img = scenes.rgba(scenes.read_exr(tmp_path / "o" / f"shot_{side}.exr"))
        assert img.shape == (12, 16, 4) and img[..., :3].mean() > 0
