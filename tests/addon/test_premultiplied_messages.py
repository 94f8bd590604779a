"""An 8-bit RGBA image set to Premultiplied alpha: Blender's buffer holds its bytes divided by
alpha. Cycles reads a packed or generated image from that buffer too (image_is_builtin), so
reading it is exact and said nothing; the export had warned "read as Blender divides it by its
alpha (its file could not be read as stored)" for them (measured equal to Cycles: a packed PNG
0.1164 / 0.1372 / 0.1181 both, a generated image 0.1251 / 0.0383 / 0.0383 both). The note
stays where it is true: a file image whose file cannot be read as stored."""
import bpy
import numpy as np
import pytest

from addon import export
from tests.addon import scenes

NOTE = "with Premultiplied alpha read as Blender divides it"


def _bytes():
    rng = np.random.default_rng(41)
    px = (rng.random((6, 6, 4)) * 255).astype(np.uint8)
    px[..., 3] = (rng.random((6, 6)) * 200 + 55).astype(np.uint8)
    return px


def _file_image(tmp_path):
    img = bpy.data.images.load(scenes.write_image(tmp_path / "pp.png", _bytes()), check_existing=False)
    img.alpha_mode = 'PREMUL'
    return img


def _packed(tmp_path):
    img = _file_image(tmp_path)
    img.pack()
    return img


def _generated(tmp_path):
    img = bpy.data.images.new("G", 8, 8, alpha=True)
    img.generated_type = 'COLOR_GRID'
    img.alpha_mode = 'PREMUL'
    a = np.array(img.pixels[:], np.float32).reshape(8, 8, 4)
    a[..., 3] = np.linspace(0.2, 1.0, 64, dtype=np.float32).reshape(8, 8)
    img.pixels.foreach_set(a.ravel())
    img.update()
    return img


def _textured(img):
    mat, nt, out = scenes._material("Textured")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.camera()
    scenes.plane("P", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")


@pytest.mark.parametrize("make", [_packed, _generated, _file_image], ids=lambda f: f.__name__.strip('_'))
def test_premultiplied_bytes_cycles_reads_as_we_do_are_not_warned_of(scene, exported, tmp_path, make):
    _textured(make(tmp_path))
    data = exported()
    assert not any(NOTE in t for _, t in data.messages), data.messages


def test_premultiplied_file_that_cannot_be_read_as_stored_is_said(tmp_path):
    """The note where it is true: a file image whose file is not the 8-bit RGBA it was (here
    rewritten as RGB since Blender loaded it) keeps Blender's divided buffer, said."""
    img = _file_image(tmp_path)
    buf = np.array(img.pixels[:], np.float32).reshape(6, 6, 4)
    scenes.write_image(tmp_path / "pp.png", _bytes()[..., :3])
    reasons = []
    kept = export.images._premultiplied_bytes(img, buf, True, reasons)
    assert kept is buf
    assert len(reasons) == 1 and NOTE in reasons[0] and "its file could not be read as stored" in reasons[0], reasons
    # Blender's buffer read for Cycles' own (packed) lookup: kept, unsaid
    reasons = []
    assert export.images._premultiplied_bytes(img, buf, False, reasons) is buf and reasons == []
