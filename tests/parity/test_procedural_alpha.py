"""Cut-outs driven by procedural textures against Cycles: a Mix Shader between a Transparent
BSDF and another shader whose factor a procedural chain computes (a Checker, a Noise through
Greater Than), and a Principled BSDF's Alpha from one (a Gradient on Object coordinates), read
per shading point by camera rays, bounce rays and transparent shadows
(MaterialBuilder._procedural_cutout / _procedural_alpha, the opacity the integrator computes
at each hit).

Before, such a factor or alpha read the texture's own value, reported ("Mix Shader factor from
procedural textures ... not evaluated per point", "Principled alpha driven by nodes; its own
value used"): the whole plate half see-through, or opaque."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering
from .test_procedural_emission import _settings

pytestmark = pytest.mark.usefixtures('parity_addon')


def _render(tmp_path, samples, bounces=1):
    """{engine: (H, W, 4) Combined RGBA}, row 0 at the bottom."""
    _settings(samples, bounces)
    sc = bpy.context.scene
    layer = sc.view_layers[0].name
    return {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], axis=-1)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}


def _cutout_material(name, factor, transparent_first=True, color=(0.9, 0.3, 0.1)):
    """Mix Shader of a Transparent BSDF and an orange Diffuse (in that order unless not
    transparent_first), its factor wired by factor(nt, fac socket, Object coordinates)."""
    mat, nt, out = scenes._material(name)
    dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
    dif.inputs['Color'].default_value = (*color, 1.0)
    tr, mix = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.5             # (what it had read)
    first, second = (tr, dif) if transparent_first else (dif, tr)
    nt.links.new(first.outputs[0], mix.inputs[1])
    nt.links.new(second.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    tc = nt.nodes.new('ShaderNodeTexCoord')
    factor(nt, mix.inputs['Fac'], tc.outputs['Object'])
    return mat


def _checker(nt, fac, coords):
    """A Checker's Fac on Object coordinates, Scale 2: 4 x 4 cells over a 2 x 2 plane."""
    ch = nt.nodes.new('ShaderNodeTexChecker')
    ch.inputs['Scale'].default_value = 2.0
    nt.links.new(coords, ch.inputs['Vector'])
    nt.links.new(ch.outputs['Fac'], fac)


def _noise_greater_than(nt, fac, coords):
    """A Noise's Fac (Scale 3) through Math Greater Than 0.5: crisp blotches."""
    nz = nt.nodes.new('ShaderNodeTexNoise')
    nz.inputs['Scale'].default_value = 3.0
    nz.inputs['Detail'].default_value = 2.0
    gt = nt.nodes.new('ShaderNodeMath')
    gt.operation = 'GREATER_THAN'
    gt.inputs[1].default_value = 0.5
    nt.links.new(coords, nz.inputs['Vector'])
    nt.links.new(nz.outputs['Fac'], gt.inputs[0])
    nt.links.new(gt.outputs[0], fac)


def _sheet_scene(make_material, floor=True):
    """The 2 x 2 sheet of make_material()'s material seen straight down by an orthographic camera that frames it
    (32 x 32 pixels, 8 a cell), over a green floor (or nothing), a sun and a blue world."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.world((0.2, 0.4, 0.9))
    scenes.plane("Sheet", size=2, materials=(make_material(),)).data.uv_layers.new(name="UVMap")
    if floor:
        scenes.plane("Floor", size=8, location=(0, 0, -1), materials=(scenes.diffuse("G", (0.2, 0.8, 0.2)),))
    scenes.light('SUN', 2.0, rotation=(np.radians(20), 0.0, 0.0))
    rendering.fair_scene_settings(sc)
    return sc


def _cells(img):
    """(4, 4, C) the means of each checker cell's inner 4 x 4 pixels."""
    return img.reshape(4, 8, 4, 8, -1)[:, 2:6, :, 2:6].mean(axis=(1, 3))


@pytest.mark.parametrize('transparent_first', [True, False], ids=['transparent_first', 'transparent_second'])
def test_checker_cutout_seen_by_the_camera(tmp_path, said, transparent_first):
    """(a) A sheet cut out by a Checker (Mix with a Transparent BSDF, either order) over a green
    floor under a tilted sun, 512 spp: each cell's mean within 2% of Cycles' (measured 1.2%; the
    opaque cells 0.0%). It had been a uniform half-see-through sheet: the floor's cells 2.8x
    Cycles' red, the orange ones 1.7x its green."""
    _sheet_scene(lambda: _cutout_material("Cut", _checker, transparent_first))
    img = _render(tmp_path, 512)
    d, c = _cells(img['DACRT'][..., :3]), _cells(img['CYCLES'][..., :3])
    np.testing.assert_allclose(d, c, rtol=0.02, atol=2e-3)
    assert np.ptp(c[..., 0]) > 0.3, "the cut-out should show"
    assert not any("not evaluated" in t or "own value" in t for t in said), said


def test_checker_cutout_alpha_with_transparent_film(tmp_path, said):
    """(d) The Checker sheet alone with Film > Transparent: each cell's alpha (1 or 0) and colour
    as Cycles' (within 1%; measured: equal, colours within 1e-5); it had been alpha 0.50
    everywhere."""
    sc = _sheet_scene(lambda: _cutout_material("Cut", _checker), floor=False)
    sc.render.film_transparent = True
    img = _render(tmp_path, 32)
    d, c = _cells(img['DACRT']), _cells(img['CYCLES'])
    np.testing.assert_allclose(d[..., 3], c[..., 3], atol=0.01)
    np.testing.assert_allclose(d[..., :3], c[..., :3], rtol=0.02, atol=2e-3)
    assert c[..., 3].min() < 0.01 and c[..., 3].max() > 0.99
    assert not any("not evaluated" in t or "own value" in t for t in said), said


def test_noise_cutout_shadow_on_the_floor(tmp_path, said):
    """(b) A plate cut out by a Noise through Greater Than, between a sun and the floor and hidden
    from the camera: the floor's mean within 2% of Cycles' (measured 0.15%), 4 x 4 blocks of its
    shadow pattern within 5% of the brightest (1.0%). It had cast a uniform half shadow: the
    mean 0.5% off, blocks 28%."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 6), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    plate = scenes.plane("Plate", size=3, location=(0, 0, 1.0),
                         materials=(_cutout_material("Cut", _noise_greater_than, color=(0.8, 0.8, 0.8)),))
    plate.visible_camera = False
    scenes.plane("Floor", size=8, materials=(scenes.diffuse("G", (0.8, 0.8, 0.8)),))
    scenes.light('SUN', 3.0, rotation=(np.radians(10), 0.0, 0.0))
    rendering.fair_scene_settings(sc)
    img = _render(tmp_path, 64)
    d, c = img['DACRT'][..., :3], img['CYCLES'][..., :3]
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02)
    bd, bc = d.reshape(4, 8, 4, 8, 3).mean((1, 3)), c.reshape(4, 8, 4, 8, 3).mean((1, 3))
    assert np.abs(bd - bc).max() < 0.05 * bc.max(), (bd[..., 0].round(3).tolist(), bc[..., 0].round(3).tolist())
    assert np.ptp(bc[..., 0]) > 0.2 * bc.max(), "the shadow pattern should show"
    assert not any("not evaluated" in t or "own value" in t for t in said), said


def test_principled_alpha_from_gradient_on_object(tmp_path, said):
    """(c) A Principled BSDF whose Alpha is a linear Gradient on the Object coordinates of a
    turned, scaled plane, over a green floor: 4 x 4 blocks within 2% of Cycles' brightest
    (measured 0.3%), the mean within 2% (0.06%). It had read the Alpha's own value (opaque): the
    mean 41% off, blocks 71%."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    mat, nt, out = scenes._material("Fade")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.9, 0.3, 0.1, 1.0)
    p.inputs['Roughness'].default_value = 1.0
    if 'Specular IOR Level' in p.inputs:
        p.inputs['Specular IOR Level'].default_value = 0.0
    tc, g = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexGradient')
    nt.links.new(tc.outputs['Object'], g.inputs['Vector'])
    nt.links.new(g.outputs['Fac'], p.inputs['Alpha'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    sc.render.resolution_x = sc.render.resolution_y = 32
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.world((0.2, 0.4, 0.9))
    sheet = scenes.plane("Sheet", size=1.6, materials=(mat,))
    sheet.rotation_euler = (0.0, 0.0, np.radians(30))
    sheet.scale = (1.2, 1.0, 1.0)
    scenes.plane("Floor", size=8, location=(0, 0, -1), materials=(scenes.diffuse("G", (0.2, 0.8, 0.2)),))
    scenes.light('SUN', 2.0, rotation=(np.radians(20), 0.0, 0.0))
    rendering.fair_scene_settings(sc)
    img = _render(tmp_path, 64)
    d, c = img['DACRT'][..., :3], img['CYCLES'][..., :3]
    bd, bc = d.reshape(4, 8, 4, 8, 3).mean((1, 3)), c.reshape(4, 8, 4, 8, 3).mean((1, 3))
    assert np.abs(bd - bc).max() < 0.02 * bc.max(), (bd[..., 0].round(3).tolist(), bc[..., 0].round(3).tolist())
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02)
    assert not any("not evaluated" in t or "own value" in t for t in said), said


def _voronoi_ramp(nt, fac, coords):
    """A Voronoi's Distance (Scale 4) through a Color Ramp of constant interpolation (black
    below 0.3, white above): round holes with crisp edges."""
    vo = nt.nodes.new('ShaderNodeTexVoronoi')
    vo.inputs['Scale'].default_value = 4.0
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.interpolation = 'CONSTANT'
    ramp.color_ramp.elements[0].color = (0.0, 0.0, 0.0, 1.0)
    ramp.color_ramp.elements[1].position = 0.3
    ramp.color_ramp.elements[1].color = (1.0, 1.0, 1.0, 1.0)
    nt.links.new(coords, vo.inputs['Vector'])
    nt.links.new(vo.outputs['Distance'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], fac)


def test_voronoi_ramp_cutout_of_a_noise_coloured_diffuse(tmp_path, said):
    """(e) Round holes from a Voronoi through a constant Color Ramp, the Transparent BSDF second,
    the other side a Diffuse whose colour is a Noise's: seen over the green floor, 4 x 4 blocks
    within 2% of Cycles' brightest (measured 0.4%), the mean within 2% (0.16%), each pixel as
    Cycles' (edges as crisp). It had been a uniform mix (blocks 37%, the mean 47% off, pixels
    0.16 off on average)."""
    def material():
        mat = _cutout_material("Holes", _voronoi_ramp, transparent_first=False)
        nt = mat.node_tree
        dif = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
        nz = nt.nodes.new('ShaderNodeTexNoise')
        nz.inputs['Scale'].default_value = 2.0
        nt.links.new(next(n for n in nt.nodes if n.type == 'TEX_COORD').outputs['Object'], nz.inputs['Vector'])
        nt.links.new(nz.outputs['Color'], dif.inputs['Color'])
        return mat
    _sheet_scene(material)
    img = _render(tmp_path, 128)
    d, c = img['DACRT'][..., :3], img['CYCLES'][..., :3]
    bd, bc = d.reshape(4, 8, 4, 8, 3).mean((1, 3)), c.reshape(4, 8, 4, 8, 3).mean((1, 3))
    # crisp edges where Cycles' are: pixel by pixel (measured: mean 0.0035, the largest 0.045, 128 spp)
    assert np.abs(d - c).mean() < 0.01 and np.abs(d - c).max() < 0.15, (np.abs(d - c).mean(), np.abs(d - c).max())
    assert np.abs(bd - bc).max() < 0.02 * bc.max(), (bd[..., 1].round(3).tolist(), bc[..., 1].round(3).tolist())
    np.testing.assert_allclose(d.mean((0, 1)), c.mean((0, 1)), rtol=0.02)
    assert not any("not evaluated" in t or "own value" in t for t in said), said


@pytest.mark.parametrize('principled', [False, True], ids=['mix_shader', 'principled_alpha'])
def test_image_alpha_times_checker_cutout(tmp_path, said, principled):
    """(f) A cut-out factor (or a Principled Alpha) that an image's Alpha (opaque on the sheet's
    left half, clear on its right; 'Closest') times a Checker computes: each cell within 2% of
    Cycles' (measured 1.0%; the image looked up per point beside the procedural). It had been
    evaluated per texel with the Checker at its own value, 0.5 over the left half (a channel of
    a cell up to 9x Cycles')."""
    px = np.zeros((2, 2, 4), np.uint8)
    px[..., :3] = 255
    px[:, 0, 3] = 255
    path = scenes.write_image(tmp_path / "half.png", px)

    def material():
        def factor(nt, fac, coords):
            tex = nt.nodes.new('ShaderNodeTexImage')
            tex.image, tex.interpolation = bpy.data.images.load(path), 'Closest'
            mul = nt.nodes.new('ShaderNodeMath')
            mul.operation = 'MULTIPLY'
            nt.links.new(tex.outputs['Alpha'], mul.inputs[0])
            _checker(nt, mul.inputs[1], coords)
            nt.links.new(mul.outputs[0], fac)
        mat = _cutout_material("Cut", factor)
        if principled:
            nt = mat.node_tree
            mix = next(n for n in nt.nodes if n.type == 'MIX_SHADER')
            p = nt.nodes.new('ShaderNodeBsdfPrincipled')
            p.inputs['Base Color'].default_value = (0.9, 0.3, 0.1, 1.0)
            p.inputs['Roughness'].default_value = 1.0
            p.inputs['Specular IOR Level'].default_value = 0.0
            nt.links.new(mix.inputs['Fac'].links[0].from_socket, p.inputs['Alpha'])
            out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
            nt.links.new(p.outputs[0], out.inputs['Surface'])
        return mat
    _sheet_scene(material)
    img = _render(tmp_path, 512)
    d, c = _cells(img['DACRT'][..., :3]), _cells(img['CYCLES'][..., :3])
    np.testing.assert_allclose(d, c, rtol=0.02, atol=2e-3)
    assert not any("not evaluated" in t or "own value" in t for t in said), said
