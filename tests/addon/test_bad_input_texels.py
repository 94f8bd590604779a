"""An infinite texel in a float image on a diffuse colour: Cycles renders it as it renders a
NaN one (lookups blending it give inf or NaN, which its film drops: black there). DACRT read
a NaN texel so, but kept +inf (fmax(inf, 0)), so paths through it turned infinite and whole
samples were dropped ("6302 sample(s) had NaN or infinite channels", naming no image): a
tester's cube 0.3415 / 0.3723 / 0.4031 against Cycles' 0.3467 / 0.3775 / 0.4084."""
import bpy
import numpy as np

from . import scenes


def _render(scene, value, tmp_path, channels=slice(0, 3)):
    """A UV-mapped plane filling an orthographic view, its Diffuse colour a 4x4 float image of
    0.5 with texel 5's channels (R, G, B by default) set to value, sunlit under a grey world."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.render.engine = 'DACRT'
    scene.render.resolution_x, scene.render.resolution_y = 16, 16
    scene.dacrt.samples = 4
    scenes.world((0.2, 0.25, 0.3))
    scenes.light('SUN', 3.0)
    scenes.camera((0, 0, 3), kind='ORTHO', ortho_scale=2.0)
    px = np.full((4, 4, 4), 0.5, np.float32)
    px[..., 3] = 1
    px[1, 1, channels] = value
    mat, nt, out = scenes._material("ImgMat")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("tex", px)
    nt.links.new(tex.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob = scenes.plane("Plane", size=2, materials=(mat,))
    uv = ob.data.uv_layers.new(name='UVMap')
    uv.data.foreach_set('uv', np.array([(0, 0), (1, 0), (1, 1), (0, 1)], np.float32).ravel())
    return scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{value}{channels}.exr", scene)))


def test_infinite_texel_renders_as_a_nan_one(scene, tmp_path, said):
    nan = _render(scene, float('nan'), tmp_path)
    n_nan = len(said)
    inf = _render(scene, float('inf'), tmp_path)
    assert np.isfinite(inf).all() and np.array_equal(inf, nan)
    # black where the lookups blend the texel in, the rest as the image's 0.5
    assert (inf[..., :3].sum(-1) == 0).any() and (inf[..., 0] > 0.3).mean() > 0.5
    for texts in (said[:n_nan], said[n_nan:]):
        assert any("image 'tex': 1 texel(s) NaN or infinite" in t for t in texts), texts
        assert not any("sample(s) had NaN or infinite channels" in t for t in texts), texts


def test_texel_with_some_channels_non_finite_is_not_said_to_render_as_cycles(scene, tmp_path, said):
    """Only B (or only the alpha) infinite: DACRT reads that channel as 0 and keeps the others,
    while Cycles drops the light samples of points blending the texel in (under a sun 0 against
    DACRT's 0.477 in R and G): the message had claimed "black there, as in Cycles" for these
    too. It now says what is kept and that Cycles is darker there."""
    for channels in (slice(2, 3), slice(3, 4)):
        n = len(said)
        img = _render(scene, float('inf'), tmp_path, channels)
        texts = said[n:]
        assert np.isfinite(img).all()
        assert any("image 'tex': 1 texel(s) with some channels or the alpha NaN or infinite" in t
                   and "darker there in Cycles" in t for t in texts), texts
        assert not any("as in Cycles" in t and "image 'tex'" in t for t in texts), texts
