"""A world Mix Shader's factor read from an Image Texture (export/worldmix.factor_images) reads the
image exactly as a material does (imagetextures.image_texture, one function for both): its world
copy had unassociated by the Alpha output's raw link (not by what Cycles' constant folding leaves),
said nothing of NaN texels."""
import numpy as np

from . import scenes


def _factor_world(scene, pixels, alpha_to=None, mapping_scale=None):
    """A Mix Shader of a red and a blue Background whose factor is an Image Texture's Color on
    Generated coordinates; the Alpha output linked to alpha_to ('dangling': a Math node feeding
    nothing; 'used': a Math Maximum with the colour, feeding the factor); a Mapping of
    mapping_scale between them when given."""
    scenes.camera()
    w, nt, out = scenes.world_tree(scene)
    red, blue = nt.nodes.new('ShaderNodeBackground'), nt.nodes.new('ShaderNodeBackground')
    red.inputs['Color'].default_value = (1.0, 0.0, 0.0, 1.0)
    blue.inputs['Color'].default_value = (0.0, 0.0, 1.0, 1.0)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Fac", pixels)
    coords = nt.nodes.new('ShaderNodeTexCoord').outputs['Generated']
    if mapping_scale is not None:
        mapping = nt.nodes.new('ShaderNodeMapping')
        mapping.inputs['Scale'].default_value = mapping_scale
        nt.links.new(coords, mapping.inputs['Vector'])
        coords = mapping.outputs['Vector']
    nt.links.new(coords, tex.inputs['Vector'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    fac = tex.outputs['Color']
    if alpha_to is not None:
        math = nt.nodes.new('ShaderNodeMath')
        math.operation = 'MAXIMUM'
        nt.links.new(tex.outputs['Alpha'], math.inputs[0])
        if alpha_to == 'used':
            bw = nt.nodes.new('ShaderNodeRGBToBW')
            nt.links.new(tex.outputs['Color'], bw.inputs[0])
            nt.links.new(bw.outputs[0], math.inputs[1])
            fac = math.outputs[0]
    nt.links.new(fac, mix.inputs['Fac'])
    nt.links.new(red.outputs[0], mix.inputs[1])
    nt.links.new(blue.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])


def _pixels(alpha=1.0):
    px = np.zeros((8, 16, 4), np.float32)
    px[..., :3] = np.linspace(0.05, 0.45, 16)[None, :, None]
    px[..., 3] = alpha
    return px


def _baked(data):
    assert data.environment is not None, (data.world, data.messages)
    assert any("baked into a" in t for _, t in data.messages), data.messages
    return data.environment.pixels


def test_an_alpha_linked_to_nothing_used_leaves_the_colour_associated(scene, exported):
    """Cycles removes a node feeding nothing before it asks whether Alpha is used: the colour of
    an associated image stays associated, as with the Alpha unlinked (it had been divided by alpha)."""
    _factor_world(scene, _pixels(alpha=0.5))
    plain = _baked(exported())
    _factor_world(scene, _pixels(alpha=0.5), alpha_to='dangling')
    dangling = _baked(exported())
    np.testing.assert_array_equal(dangling, plain)
    _factor_world(scene, _pixels(alpha=0.5), alpha_to='used')      # (the Alpha read: unassociated)
    assert not np.array_equal(_baked(exported()), plain)


def test_nan_texels_of_a_factor_image_are_said(scene, exported):
    px = _pixels()
    px[2, 3, :3] = np.nan
    _factor_world(scene, px)
    data = exported()
    _baked(data)
    assert any("image 'Fac': 1 texel(s) NaN or infinite" in t for _, t in data.messages), data.messages


def test_a_nan_mapping_reads_the_factor_image_black(scene, exported):
    """A NaN Mapping scale: Cycles' lookups are NaN, read as a black texel (factor 0: the first
    side, red, everywhere), as a material reads it (held before too: the factor's coordinates and
    Mapping are computed per direction, procedurals' per-point path, as a material's are)."""
    _factor_world(scene, _pixels(), mapping_scale=(float('nan'), 1.0, 1.0))
    data = exported()
    px = _baked(data).reshape(-1, 3)
    np.testing.assert_allclose(px, np.broadcast_to([1.0, 0.0, 0.0], px.shape), atol=1e-6)
    assert any("Mapping node 'Mapping' Scale is (nan, 1, 1)" in t for _, t in data.messages), data.messages
