"""A stereo / multiview save that fails is an error naming the file, never 'wrote ...': Blender
writes each view to its own file and raises all the same, so the CLI accepted any error once the
view files existed, and a write that really failed leaves them existing and empty (Stereo 3D,
Pixel Aspect 2 and a Depth pass: exit 0, 'DACRT: wrote ... shot_L.exr and shot_R.exr', both 0
bytes). Only view files this save wrote, non-empty and readable, are the result now; a stale
file of an earlier run does not pass for one."""
import os
import subprocess
import sys

import bpy
import pytest

from addon import cli

from . import conftest, scenes


def _stereo(scene):
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=100, materials=(scenes.diffuse("Ground", (0.2, 0.4, 0.6)),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 1
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'


def _failing_multilayer(scene):
    """A render result Blender cannot save as multilayer EXR: Render Single Layer and a second
    render in one session ('Each part should have a unique name'; Cycles' fails alike), the
    view files left empty."""
    scene.view_layers.new("Second")
    scene.render.use_single_layer = True
    bpy.ops.render.render()
    bpy.ops.render.render()


@pytest.mark.parametrize('stale', [False, True], ids=['fresh', 'stale-files'])
def test_failed_view_write_is_an_error_naming_the_files(scene, tmp_path, stale):
    _stereo(scene)
    if stale:       # a good earlier save of the same names
        bpy.ops.render.render()
        scene.view_layers[0].use_pass_z = True
        cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
        assert all(os.path.getsize(tmp_path / f"shot_{s}.exr") > 0 for s in "LR")
    _failing_multilayer(scene)
    with pytest.raises(RuntimeError) as e:
        cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    assert "shot_L.exr" in str(e.value) and "shot_R.exr" in str(e.value) and "not written" in str(e.value)
    # no empty file passes for a result, and no stale one is left under the new render's name
    assert sorted(os.listdir(tmp_path)) == ["shot_L.png", "shot_R.png"], os.listdir(tmp_path)


def test_cli_exits_non_zero_naming_a_view_file_it_could_not_write(scene, tmp_path):
    """Through the CLI: the right eye's EXR cannot be made (a folder has its name): exit 1, the
    message names it, nothing said to be written."""
    _stereo(scene)
    scene.view_layers[0].use_pass_z = True
    blend = tmp_path / "stereo.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    (tmp_path / "o" / "shot_R.exr").mkdir(parents=True)
    env = dict(os.environ, PYTHONPATH=str(conftest.ROOT))
    out = subprocess.run([sys.executable, "-m", "addon.cli", "render", str(blend), "--samples", "1",
                          "--out", str(tmp_path / "o" / "shot.png")], cwd=str(tmp_path),
                         capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 1, out.stdout + out.stderr
    assert "could not write the image" in out.stderr and "shot_R.exr" in out.stderr, out.stderr
    assert "DACRT: wrote" not in out.stdout + out.stderr


def test_a_good_stereo_save_still_returns_every_view(scene, tmp_path):
    """The usual case is unchanged: Blender raises after writing both views; both are the result."""
    _stereo(scene)
    scene.view_layers[0].use_pass_z = True
    bpy.ops.render.render()
    written = cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    assert sorted(os.path.basename(w) for w in written) == ["shot_L.exr", "shot_L.png", "shot_R.exr", "shot_R.png"]
    assert all(os.path.getsize(w) > 0 for w in written)


def test_a_failed_single_file_names_it_and_leaves_no_empty_file(scene, tmp_path):
    """Mono: Blender's error, with the file named; the 0-byte EXR it left is removed."""
    _stereo(scene)
    scene.render.use_multiview = False
    _failing_multilayer(scene)
    with pytest.raises(RuntimeError) as e:
        cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    assert "shot.exr not written" in str(e.value) and "Blender:" in str(e.value), str(e.value)
    assert sorted(os.listdir(tmp_path)) == ["shot.png"]


def test_views_sharing_a_file_suffix_are_an_error(scene, tmp_path):
    """Two views with one suffix: one image had overwritten the other while the CLI said it wrote
    both (four names for two files). Now refused, naming the views and the setting."""
    _stereo(scene)
    scene.render.views['right'].file_suffix = scene.render.views['left'].file_suffix
    bpy.ops.render.render()
    with pytest.raises(RuntimeError, match="views 'left', 'right' share a file suffix"):
        cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
