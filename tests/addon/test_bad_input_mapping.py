"""A NaN or infinite Mapping node (a script or driver gone wrong) before an Image Texture or an
Environment Texture: Cycles looks the image up at NaN coordinates, gets NaN, and its closures
drop it (the colour black, the alpha opaque; the world black). DACRT's render failed with an
internal message ("texture_transform must be (2, 3) finite", "environment.to_map must be an
orthogonal 3x3 matrix"). Now the image reads black and opaque, the Mapping node is named."""
import bpy
import numpy as np
import pytest

from . import scenes

NAN = float('nan')


def _scene(scene, into, which='Scale', value=(1, 1, 1), pixels=None):
    """A UV-mapped plane whose Principled BSDF takes a checker image (or pixels) through a
    Mapping node (its input `which` set to value) into `into`, sunlit under a grey world."""
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.world((0.2, 0.25, 0.3))
    scenes.light('SUN', 3.0)
    scenes.camera((0, 0, 3))
    mat = bpy.data.materials.new("ImgMat")
    nt = mat.node_tree
    if pixels is None:
        pixels = np.zeros((8, 8, 4), np.float32)
        pixels[..., 3] = 1
        pixels[::2, ::2, 0] = pixels[1::2, 1::2, 1] = 1
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("chk", pixels)
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.inputs[which].default_value = value
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    nt.links.new(mp.outputs[0], tex.inputs['Vector'])
    bsdf = nt.nodes['Principled BSDF']
    nt.links.new(tex.outputs['Color'], bsdf.inputs[into])
    if into == 'Emission Color':
        bsdf.inputs['Emission Strength'].default_value = 2.0
    ob = scenes.plane("Plane", size=4, materials=(mat,))
    ob.data.uv_layers.new(name='UVMap')
    return scenes.render_rgba(scene)


@pytest.mark.parametrize("into", ['Base Color', 'Emission Color'])
@pytest.mark.parametrize("which, value, named", [('Scale', (NAN, 1, 1), "Scale is (nan, 1, 1)"),
                                                ('Location', (0, NAN, 0), "Location is (0, nan, 0)")])
def test_nan_mapping_before_an_image_reads_it_black(scene, said, into, which, value, named):
    """(Blender stores an infinite input as the largest float: no infinity reaches the export.)"""
    img = _scene(scene, into, which, value)   # had failed: "texture_transform must be (2, 3) finite"
    assert any(f"Mapping node 'Mapping' {named}" in t and "image 'chk' reads black" in t for t in said), said
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.render.engine = 'DACRT'
    black = np.zeros((8, 8, 4), np.float32)
    black[..., 3] = 1
    ref = _scene(scene, into, pixels=black)
    assert np.isfinite(img).all() and np.allclose(img, ref, atol=1e-6)


def test_nan_mapping_rotation_before_an_environment_renders_the_world_black(scene, said):
    """Cycles renders the world black there (a tester's frame: 0.340 / 0.315 / 0.315 around a
    sunlit cube)."""
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.camera((0, 0, 3))
    image = scenes.float_image("sky", np.full((4, 8, 4), 0.7, np.float32))
    scenes.environment_world(image, rotation=(NAN, 0, 0))
    img = scenes.render_rgba(scene)
    assert np.all(img[..., :3] == 0.0) and np.all(img[..., 3] == 1.0)
    assert any("Mapping node 'Mapping' Rotation is (nan, 0, 0)" in t and "environment image 'sky'" in t
               and "black" in t for t in said), said


@pytest.mark.parametrize("which, value, named", [('Scale', (1, NAN, 1), "Scale is (1, nan, 1)"),
                                                ('Location', (NAN, 0, 0), "Location is (nan, 0, 0)")])
def test_nan_mapping_scale_or_location_before_an_environment_renders_the_world_black(scene, said, which, value,
                                                                                      named):
    """A NaN Scale had been read as a zero one (ignored) and a NaN Location ignored: the
    environment rendered as if unmapped, where Cycles' directions are NaN and its world black."""
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.camera((0, 0, 3))
    image = scenes.float_image("sky", np.full((4, 8, 4), 0.7, np.float32))
    w = scenes.environment_world(image, rotation=(0, 0, 0))
    next(n for n in w.node_tree.nodes if n.type == 'MAPPING').inputs[which].default_value = value
    img = scenes.render_rgba(scene)
    assert np.all(img[..., :3] == 0.0)
    assert any(f"Mapping node 'Mapping' {named}" in t and "black" in t for t in said), said
