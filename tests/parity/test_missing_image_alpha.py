"""A missing image (an Image Texture without one, a file that is gone, a sequence frame with no
file) is Cycles' opaque magenta: its Color is (1, 0, 1), its Alpha 1. The evaluation had read
the Alpha output as magenta too (a mask or factor from a broken texture path became magenta's
luminance, 0.285, or magenta itself) under a message saying "magenta, as Cycles". A plane lit
by a sun of strength pi with direct light only (radiance = albedo), seen square by an
orthographic camera; the Alpha read as a colour, a Mix factor, through a Math node into an
Emission's strength, and into an AOV."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _no_image(tmp_path):
    return None


def _missing_file(tmp_path):
    img = bpy.data.images.new("Gone", 4, 4)
    img.source = 'FILE'
    img.filepath = str(tmp_path / "does_not_exist.png")
    return img


def _missing_frame(tmp_path):
    for f in (1, 2, 4):
        scenes.write_image(tmp_path / f"seq.{f:04d}.png", np.full((2, 2, 3), 120, np.uint8))
    img = bpy.data.images.load(str(tmp_path / "seq.0001.png"))
    img.source = 'SEQUENCE'
    bpy.context.scene.frame_set(3)          # seq.0003.png is not there
    return img


def _as_color(nt, alpha, shader):
    nt.links.new(alpha, shader.inputs['Color'])


def _as_factor(nt, alpha, shader):
    m = scenes.mix_node(nt, 'MIX', (0.9, 0.1, 0.1), (0.2, 0.6, 0.3), 0.5)
    nt.links.new(alpha, m.inputs['Factor'])
    nt.links.new(m.outputs['Result'], shader.inputs['Color'])


def _as_strength(nt, alpha, shader):
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Color'].default_value = (0.3, 0.5, 0.7, 1.0)
    m = nt.nodes.new('ShaderNodeMath')
    m.operation, m.inputs[1].default_value = 'MULTIPLY', 0.5
    nt.links.new(alpha, m.inputs[0])
    nt.links.new(m.outputs[0], e.inputs['Strength'])
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(shader.outputs[0], add.inputs[0])
    nt.links.new(e.outputs[0], add.inputs[1])
    return add


@pytest.mark.parametrize("source", [_no_image, _missing_file, _missing_frame], ids=lambda f: f.__name__[1:])
@pytest.mark.parametrize("use", [_as_color, _as_factor, _as_strength], ids=lambda f: f.__name__[4:])
def test_a_missing_images_alpha_is_one_as_in_cycles(tmp_path, source, use, said):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 8
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.light('SUN', math.pi)
    scenes.black_world()
    mat, nt, out = scenes._material("Broken")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.05, 0.05, 0.05, 1.0)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = source(tmp_path)
    if tex.image is not None and tex.image.source == 'SEQUENCE':
        tex.image_user.frame_start, tex.image_user.frame_duration = 1, 4
    surface = use(nt, tex.outputs['Alpha'], d) or d
    nt.links.new(surface.outputs[0], out.inputs['Surface'])
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'mask'
    nt.links.new(tex.outputs['Alpha'], aov.inputs['Value'])
    a = sc.view_layers[0].aovs.add()
    a.name, a.type = 'mask', 'VALUE'
    scenes.plane("P", size=2, materials=(mat,)).data.uv_layers.new(name='UVMap')
    rendering.matched(sc, 4)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        got[engine] = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc, multilayer=True))
    c, d = got['CYCLES'], got['DACRT']
    for ch in ('R', 'G', 'B'):
        key = f"ViewLayer.Combined.{ch}"
        # a flat albedo under a sun, direct light only: the same to float rounding
        assert abs(float(d[key].mean()) - float(c[key].mean())) < 1e-3, (key, d[key].mean(), c[key].mean())
    assert abs(float(d["ViewLayer.mask.X"].mean()) - 1.0) < 1e-6, d["ViewLayer.mask.X"].mean()
    # the message names the missing image, which is what Cycles renders (magenta, opaque)
    assert any("(magenta, as Cycles)" in t for t in said), said
