"""`compare` (python -m tests.bench compare, build.py compare) on .blend files it had failed on
with "DACRT worker failed: RuntimeError: Error: Image 'Render Result' could not be saved" and a
traceback: a scene with no view layer enabled (now refused with the reason, as the CLI says it)
and a stereo file (now its left view alone is rendered and compared by both engines). Its work
folder is inside --out, not the repository's bench-out, and a refused scene leaves none.
`--materials as-is` lists what the DACRT render approximated, not every material of the file."""
import json
import subprocess
import sys
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.bench import compare, renderjobs
from tests.bench.scenes import OUT

from . import conftest, scenes


def _blend(scene, path, **settings):
    """A small lit box on a plane (48x36) saved as path, with `settings` applied to it."""
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    scenes.camera((4, -5, 3), rotation=(1.1, 0, 0.7))
    # (pivot 'LEFT', Blender's default, would make the left eye the mono camera)
    scene.camera.data.stereo.interocular_distance, scene.camera.data.stereo.pivot = 1.0, 'CENTER'
    scenes.plane("Ground", size=20, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    scenes.cube("Box", size=1.5, location=(0, 0, 0.75), materials=(scenes.diffuse("Red", (0.8, 0.1, 0.1)),))
    scenes.light('SUN', 3.0, rotation=(0.6, 0.2, 0.3))
    for apply in settings.values():
        apply(scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    return path


def _compare(blend, out, samples=8, materials="diffuse"):
    return subprocess.run([sys.executable, "-m", "tests.bench", "compare", str(blend), "--samples",
                           str(samples), "--out", str(out), "--materials", materials], cwd=str(conftest.ROOT),
                          capture_output=True, text=True, timeout=600)


def _work_folders():
    return set(OUT.glob("compare-*")) if OUT.is_dir() else set()


def test_a_scene_without_a_rendered_view_layer_is_refused_with_the_reason(scene, tmp_path):
    def no_layer(sc):
        sc.view_layers[0].use = False
    blend = _blend(scene, tmp_path / "nolayer.blend", no_layer=no_layer)
    before = _work_folders()
    got = _compare(blend, tmp_path / "out")
    assert got.returncode == 2, got.stdout + got.stderr
    assert "no view layer enabled for rendering (View Layer Properties > Use for Rendering)" in got.stderr
    assert "could not be saved" not in got.stderr and "Traceback" not in got.stderr, got.stderr
    assert list((tmp_path / "out").iterdir()) == []          # nothing left behind: the reason is said
    assert _work_folders() == before


@pytest.mark.parametrize("views_format", ['INDIVIDUAL', 'ANAGLYPH'])
def test_a_stereo_file_compares_its_left_view(scene, tmp_path, views_format):
    def stereo(sc):
        sc.render.use_multiview, sc.render.views_format = True, 'STEREO_3D'
        if views_format != 'INDIVIDUAL':      # the file's own output setting must not matter
            sc.render.image_settings.views_format = 'STEREO_3D'
            sc.render.image_settings.stereo_3d_format.display_mode = views_format
    before = _work_folders()
    got = _compare(_blend(scene, tmp_path / "stereo.blend", stereo=stereo), tmp_path / "stereo")
    assert got.returncode == 0, got.stdout + got.stderr
    assert "view 'left' alone rendered and compared" in got.stdout
    doc = json.loads((tmp_path / "stereo" / "compare.json").read_text())
    assert doc["view"] == "left" and doc["resolution"] == [48, 36]
    # both engines rendered the same view: noise alone (ratio ~1; a different view: >> 10)
    assert doc["relmse_ratio"] < 3, doc["relmse_ratio"]
    assert all(abs(r - 1) < 0.05 for r in doc["mean_ratio_rgb"]), doc["mean_ratio_rgb"]
    assert sorted(p.name for p in (tmp_path / "stereo").iterdir()) == [
        "compare.json", "cycles.exr", "dacrt.exr", "difference.png", "side_by_side.png"]
    assert _work_folders() == before
    # the left eye, not the mono camera: the mono file's DACRT image differs from it
    scene.render.use_multiview = False
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "mono.blend"), copy=True)
    mono = _compare(tmp_path / "mono.blend", tmp_path / "mono")
    assert mono.returncode == 0, mono.stdout + mono.stderr
    left, centre = (scenes.rgba(scenes.read_exr(tmp_path / d / "dacrt.exr")) for d in ("stereo", "mono"))
    red = lambda img: np.nonzero((img[..., 0] - img[..., 1] > 0.1).any(axis=0))[0].mean()  # noqa: E731
    assert abs(red(left) - red(centre)) > 4      # the box's columns: moved in the left eye


@pytest.mark.parametrize("expected, kept", [(True, False), (False, True)])
def test_the_work_folder_is_under_out_and_kept_only_for_a_failure(tmp_path, monkeypatch, expected, kept):
    """A failure (a bug) keeps the work folder, whose log the error names, inside --out; a
    scene refused with a reason keeps nothing; neither writes to the repository's bench-out."""
    seen = []

    def fail(engine, renders, work, progress=None, label=""):
        seen.append(work)
        (work / "worker.log").write_text("log")
        raise renderjobs.WorkerError("DACRT worker failed: X", expected=expected)
    monkeypatch.setattr(compare, "run_jobs", fail)
    before = _work_folders()
    args = SimpleNamespace(scene="cornell", samples=1, bounces=None, seed=0, materials="diffuse",
                           out=tmp_path / "out")
    with pytest.raises(renderjobs.WorkerError):
        compare.run(args)
    assert seen and seen[0].parent == tmp_path / "out"
    assert seen[0].exists() == kept and (seen[0] / "worker.log").exists() == kept
    assert _work_folders() == before


def test_as_is_lists_what_the_dacrt_render_approximated_only(scene, tmp_path):
    """--materials as-is listed every material and material-less object of the file: a hidden
    helper without a material as '(default surface)', a Glossy material on no object or on a
    hidden one, though the render (and its relMSE) had nothing of them. Now what the DACRT render
    itself approximated: the visible Glossy object, and the default surface once a mesh without
    a material is rendered."""
    def objects(sc):
        scenes.cube("Shiny", size=1.0, location=(2, 0, 0.5), materials=(_glossy("Glossy"),))
        scenes.cube("HiddenBare", size=1.0, location=(-2, 0, 0.5)).hide_render = True
        scenes.cube("HiddenShiny", size=1.0, location=(-2, 2, 0.5),
                    materials=(_glossy("HiddenGlossy"),)).hide_render = True
        _glossy("Unused").use_fake_user = True
    blend = _blend(scene, tmp_path / "helpers.blend", objects=objects)
    listed = lambda out: {line.split("'")[1] for line in out.splitlines()  # noqa: E731
                          if "DACRT approximates '" in line}
    got = _compare(blend, tmp_path / "a", samples=4, materials="as-is")
    assert got.returncode == 0, got.stdout + got.stderr
    approximated = json.loads((tmp_path / "a" / "compare.json").read_text())["materials"]["approximated"]
    assert set(approximated) == {"Glossy"} and listed(got.stdout) == {"Glossy"}, got.stdout
    bpy.data.objects["HiddenBare"].hide_render = False
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    got = _compare(blend, tmp_path / "b", samples=4, materials="as-is")
    assert got.returncode == 0, got.stdout + got.stderr
    assert listed(got.stdout) == {"Glossy", "(default surface)"}, got.stdout


def _glossy(name):
    mat, nt, out = scenes._material(name)
    nt.links.new(nt.nodes.new('ShaderNodeBsdfGlossy').outputs[0], out.inputs['Surface'])
    return mat
