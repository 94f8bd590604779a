"""Cycles' Light Paths > Caustics settings, which DACRT does not apply, are said where they change
what Cycles renders of the scene's materials (settings.cycles_glossy_messages): Filter Glossy
where a glossy layer of roughness below 0.71 is rendered (Cycles blurs it past a diffuse bounce:
an 8-bounce room of Principled walls at roughness 0.1 had rendered 1.17x Cycles without a word,
tests/parity/test_principled_room.py), Reflective / Refractive Caustics off where a glossy
reflection / a glass or transmission is rendered, and glass that shadow rays cross clear (the
archviz Is Shadow Ray -> Transparent trick, or Shadow visibility off) under Refractive Caustics,
which Cycles counts twice or more (a window room 0.53x, 1.25x with Refractive Caustics off). None
of them at 0 bounces or where no such material is rendered. DACRT only, 1 sample at 32x24."""
import math

import bpy

import pytest

from . import scenes

FILTER = "Filter Glossy"
REFLECTIVE = "Caustics > Reflective is off"
REFRACTIVE = "Caustics > Refractive is off"
TWICE = "counting that light twice or more"


def _glass(name, roughness=0.0):
    m, nt, out = scenes._material(name)
    g = nt.nodes.new('ShaderNodeBsdfGlass')
    g.inputs['Roughness'].default_value = roughness
    nt.links.new(g.outputs[0], out.inputs['Surface'])
    return m, g


def _shadow_trick(name):
    m, g = _glass(name)
    nt = m.node_tree
    t, lp, mx = (nt.nodes.new(k) for k in ('ShaderNodeBsdfTransparent', 'ShaderNodeLightPath', 'ShaderNodeMixShader'))
    nt.links.new(lp.outputs['Is Shadow Ray'], mx.inputs[0])
    nt.links.new(g.outputs[0], mx.inputs[1])
    nt.links.new(t.outputs[0], mx.inputs[2])
    nt.links.new(mx.outputs[0], next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL').inputs['Surface'])
    return m


def _scene(sc, pane=None, floor=None, bounces=8):
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(58), 0, 0))
    scenes.plane("Floor", size=12, materials=[floor or scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    if pane is not None:
        scenes.cube("Pane", size=1.0, location=(0, 0, 1), materials=[pane])
    scenes.light('SUN', 3.0, rotation=(math.radians(30), 0, 0))
    sc.dacrt.samples = 1
    sc.dacrt.max_bounces = bounces


def _said(said, *keys):
    said.clear()
    bpy.ops.render.render()
    return {k: [t for t in said if k in t] for k in keys}


def test_filter_glossy_said_for_sharp_glossy_layers(scene, said):
    rough = scenes.principled("Rough", (0.8, 0.8, 0.8), specular=0.5)
    rough.node_tree.nodes['Principled BSDF'].inputs['Roughness'].default_value = 0.9
    _scene(scene, floor=rough)
    assert scene.cycles.blur_glossy == 1.0          # Cycles' default
    assert not _said(said, FILTER)[FILTER]   # roughness 0.9: Cycles never blurs it
    rough.node_tree.nodes['Principled BSDF'].inputs['Roughness'].default_value = 0.5
    got = _said(said, FILTER)[FILTER]
    assert len(got) == 1 and "1.17x" in got[0], got
    scene.cycles.blur_glossy = 0.0
    assert not _said(said, FILTER)[FILTER]
    scene.cycles.blur_glossy = 1.0
    scene.dacrt.max_bounces = 0                      # no bounce: nothing blurred
    assert not _said(said, FILTER)[FILTER]


def test_filter_glossy_said_for_objects_without_material(scene, said):
    # Blender's default surface is a Principled of roughness 0.5
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(58), 0, 0))
    scenes.plane("Floor", size=12)
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 1
    assert _said(said, FILTER)[FILTER]


def test_caustics_toggles_said_where_they_matter(scene, said):
    _scene(scene)                                    # diffuse only
    scene.cycles.caustics_reflective = scene.cycles.caustics_refractive = False
    got = _said(said, FILTER, REFLECTIVE, REFRACTIVE, TWICE)
    assert not any(got.values()), got
    m, _ = _glass("Pane", roughness=0.8)
    scenes.cube("Pane", size=1.0, location=(0, 0, 1), materials=[m])
    got = _said(said, FILTER, REFLECTIVE, REFRACTIVE, TWICE)
    assert got[REFLECTIVE] and got[REFRACTIVE] and not got[TWICE] and not got[FILTER], got
    scene.cycles.caustics_reflective = True
    got = _said(said, REFLECTIVE, REFRACTIVE)
    assert not got[REFLECTIVE] and got[REFRACTIVE], got
    scene.cycles.caustics_refractive = True
    got = _said(said, REFLECTIVE, REFRACTIVE, TWICE)
    assert not any(got.values()), got               # plain glass under caustics: the glass's own warning


@pytest.mark.parametrize('how', ['is_shadow_ray', 'shadow_visibility'])
def test_glass_crossed_clear_by_shadow_rays(scene, said, how):
    if how == 'is_shadow_ray':
        _scene(scene, pane=_shadow_trick("Trick"))
    else:
        m, _ = _glass("Glass")
        _scene(scene, pane=m)
        scene.objects['Pane'].visible_shadow = False
    got = _said(said, TWICE, REFRACTIVE)
    assert len(got[TWICE]) == 1 and "0.53x" in got[TWICE][0] and not got[REFRACTIVE], got
    scene.cycles.caustics_refractive = False
    got = _said(said, TWICE, REFRACTIVE)
    assert not got[TWICE] and len(got[REFRACTIVE]) == 1 and "1.25x" in got[REFRACTIVE][0], got
    scene.dacrt.max_bounces = 0
    got = _said(said, TWICE, REFRACTIVE)
    assert not any(got.values()), got
