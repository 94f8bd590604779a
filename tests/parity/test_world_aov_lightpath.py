"""World AOVs fed by Light Path outputs, as Cycles writes them: the world's AOV Output nodes
write where camera rays miss, so a Light Path reads a camera ray's values there (Is Camera Ray
1, the other ray kinds and the depths 0, but Ray Depth 1: the background is evaluated one
bounce further), through Math and Mix nodes. They had been written as
the AOV input's own value (0 where Cycles writes 0.924 on the sky) under a warning that named
no node; what varies over the sky (a texture coordinate) is still read at its own value, and
the warning now names the node and output."""
import math

import bpy
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 1.5), rotation=(math.radians(80), 0, 0), kind='PERSP')
    scenes.plane(size=4, location=(0, 0, 0), materials=[scenes.diffuse("Floor", (0.5, 0.5, 0.5))])
    scenes.world((0.2, 0.3, 0.5), 1.0)
    vl = sc.view_layers[0]
    for name, kind in (('cam', 'VALUE'), ('mix', 'COLOR'), ('math', 'VALUE'), ('gen', 'VALUE')):
        a = vl.aovs.add()
        a.name, a.type = name, kind
    nt = sc.world.node_tree
    lp = nt.nodes.new('ShaderNodeLightPath')

    def aov(name):
        node = nt.nodes.new('ShaderNodeOutputAOV')
        node.aov_name = name
        return node
    nt.links.new(lp.outputs['Is Camera Ray'], aov('cam').inputs['Value'])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type = 'RGBA'
    mix.inputs['A'].default_value = (0.1, 0.2, 0.3, 1.0)
    mix.inputs['B'].default_value = (0.9, 0.6, 0.4, 1.0)
    nt.links.new(lp.outputs['Is Camera Ray'], mix.inputs['Factor'])
    nt.links.new(mix.outputs['Result'], aov('mix').inputs['Color'])
    add = nt.nodes.new('ShaderNodeMath')
    add.operation = 'ADD'
    times = nt.nodes.new('ShaderNodeMath')
    times.operation = 'MULTIPLY'
    times.inputs[1].default_value = 0.25
    nt.links.new(lp.outputs['Is Diffuse Ray'], add.inputs[0])
    nt.links.new(lp.outputs['Ray Depth'], add.inputs[1])
    nt.links.new(add.outputs[0], times.inputs[0])     # 0.25 x (0 + 1) on the sky (Ray Depth 1 there)...
    plus = nt.nodes.new('ShaderNodeMath')
    plus.operation = 'ADD'
    nt.links.new(times.outputs[0], plus.inputs[0])
    nt.links.new(lp.outputs['Is Camera Ray'], plus.inputs[1])   # ... + 1: 1.25
    nt.links.new(plus.outputs[0], aov('math').inputs['Value'])
    coords = nt.nodes.new('ShaderNodeTexCoord')
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    nt.links.new(coords.outputs['Generated'], sep.inputs[0])
    nt.links.new(sep.outputs['Z'], aov('gen').inputs['Value'])
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    return sc


def test_world_aov_light_path_matches_cycles(tmp_path, said):
    """On the pixels that see only the sky, each Light Path AOV's mean within 0.01 of Cycles'
    (they are constants there: 1, the mix's B colour, 1.25: Cycles evaluates the background one
    bounce further, Ray Depth 1); the Generated one is reported by
    node and output."""
    sc = _scene()
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    c, d = out['CYCLES'], out['DACRT']
    sky = c[f'{name}.cam.X'] > 0.999                 # (row 0 at the bottom: the sky is the top)
    assert 0.2 < sky.mean() < 0.8
    for channel, want in (('cam.X', 1.0), ('math.X', 1.25), ('mix.R', 0.9), ('mix.G', 0.6), ('mix.B', 0.4)):
        assert c[f'{name}.{channel}'][sky].mean() == pytest.approx(want, abs=0.01), channel
        assert d[f'{name}.{channel}'][sky].mean() == pytest.approx(want, abs=0.01), channel
    # the whole image, edges included: the same share of sky samples in both
    assert d[f'{name}.cam.X'].mean() == pytest.approx(c[f'{name}.cam.X'].mean(), abs=0.01)
    text = ' '.join(said)
    assert "AOV 'gen' value: 'Texture Coordinate' Generated not evaluated" in text, said
    assert "AOV 'cam'" not in text and "AOV 'math'" not in text and "AOV 'mix'" not in text, said
