"""Light linking agrees with Cycles: an emitter's receiver collection decides which objects it
lights (with any object included, only those; else all but the excluded), for an area light
and for an emissive mesh, directly (three planes, no bounce) and with bounces (the Cornell
box's light kept off the back wall and the tall block: their bounced light changes too).
A renderer ignoring the links fails each case by far more than the tolerances."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _link(emitter, states, children=None):
    """Give emitter a receiver collection of the named objects in their states, and child
    collections {name: (state, object names)}."""
    coll = bpy.data.collections.new(f"{emitter.name}Receivers")
    for name in states:
        coll.objects.link(bpy.data.objects[name])
    for ob, item in zip(coll.objects, coll.collection_objects):
        item.light_linking.link_state = states[ob.name]
    for cname, (state, names) in (children or {}).items():
        child = bpy.data.collections.new(cname)
        coll.children.link(child)
        for name in names:
            child.objects.link(bpy.data.objects[name])
        coll.collection_children[-1].light_linking.link_state = state
    emitter.light_linking.receiver_collection = coll


def _planes(emissive):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 30, 10
    scenes.camera(location=(0, 0, 10), kind='ORTHO', ortho_scale=6.0)
    for name, x in (("A", -2), ("B", 0), ("C", 2)):
        scenes.plane(name, size=1.8, location=(x, 0, 0), materials=[scenes.diffuse(name, (0.8, 0.8, 0.8))])
    if emissive:
        emitter = scenes.plane("Glow", size=6, location=(0, 0, 3),
                               materials=[scenes.emission("Glow", (1, 1, 1), 3.0)])
        emitter.rotation_euler = (np.pi, 0, 0)           # emitting side down
        emitter.visible_camera = False
    else:
        emitter = scenes.light('AREA', 30.0, (0, 0, 3), size=2.0)
    _direct_light(sc, 128)
    return sc, emitter


def _direct_light(sc, samples):
    """Both engines at `samples`, no bounce (direct light only), no denoising."""
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.use_denoising = False


def _means(sc, engine, tmp_path, rows, half, cols=(5, 15, 25)):
    """The mean RGB of the 30 x 10 render's windows (rows, cols +- half), by `engine`."""
    sc.render.engine = engine
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(str(tmp_path / f"{engine}.exr"))))
    return np.array([img[rows, c - half:c + half, :3].mean(axis=(0, 1)) for c in cols])


def _plane_means(sc, engine, tmp_path):
    return _means(sc, engine, tmp_path, slice(2, 8), 3)[:, 0]


@pytest.mark.parametrize('emissive', [False, True])
@pytest.mark.parametrize('states,children,lit', [
    ({"A": 'INCLUDE'}, None, (True, False, False)),
    ({"A": 'EXCLUDE'}, None, (False, True, True)),
    ({"A": 'INCLUDE', "B": 'EXCLUDE'}, None, (True, False, False)),
    ({}, {"Pair": ('INCLUDE', ("B", "C"))}, (False, True, True)),       # a child collection's state
])
def test_receiver_collection_lights_the_linked_planes(emissive, states, children, lit, tmp_path):
    sc, emitter = _planes(emissive)
    _link(emitter, states, children)
    c, d = _plane_means(sc, 'CYCLES', tmp_path), _plane_means(sc, 'DACRT', tmp_path)
    assert np.array_equal(c > 0.01, np.array(lit)), c                  # what the links mean in Cycles
    assert np.all(np.abs(d - c) <= 0.02 * np.maximum(c, 0.05)), (d, c)


def test_light_linking_with_bounces_matches_cycles(tmp_path):
    """The Cornell box's area light excluded from the back wall and the tall block, 4 bounces:
    those surfaces get only bounced light, and what they would have bounced is missing."""
    means = {}
    for linked in (False, True):
        sc = rendering.small_cornell()
        if linked:
            _link(bpy.data.objects["CeilingLight"], {"Back": 'EXCLUDE', "TallBlock": 'EXCLUDE'})
        for engine, m in rendering.engine_means(sc, tmp_path, linked).items():
            means[engine, linked] = m
    ratio = means['DACRT', True] / means['CYCLES', True]
    assert np.all(np.abs(ratio - 1) < 0.01), ratio
    assert np.all(means['CYCLES', True] < 0.9 * means['CYCLES', False])    # the links matter here


def _blockers(emitter_kind, tinted):
    """A floor under two raised plates B (left) and C (right), hidden from the camera, lit from
    above by a sun or an area light; with tinted, C is a tinted transparent sheet."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 30, 10
    scenes.camera(location=(0, 0, 10), kind='ORTHO', ortho_scale=6.0)
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Floor", (0.8, 0.8, 0.8))])
    for name, x in (("B", -1.5), ("C", 1.5)):
        mat = scenes.diffuse(name, (0.8, 0.8, 0.8))
        if tinted and name == "C":
            mat, nt, out = scenes._material(name)
            clear = nt.nodes.new('ShaderNodeBsdfTransparent')
            clear.inputs['Color'].default_value = (0.9, 0.4, 0.2, 1.0)
            nt.links.new(clear.outputs['BSDF'], out.inputs['Surface'])
        scenes.plane(name, size=1.5, location=(x, 0, 1), materials=[mat]).visible_camera = False
    emitter = scenes.light('SUN', 3.0) if emitter_kind == 'SUN' else scenes.light('AREA', 40.0, (0, 0, 4), size=1.0)
    _direct_light(sc, 64)
    return sc, emitter


def _floor_means(sc, engine, tmp_path):
    return _means(sc, engine, tmp_path, slice(3, 7), 2, (7, 15, 22))


@pytest.mark.parametrize('emitter_kind,tinted', [('SUN', False), ('AREA', True)])
@pytest.mark.parametrize('states', [{"B": 'INCLUDE'}, {"B": 'EXCLUDE'}, {"C": 'INCLUDE'}])
def test_blocker_collection_decides_the_shadows(emitter_kind, tinted, states, tmp_path):
    """Shadow linking: with any blocker included only those cast the emitter's shadows, else
    all but the excluded; a transparent blocker tints them (Cycles' transparent shadows)."""
    sc, emitter = _blockers(emitter_kind, tinted)
    plain_c = _floor_means(sc, 'CYCLES', tmp_path)
    coll = bpy.data.collections.new("Blockers")
    for name in states:
        coll.objects.link(bpy.data.objects[name])
    for ob, item in zip(coll.objects, coll.collection_objects):
        item.light_linking.link_state = states[ob.name]
    emitter.light_linking.blocker_collection = coll
    c, d = _floor_means(sc, 'CYCLES', tmp_path), _floor_means(sc, 'DACRT', tmp_path)
    assert np.abs(c - plain_c).max() > 0.05, "the blockers must change the shadows"
    assert np.all(np.abs(d - c) <= 0.02 * np.maximum(c, 0.05)), (d, c)
