"""An emission image whose every channel averages <= 0 while some texels are positive (a float
image of three +0.3 columns and one -1.0 column) still emits each texel's own value, as Cycles
does (its +0.3 texels at 0.300); the material had counted as not emissive, and the render came
out black under 'the scene has no lights, no emissive materials'."""
import numpy as np
import pytest

from . import scenes


@pytest.mark.parametrize('negative', [-1.0, -0.5])
def test_an_emission_image_of_negative_means_emits_its_positive_texels(scene, said, negative):
    px = np.ones((4, 4, 4), np.float32)
    px[..., :3] = 0.3
    px[:, 0, :3] = negative                 # channel means -0.025 (-1.0), +0.1 (-0.5)
    img = scenes.float_image("Screen", px)
    img.colorspace_settings.name = 'Linear Rec.709'
    mat, nt, out = scenes._material("Screen")
    tex, em = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeEmission')
    tex.image, tex.interpolation = img, 'Closest'
    nt.links.new(tex.outputs['Color'], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Screen", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.dacrt.samples, scene.dacrt.max_bounces, scene.dacrt.filter_type = 4, 0, 'BOX'
    rgb = scenes.render_rgba(scene)[..., :3]
    np.testing.assert_allclose(rgb[:, 10:], 0.3, atol=1e-5)          # the +0.3 columns
    np.testing.assert_allclose(rgb[:, :6], negative, atol=1e-5)     # the negative one, as Cycles
    assert not any("no emissive materials" in t for t in said), said
