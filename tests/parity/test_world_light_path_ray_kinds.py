"""A world Mix Shader whose factor is a Light Path ray-type output renders per ray kind, as Cycles
evaluates the background (export/world.py RAY_OUTPUTS): camera rays read Is Camera Ray, diffuse
bounces that miss Is Diffuse and Is Reflection Ray, the world's light samples and its importance
map none (PATH_RAY_EMISSION alone), and no world evaluation Is Shadow Ray. Where the world varies
over directions it is one light, sampled by the lighting world's map, and the bounce world takes
that light's MIS weight (emitterhits._gather_bounce_world). A floor and a ball under a Mix of an
orange and a blue Background, an image in one of them, against Cycles per channel mean (1%) and
per pixel and 4x4 block (Welch test over seeds, tests/parity/stats.py).

The factor had been read at its own value 0.5, said ("world Mix Shader factor not computed"):
the Is Diffuse Ray floor 1.75 / 0.81 / 0.55x Cycles per channel, the sky 0.71 / 1.28 / 4.6x."""
import math

import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import stats

pytestmark = pytest.mark.usefixtures('parity_addon')

SEEDS = (1, 2, 3)

CASES = {   # Light Path output, which Background takes the image (None: both constant)
    'diffuse_constant': ('Is Diffuse Ray', None),
    'diffuse_over_image': ('Is Diffuse Ray', 'first'),
    'reflection_image_for_bounces': ('Is Reflection Ray', 'second'),
    'shadow_over_image': ('Is Shadow Ray', 'first'),
    'glossy_in_a_diffuse_scene': ('Is Glossy Ray', None),
}


def _image():
    h, w = 16, 32
    px = np.zeros((h, w, 4), np.float32)
    px[..., 3] = 1.0
    px[..., 0] = np.linspace(0.1, 3.0, w)[None, :]
    px[..., 1] = np.linspace(0.1, 1.0, h)[:, None]
    px[..., 2] = 0.3
    return scenes.float_image("Gradient", px)


def _scene(output, image):
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 30
    scenes.camera(location=(0, -6, 2.0), rotation=(math.radians(75), 0, 0))
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    scenes.uv_sphere("Ball", radius=0.8, location=(0, 0, 0.8), materials=[scenes.diffuse("White", (0.8, 0.8, 0.8))])
    _, nt, out = scenes.world_tree()
    a, b = nt.nodes.new('ShaderNodeBackground'), nt.nodes.new('ShaderNodeBackground')
    a.inputs['Color'].default_value = (1.0, 0.5, 0.2, 1.0)
    b.inputs['Color'].default_value, b.inputs['Strength'].default_value = (0.2, 0.4, 1.0, 1.0), 2.0
    if image is not None:
        env = nt.nodes.new('ShaderNodeTexEnvironment')
        env.image = _image()
        nt.links.new(env.outputs['Color'], (a if image == 'first' else b).inputs['Color'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs[output], mix.inputs['Fac'])
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    sc.cycles.samples = sc.dacrt.samples = 32
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 2
    sc.cycles.sample_clamp_direct = sc.cycles.sample_clamp_indirect = 0.0
    sc.dacrt.sample_clamp_direct = sc.dacrt.sample_clamp_indirect = 0.0
    return sc


@pytest.mark.parametrize('case', sorted(CASES))
def test_world_mixed_by_ray_kind_matches_cycles(case, tmp_path, said):
    sc = _scene(*CASES[case])
    layer = sc.view_layers[0].name
    images = {'CYCLES': [], 'DACRT': []}
    for seed in SEEDS:
        sc.cycles.seed = sc.dacrt.seed = seed
        for engine, exr in scenes.render_engines(sc, tmp_path / str(seed)).items():
            images[engine].append(np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1))
    result = stats.compare(np.stack(images['CYCLES']), np.stack(images['DACRT']))
    assert result.passed, result.summary()
    assert not [t for t in said if "factor not computed" in t], said
    assert not [t for t in said if "read it by their own kind" in t], said
    assert not [t for t in said if "share of the light choice" in t], said     # (the world is its only light)


@pytest.mark.parametrize('image', ['first', None])
def test_bounce_world_beside_other_lights_is_said(image, tmp_path, said):
    """The bounce world takes the MIS weight of the world's light samples, so the light choice's
    share for the world shapes it: said beside a lamp where the world is light-sampled (an image:
    fuzz 1589 1.04-1.09x Cycles beside an emitter), not where it is not (two constant colours:
    no light samples of the world, in Cycles either)."""
    sc = _scene('Is Diffuse Ray', image)
    scenes.light('POINT', 100.0, location=(2.0, -1.0, 3.0))
    sc.dacrt.samples = 1
    sc.render.engine = 'DACRT'
    scenes.render_exr(tmp_path / "lit.exr", sc)
    assert bool([t for t in said if "share of the light choice" in t]) == (image is not None), said


@pytest.mark.parametrize('output, closure, named', [
    ('Is Diffuse Ray', 'ShaderNodeBsdfGlossy', True),       # Cycles' glossy bounce reads Is Diffuse 0
    ('Is Glossy Ray', 'ShaderNodeBsdfGlossy', True),
    ('Is Transmission Ray', 'ShaderNodeBsdfTranslucent', True),
    ('Is Transmission Ray', 'ShaderNodeBsdfGlass', True),
    ('Is Reflection Ray', 'ShaderNodeBsdfGlossy', False),   # a glossy reflection is a reflection
    ('Is Glossy Ray', 'ShaderNodeBsdfDiffuse', False),      # no glossy ray in Cycles either: exact
    ('Is Shadow Ray', 'ShaderNodeBsdfGlass', False),        # no world evaluation is a shadow ray's
])
def test_ray_kinds_diffuse_bounces_stand_for_are_said(output, closure, named):
    """Bounces DACRT renders as diffuse reflections (glossy stand-ins, glass passes, translucent
    transmissions) read other ray types in Cycles: said, naming the material, where the world
    reads one of those types; not where every such bounce reads the world as Cycles does."""
    from addon import export
    import bpy
    _scene(output, None)
    mat, nt, out = scenes._material("Odd")
    nt.links.new(nt.nodes.new(closure).outputs[0], out.inputs['Surface'])
    scenes.cube("Box", size=0.6, location=(1.5, 0, 0.3), materials=[mat])
    messages = [m for _, m in export.export_scene(bpy.context.evaluated_depsgraph_get()).messages
                if "read it by their own kind" in m]
    assert bool(messages) == named, messages
    assert not messages or "'Odd'" in messages[0] and repr(output) in messages[0], messages


@pytest.mark.parametrize('byte_image', [True, False])
def test_colour_beside_an_srgb_image_left_unsampled_is_said(byte_image):
    """A lighting world of an image plus a uniform colour, where diffuse bounces see another: the
    colour is added into a float image's texels (one light, as Cycles samples it), but an 8-bit
    sRGB image is blended before decoding, so the colour stays apart, unsampled: said there only."""
    from addon import export
    import bpy
    sc = _scene('Is Diffuse Ray', 'first')
    nt = sc.world.node_tree
    mix = next(n for n in nt.nodes if n.type == 'MIX_SHADER')
    first = mix.inputs[1].links[0].from_node
    if byte_image:
        img = bpy.data.images.new("Bytes", 32, 16, float_buffer=False, alpha=True)
        px = np.full((16, 32, 4), 0.5, np.float32)
        px[..., 0] = np.linspace(0.1, 1.0, 32)[None, :]
        img.pixels.foreach_set(px.ravel())
        img.pack()
        next(n for n in nt.nodes if n.type == 'TEX_ENVIRONMENT').image = img
    glow = nt.nodes.new('ShaderNodeBackground')
    glow.inputs['Color'].default_value = (0.3, 0.3, 0.3, 1.0)
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(first.outputs[0], add.inputs[0])
    nt.links.new(glow.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], mix.inputs[1])
    messages = [m for _, m in export.export_scene(bpy.context.evaluated_depsgraph_get()).messages
                if "beside an sRGB image" in m]
    assert bool(messages) == byte_image, messages
