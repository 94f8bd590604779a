"""Emitters with Ray Visibility > Shadow off but Diffuse on: their light samples pass through
their own faces, where bounce rays stop, so what they light only that way (an emitting inner
shell behind the bounce-visible outer one of a Solidified emissive cube) weighs what MIS gives
it: the image depends on the light-selection pdf. Cycles' light tree picks each emissive
triangle apart, DACRT's the object and then its triangles by power, which is what Cycles gives
with its Light Tree off (the Solidified cube over a floor, 0 bounces: Cycles 0.3215 with the
tree, 0.3489 without, DACRT 0.3470 either way; a sphere of Front-sampled emissive faces 1.24x).
That was silent; it is said, naming the objects, where it can change the image: light-sampled
emissive triangles with Shadow off, the Light Tree on (DACRT's setting, copied from Cycles')."""
import math

import bpy
import pytest

from tests.parity import rendering

from . import scenes

SAID = "have Ray Visibility > Shadow off"


def _scene(sc, shadow=False, diffuse=True, sampling='AUTO', strength=3.0, tree=True):
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    scenes.plane(size=8, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    m = scenes.emission('lamp', (1.0, 1.0, 1.0), strength)
    m.cycles.emission_sampling = sampling
    cube = scenes.cube('Shell', size=1.0, location=(0, 0, 0.6), materials=[m])
    cube.modifiers.new('s', 'SOLIDIFY').thickness = 0.05
    cube.visible_shadow, cube.visible_diffuse = shadow, diffuse
    # a shadowless reflector beside it: not an emitter, nothing to say
    ob = scenes.cube('Box', size=0.5, location=(1.5, 0, 0.25), materials=[scenes.diffuse('d', (0.5, 0.5, 0.5))])
    ob.visible_shadow = False
    scenes.black_world()
    rendering.matched(sc, 1, bounces=0)
    sc.dacrt.use_light_tree = tree


def _said(sc, said):
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if SAID in t]


def test_said_once_naming_the_emitter(scene, said):
    _scene(scene)
    got = _said(scene, said)
    assert len(got) == 1 and got[0].startswith("emitter(s) 'Shell' have"), got
    assert "as Cycles does with its Light Tree off" in got[0]


@pytest.mark.parametrize('case', ['shadow_on', 'diffuse_off', 'sampling_none', 'tree_off', 'dark'])
def test_not_said_where_the_image_cannot_change(scene, said, case):
    _scene(scene, shadow=case == 'shadow_on', diffuse=case != 'diffuse_off',
           sampling='NONE' if case == 'sampling_none' else 'AUTO', tree=case != 'tree_off',
           strength=0.0 if case == 'dark' else 3.0)
    assert not _said(scene, said)


def test_front_sampled_faces_said(scene, said):
    # per-face Front sampling (the fuzzer's seed 845: 1.24x Cycles) is light-sampled too
    _scene(scene, sampling='FRONT')
    assert len(_said(scene, said)) == 1


def test_emitter_tinting_its_own_shadow_rays_is_not_shadowless(scene, said):
    """An emitter whose shader gives shadow rays a tinted Transparent BSDF (Mix by Light Path
    Is Shadow Ray) is built per ray kind (export/rayvariants.py): its emitting faces are seen by
    bounce rays and a copy of them by shadow rays, so its light samples are stopped or dimmed by
    its faces as in Cycles; its Shadow visibility is on, and nothing is said of it."""
    _scene(scene, shadow=True)
    m = bpy.data.materials['lamp']
    nt = m.node_tree
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL')
    e = next(n for n in nt.nodes if n.type == 'EMISSION')
    mix, t = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeBsdfTransparent')
    t.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1.0)
    nt.links.new(e.outputs[0], mix.inputs[1])
    nt.links.new(t.outputs[0], mix.inputs[2])
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Shadow Ray'], mix.inputs['Fac'])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    assert not any(SAID in t for t in _said(scene, said)), said
