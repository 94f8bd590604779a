"""The CLI's multilayer EXR at Pixel Aspect != 1: Blender 5.0's multilayer writer gives the
aspect to the first part alone and OpenEXR refuses parts that disagree, so a render with any pass
beyond Combined (or two layers) failed after rendering: exit 1, 'could not write the image', a
0-byte EXR (64x48 Cornell box, Pixel Aspect 2, Depth). The CLI now writes it at aspect 1, sets
the true aspect on every part afterwards (as Blender's plain EXR records it) and says so; the
.blend's aspect is left as it was."""
import os
import subprocess
import sys

import bpy
import numpy as np
import pytest

from addon import cli

from . import conftest, scenes


def _scene(scene, aspect=(2.0, 1.0)):
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=100, materials=(scenes.diffuse("Ground", (0.2, 0.4, 0.6)),))
    scenes.cube("Box", size=1.0, location=(0, 0, 0.5), materials=(scenes.diffuse("Red", (0.8, 0.1, 0.1)),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 1
    scene.render.pixel_aspect_x, scene.render.pixel_aspect_y = aspect


def _headers(path):
    """[(part name, PixelAspectRatio, XResolution, YResolution)] of an EXR."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    out, i = [], 0
    while inp.seek_subimage(i, 0):
        s = inp.spec()
        out.append((s.getattribute('name'), s.getattribute('PixelAspectRatio'), s.getattribute('XResolution'),
                    s.getattribute('YResolution')))
        i += 1
    inp.close()
    return out


def _cli(blend, out, cwd):
    env = dict(os.environ, PYTHONPATH=str(conftest.ROOT))
    return subprocess.run([sys.executable, "-m", "addon.cli", "render", str(blend), "--samples", "1",
                           "--out", str(out)], cwd=str(cwd), capture_output=True, text=True, timeout=600, env=env)


def test_cli_writes_the_multilayer_exr_at_pixel_aspect_2(scene, tmp_path):
    """The hunt's case through the CLI: exit 0, every pass in the EXR, each part's aspect 2 and
    the resolution Blender's plain EXR of the same render records (without passes)."""
    _scene(scene)
    blend = tmp_path / "plain.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    plain = _cli(blend, tmp_path / "plain" / "shot.png", tmp_path)
    assert plain.returncode == 0, plain.stdout + plain.stderr
    scene.view_layers[0].use_pass_z = True
    blend = tmp_path / "depth.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = _cli(blend, tmp_path / "depth" / "shot.png", tmp_path)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "could not write" not in out.stderr and "PixelAspectRatio then set to 2" in out.stdout, out.stdout
    exr = tmp_path / "depth" / "shot.exr"
    headers = _headers(exr)
    layer = scene.view_layers[0].name
    assert {h[0] for h in headers} >= {f"{layer}.Combined", f"{layer}.Depth"}, headers
    assert all(h[1] == 2.0 for h in headers), headers
    reference = _headers(tmp_path / "plain" / "shot.exr")[0]
    assert reference[1:] == (2.0, 36.0, 72.0) and headers[0][1:] == reference[1:], (headers, reference)
    channels = scenes.read_exr(exr)
    combined = scenes.rgba(channels, f"{layer}.Combined.")
    assert combined.shape == (12, 16, 4) and combined[..., :3].mean() > 0
    assert np.allclose(combined, scenes.rgba(scenes.read_exr(tmp_path / "plain" / "shot.exr")), atol=1e-6)
    depth = channels[f"{layer}.Depth.Z"]
    assert set(np.unique(depth)) == {4.0, 5.0}, np.unique(depth)      # the box's top, the ground


@pytest.mark.parametrize('aspect', [(1.0, 3.0), (3.0, 2.0)])
def test_save_render_sets_the_aspect_and_leaves_the_scene_alone(scene, tmp_path, capsys, aspect):
    """In process: the aspect (pixel width / height) on every part, with the resolution Blender
    writes for it (a plain EXR of the same render), and the scene's Pixel Aspect restored."""
    _scene(scene, aspect)
    bpy.ops.render.render()
    plain = cli.save_render(scene, str(tmp_path / "plain.png"), str(tmp_path / "plain.exr"))
    scene.view_layers[0].use_pass_z = True
    bpy.ops.render.render()
    written = cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    assert written == [str(tmp_path / "shot.png"), str(tmp_path / "shot.exr")] and len(plain) == 2
    assert (scene.render.pixel_aspect_x, scene.render.pixel_aspect_y) == aspect
    headers, reference = _headers(tmp_path / "shot.exr"), _headers(tmp_path / "plain.exr")[0]
    ratio = aspect[0] / aspect[1]
    assert len(headers) >= 2 and all(abs(h[1] - ratio) < 1e-6 for h in headers), headers
    assert np.allclose(headers[0][1:], reference[1:]), (headers[0], reference)
    assert f"PixelAspectRatio then set to {ratio:g}" in capsys.readouterr().out


def test_without_openimageio_the_exr_is_written_at_aspect_1_and_said(scene, tmp_path, capsys, monkeypatch):
    """Where the aspect cannot be set afterwards, the pixels are still written and the output
    says the file's aspect is 1."""
    _scene(scene)
    scene.view_layers[0].use_pass_z = True
    bpy.ops.render.render()
    monkeypatch.setitem(sys.modules, 'OpenImageIO', None)       # import fails
    cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    monkeypatch.undo()
    assert os.path.getsize(tmp_path / "shot.exr") > 0
    assert all(h[1] == 1.0 for h in _headers(tmp_path / "shot.exr"))
    said = capsys.readouterr().out
    assert "PixelAspectRatio is left at 1 (OpenImageIO is not installed)" in said, said
    assert scene.render.pixel_aspect_x == 2.0


def test_stereo_views_are_written_with_the_aspect(scene, tmp_path):
    """Stereo 3D, Pixel Aspect 2 and a Depth pass: each eye's EXR is written (they were 0 bytes,
    the CLI saying it wrote them) with the aspect on every part."""
    _scene(scene)
    scene.view_layers[0].use_pass_z = True
    scene.render.use_multiview, scene.render.views_format = True, 'STEREO_3D'
    bpy.ops.render.render()
    written = cli.save_render(scene, str(tmp_path / "shot.png"), str(tmp_path / "shot.exr"))
    exrs = [w for w in written if w.endswith(".exr")]
    assert sorted(os.path.basename(w) for w in exrs) == ["shot_L.exr", "shot_R.exr"], written
    for exr in exrs:
        headers = _headers(exr)
        assert len(headers) >= 2 and all(h[1] == 2.0 for h in headers), (exr, headers)
        assert scenes.rgba(scenes.read_exr(exr), f"{scene.view_layers[0].name}.Combined.")[..., :3].mean() > 0
