"""Which file and colour space the export reads an image from, as Cycles (the renders are
compared in tests/parity/test_image_files.py): an image sequence's frame from its image user
(imageuser.py, Blender's BKE_image_user_frame_get: start, duration clamped or cyclic, then the
offset; the file name's last digits replaced, zero-padded), for Image and Environment Textures
alike; colour spaces resolved through Blender's OCIO config (colorspaces.py: roles such as
'scene_linear' are the space they name)."""
import bpy
import numpy as np
import pytest

from addon import export
from addon.export import colorspaces
from addon.export.imageuser import sequence_path, user_frame
from addon.texture import srgb_to_linear

from . import scenes

FRAMES = [[200, 30, 30], [30, 200, 30], [30, 30, 200]]


def _sequence(tmp_path):
    for i, rgb in enumerate(FRAMES):
        scenes.write_image(tmp_path / f"seq_{i + 1:03d}.png", np.array([[rgb]], np.uint8))
    img = bpy.data.images.load(str(tmp_path / "seq_001.png"))
    img.source = 'SEQUENCE'
    return img


@pytest.mark.parametrize('scene_frame, start, duration, offset, cyclic, want', [
    (2, 1, 3, 0, False, 2),
    (9, 1, 3, 0, False, 3),        # clamped to the duration
    (-4, 1, 3, 0, False, 0),       # ... and to 0
    (5, 1, 3, 0, True, 2),         # wrapped
    (3, 1, 3, 0, True, 3),         # a wrap's 0 is the last frame
    (-1, 1, 3, 0, True, 2),
    (8, 4, 3, 2, True, 4),         # the offset after the wrap (Cycles: frame 4, not 1)
    (2, 1, 3, 10, False, 12),
    (2, 1, 0, 5, False, 0),        # no duration: frame 0
])
def test_user_frame_as_blender(tmp_path, scene_frame, start, duration, offset, cyclic, want):
    img = _sequence(tmp_path)
    mat, nt, out = scenes._material("M")
    user = nt.nodes.new('ShaderNodeTexImage').image_user
    user.frame_start, user.frame_duration, user.frame_offset, user.use_cyclic = start, duration, offset, cyclic
    assert user_frame(img, user, scene_frame) == want


@pytest.mark.parametrize('name', ['seq_007.png', 'img_001.jp2', 'a1b22.c3', 'plate.0001', 'nodigits.png',
                                  'noext_01', '.hidden7', 'x..5', 'v2.tar.gz'])
def test_sequence_path_is_the_file_blender_reads(tmp_path, name):
    """Against Blender's own answer (Image.filepath_from_user at the image user's frame): the
    last digits before the extension, padded; digits in an extension ('.jp2') are not the
    frame's (frame 3 of img_001.jp2 had been read from 'img_001.jp3'); a name without digits
    gets the frame before its extension; a negative frame reads as 0."""
    img = bpy.data.images.new(name, 4, 4)
    img.filepath_raw = str(tmp_path / name)
    img.source = 'SEQUENCE'
    mat, nt, out = scenes._material("M")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    for frame in (0, 1, 3, 1234, -2):
        tex.image_user.frame_current = frame
        assert sequence_path(img, frame) == img.filepath_from_user(image_user=tex.image_user), (name, frame)
    assert sequence_path(img, 3) != str(tmp_path / name)


def _diffuse_of(img, user_settings):
    mat, nt, out = scenes._material("Seq " + img.name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    user_settings(tex.image_user)
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    builder = export.materials.MaterialBuilder()
    return builder.materials[builder.index(mat)]


def test_sequence_texture_reads_the_frame_shown(tmp_path):
    """At scene frame 2 the user shows frame 2 (green); a second node offset by 1 shows frame 3
    (blue): the two are read apart, not shared as one image."""
    img = _sequence(tmp_path)
    bpy.context.scene.frame_set(2)

    def frames(offset):
        def settings(user):
            user.frame_start, user.frame_duration, user.frame_offset = 1, 3, offset
        return settings

    for offset, want in ((0, FRAMES[1]), (1, FRAMES[2])):
        m = _diffuse_of(img, frames(offset))
        assert not m.approximated, m.approximated
        np.testing.assert_allclose(m.texture[0, 0, :3], srgb_to_linear(np.array(want) / 255.0), atol=1e-6)


def test_sequence_frame_is_the_rendered_scenes(tmp_path, exported):
    """The frame is the rendered scene's, not the context's: a sequencer scene strip renders
    its scene at the strip's frame (here the main scene's frame 10 shows the strip's frame 3),
    and the image sequence must show that frame's file (it read the context scene's: frame 10,
    clamped to 3 frames, not the same file in general)."""
    img = _sequence(tmp_path)
    main = bpy.context.scene
    shot = bpy.data.scenes.new("Shot")
    shot.render.engine = 'DACRT'
    mat, nt, out = scenes._material("Seq")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    tex.image_user.frame_start, tex.image_user.frame_duration, tex.image_user.use_cyclic = 1, 3, True
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    shot.camera = scenes.camera(scene=shot)
    scenes.plane("P", materials=(mat,), scene=shot)
    world = scenes.environment_world(img, scene=shot)
    node = next(n for n in world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    node.image_user.frame_start, node.image_user.frame_duration, node.image_user.use_cyclic = 1, 3, True
    main.render.use_sequencer = True
    strips = main.sequence_editor_create()
    strips = strips.strips if hasattr(strips, 'strips') else strips.sequences
    strips.new_scene("S", shot, channel=1, frame_start=8)     # main frame 10: the shot's frame 3
    main.frame_set(10)                                        # (cyclic: frame 10 would show 1)
    data = exported()                         # the strip's scene, the one the engine renders
    blue = srgb_to_linear(np.array(FRAMES[2]) / 255.0)
    m = next(m for m in data.materials if m.name == "Seq")
    np.testing.assert_allclose(m.texture[0, 0, :3], blue, atol=1e-6)
    np.testing.assert_allclose(data.environment.pixels[0, 0, :3], blue, atol=1e-6)


def test_missing_frame_is_magenta_and_reported(tmp_path):
    img = _sequence(tmp_path)
    bpy.context.scene.frame_set(2)

    def settings(user):
        user.frame_start, user.frame_duration, user.frame_offset = 1, 3, 5     # frame 7: no file
    m = _diffuse_of(img, settings)
    assert "frame 7 could not be read" in m.approximated and "seq_007.png" in m.approximated


def test_environment_sequence_reads_the_frame_shown(tmp_path):
    img = _sequence(tmp_path)
    bpy.context.scene.frame_set(3)
    world = scenes.environment_world(img)
    node = next(n for n in world.node_tree.nodes if n.type == 'TEX_ENVIRONMENT')
    node.image_user.frame_start, node.image_user.frame_duration = 1, 3
    reasons = []
    pixels = export.images.image_pixels(img, reasons, user=node.image_user)
    assert not reasons, reasons
    np.testing.assert_allclose(pixels[0, 0, :3], srgb_to_linear(np.array(FRAMES[2]) / 255.0), atol=1e-6)


@pytest.mark.parametrize('space, kind', [
    ('sRGB', colorspaces.SRGB), ('Linear Rec.709', colorspaces.LINEAR), ('scene_linear', colorspaces.LINEAR),
    ('Non-Color', colorspaces.DATA), ('Linear Rec.2020', colorspaces.CONVERT), ('ACEScg', colorspaces.CONVERT),
    ('Filmic sRGB', colorspaces.CONVERT), ('AgX Base sRGB', colorspaces.CONVERT),
])
def test_colour_space_kinds(space, kind):
    img = bpy.data.images.new("cs", 1, 1)
    img.colorspace_settings.name = space
    reasons = []
    assert colorspaces.space_kind(img, reasons) == kind and not reasons


def test_8bit_rec2020_is_converted_by_its_matrix(tmp_path):
    """An 8-bit file in Linear Rec.2020: its bytes / 255 times the Rec.2020 -> Rec.709 matrix
    (ITU-R BT.2087), as OCIO's conversion gives it."""
    rec2020_to_709 = np.array([[1.6605, -0.5876, -0.0728], [-0.1246, 1.1329, -0.0083], [-0.0182, -0.1006, 1.1187]])
    img = bpy.data.images.load(scenes.write_image(tmp_path / "c.png", np.array([[[179, 77, 38]]], np.uint8)))
    img.colorspace_settings.name = 'Linear Rec.2020'
    reasons = []
    got = export.images.image_pixels(img, reasons)[0, 0, :3]
    assert not reasons, reasons
    np.testing.assert_allclose(got, rec2020_to_709 @ (np.array([179, 77, 38]) / 255.0), atol=2e-4)


def test_8bit_rgba_in_a_converted_space_is_associated_in_float(tmp_path):
    """An 8-bit RGBA file Cycles must convert (here Linear Rec.2020) is loaded as floats and
    its alpha multiplied in float, then converted: the byte product c * a / 255, truncated as
    Cycles associates sRGB bytes, had darkened low-alpha texels (242, 163, 102, 40): 37 where
    37.96 is the product, ~3% on red, up to 0.18x on a P3 blue)."""
    rec2020_to_709 = np.array([[1.6605, -0.5876, -0.0728], [-0.1246, 1.1329, -0.0083], [-0.0182, -0.1006, 1.1187]])
    texel = np.array([242, 163, 102, 40])
    img = bpy.data.images.load(scenes.write_image(tmp_path / "a.png", texel.astype(np.uint8).reshape(1, 1, 4)))
    img.colorspace_settings.name = 'Linear Rec.2020'
    reasons = []
    got = export.images.image_pixels(img, reasons)[0, 0]
    assert not reasons, reasons
    want = rec2020_to_709 @ (texel[:3] / 255.0 * texel[3] / 255.0)
    np.testing.assert_allclose(got[:3], want, rtol=2e-3)
    assert got[3] == np.float32(40 / 255.0)


@pytest.mark.parametrize('damage', ['deleted', 'cut short'])
def test_a_file_gone_since_blender_loaded_it_is_magenta_and_named(tmp_path, damage):
    """Cycles loads an image's file at the render: deleted or cut short since Blender read its
    pixels, it renders magenta there; the stale buffer had rendered silently. The message
    names the file."""
    path = tmp_path / "gone.png"
    scenes.write_image(path, np.array([[[230, 20, 20]]], np.uint8))
    img = bpy.data.images.load(str(path))
    assert np.allclose(img.pixels[:3], np.array([230, 20, 20]) / 255.0, atol=1e-6) and img.has_data
    if damage == 'deleted':
        path.unlink()
    else:
        path.write_bytes(path.read_bytes()[:30])
    reasons = []
    assert export.images.image_pixels(img, reasons) is None         # the export's magenta
    why = "is missing" if damage == 'deleted' else "could not be read"
    assert reasons == [f"image 'gone.png': its file {path} {why} (magenta, as Cycles)"], reasons
    m = _diffuse_of(img, lambda user: None)
    np.testing.assert_allclose(m.base_color, (1, 0, 1), atol=1e-6)          # magenta, no texture
    assert m.texture is None
    assert f"its file {path} {why}" in m.approximated


def test_a_file_image_is_read_from_its_file_at_each_render(tmp_path):
    """Cycles reads an image that has a file from the file at every render (image_is_builtin
    only for packed, generated and movie images): a PNG rewritten between two renders in one
    process renders as rewritten (it had kept the first render's red, Blender's cached
    buffer); a packed image is read from Blender, as Cycles does."""
    path = tmp_path / "swap.png"
    scenes.write_image(path, np.array([[[230, 20, 20]]], np.uint8))
    img = bpy.data.images.load(str(path))
    first = np.asarray(export.images.image_pixels(img, []))
    assert np.allclose(first[0, 0, :3], srgb_to_linear(np.array([230, 20, 20]) / 255.0), atol=1e-6)
    assert np.allclose(img.pixels[:3], np.array([230, 20, 20]) / 255.0, atol=1e-6)   # Blender's, loaded
    scenes.write_image(path, np.array([[[20, 20, 230]]], np.uint8))
    again = np.asarray(export.images.image_pixels(img, []))
    assert np.allclose(again[0, 0, :3], srgb_to_linear(np.array([20, 20, 230]) / 255.0), atol=1e-6)
    assert np.allclose(img.pixels[:3], np.array([230, 20, 20]) / 255.0, atol=1e-6)   # Blender's still red
    img.pack()
    packed = np.asarray(export.images.image_pixels(img, []))
    assert np.allclose(packed[0, 0, :3], first[0, 0, :3], atol=1e-6)


@pytest.mark.parametrize('use', ['mix', 'principled'])
def test_a_missing_images_alpha_is_opaque_as_cycles_magenta(tmp_path, use):
    """A missing image is Cycles' opaque magenta: its Alpha is 1, so a cut-out Mix Shader gives
    its second shader and a Principled its opaque self; the socket's own value had stood in
    (a leaf half see-through where Cycles' was opaque)."""
    path = tmp_path / "alpha.png"
    scenes.write_image(path, np.array([[[50, 150, 80, 128]]], np.uint8))
    img = bpy.data.images.load(str(path))
    mat, nt, out = scenes._material("Leaf " + use)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = img
    if use == 'mix':
        d, t, mix = (nt.nodes.new(k) for k in ('ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfTransparent',
                                               'ShaderNodeMixShader'))
        nt.links.new(tex.outputs['Alpha'], mix.inputs['Fac'])
        nt.links.new(t.outputs[0], mix.inputs[1])
        nt.links.new(d.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
    else:
        p = nt.nodes.new('ShaderNodeBsdfPrincipled')
        p.inputs['Alpha'].default_value = 0.3
        nt.links.new(tex.outputs['Alpha'], p.inputs['Alpha'])
        nt.links.new(p.outputs[0], out.inputs['Surface'])
    path.unlink()
    builder = export.materials.MaterialBuilder()
    m = builder.materials[builder.index(mat)]
    assert m.transparency is None and m.opacity is None, (m.transparency, m.opacity)
    assert "is missing (magenta, as Cycles)" in m.approximated and "own value" not in m.approximated, m.approximated


def test_a_missing_normal_map_image_tilts_the_surface_as_cycles_magenta(scene, tmp_path):
    """Cycles reads a missing normal map image as magenta, the tangent-space normal (1, -1, 1):
    a plane under an overhead sun is lit at cos = 1 / sqrt(3) (Cycles 0.4411 = 0.8 x 3 / pi /
    sqrt(3)); it had stayed flat (0.7639) under a message saying 'magenta, as Cycles'."""
    import math
    path = tmp_path / "normal.png"
    scenes.write_image(path, np.full((4, 4, 3), (128, 128, 255), np.uint8))
    img = bpy.data.images.load(str(path))
    img.colorspace_settings.name = 'Non-Color'
    mat, nt, out = scenes._material("Bumpy")
    tex, nm, d = (nt.nodes.new(k) for k in ('ShaderNodeTexImage', 'ShaderNodeNormalMap', 'ShaderNodeBsdfDiffuse'))
    tex.image = img
    nt.links.new(tex.outputs['Color'], nm.inputs['Color'])
    nt.links.new(nm.outputs[0], d.inputs['Normal'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.light('SUN', 3.0)
    scenes.black_world()
    scene.dacrt.samples, scene.dacrt.max_bounces, scene.dacrt.filter_type = 4, 0, 'BOX'
    flat = scenes.render_rgba(scene)[4:-4, 4:-4, :3].mean()
    path.unlink()
    tilted = scenes.render_rgba(scene)[4:-4, 4:-4, :3].mean()
    assert flat == pytest.approx(0.8 * 3 / math.pi, rel=5e-3)        # (128/255: all but flat)
    assert tilted / flat == pytest.approx(1 / math.sqrt(3), rel=5e-3)
