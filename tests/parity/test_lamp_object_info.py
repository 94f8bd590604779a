"""Object Info in a lamp's node tree agrees with Cycles, which evaluates it for the light object
(lights are objects there): Random, Location, Alpha, Object Index into the Emission Strength,
Color into the Emission Color, on several lamps and on a lamp instanced by two collection
instances (each instance's random id and its instancer's colour, as a mesh instance's).

Suns straight down on a diffuse floor, seen from above, direct light only; each lamp emits in
one channel, so each channel's mean is one lamp's. Before, Object Info stood at the own value of
the input it feeds (reported): Random x 10 was 0.70x Cycles (5 where Cycles has 7.2), Color grey."""


import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

RED, GREEN, BLUE = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def _math(nt, op, a, b):
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = op
    nt.links.new(a, m.inputs[0])
    m.inputs[1].default_value = b
    return m.outputs[0]


def _sun(name, emission=(1.0, 1.0, 1.0), strength=None, color=None, collection=None,
         location=(0.0, 0.0, 3.0)):
    """A 1 W/m^2 sun straight down; its Emission's Strength from strength(nt, Object Info node)
    and Color from color(nt, node) (None: the Emission's own, `emission`)."""
    data = bpy.data.lights.new(name, 'SUN')
    data.energy, data.angle = 1.0, 0.0
    ob = bpy.data.objects.new(name, data)
    (collection or bpy.context.scene.collection).objects.link(ob)
    ob.location = location
    data.use_nodes = True
    nt = data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    em.inputs['Color'].default_value = (*emission, 1.0)
    info = nt.nodes.new('ShaderNodeObjectInfo')
    if strength is not None:
        nt.links.new(strength(nt, info), em.inputs['Strength'])
    if color is not None:
        nt.links.new(color(nt, info), em.inputs['Color'])
    return ob


def _render(tmp_path, said):
    """Both engines' mean RGB of the floor (the DACRT run's reports in `said` afterwards)."""
    sc = bpy.context.scene
    scenes.plane("Floor", size=20, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=4.0)
    scenes.black_world()
    sc.render.resolution_x = sc.render.resolution_y = 24
    c = sc.cycles
    c.device = 'CPU'
    c.use_denoising = c.use_adaptive_sampling = False
    c.samples = sc.dacrt.samples = 128
    c.max_bounces = sc.dacrt.max_bounces = 0
    c.light_sampling_threshold = 0.0
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))
        means[engine] = img[..., :3].reshape(-1, 3).mean(0)
    return means


def _fresh():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)


def _agree(means, said, tol=0.02):
    c, d = means['CYCLES'], means['DACRT']
    print(f"Cycles {c.round(4)}, DACRT {d.round(4)}, ratio {(d / c).round(4)}")
    assert c.min() > 0.05, means               # every lamp lights its channel
    assert np.abs(d / c - 1).max() < tol, (d / c, means)
    assert not [s for s in said if 'Object Info' in s or 'approximated' in s], said


def test_random_on_several_lamps(tmp_path, said):
    _fresh()
    for name, emission in (('Lamp', RED), ('Lamp.001', GREEN), ('Sun Key', BLUE)):
        _sun(name, emission, strength=lambda nt, i: _math(nt, 'MULTIPLY', i.outputs['Random'], 10.0))
    means = _render(tmp_path, said)
    _agree(means, said)
    # three lamps, three randoms (not one value stood in for all)
    assert np.ptp(means['CYCLES']) > 0.02, means


def test_location_alpha_index_and_color(tmp_path, said):
    _fresh()
    index = _sun('Indexed', RED, strength=lambda nt, i: _math(nt, 'MULTIPLY', i.outputs['Object Index'], 0.5))
    index.pass_index = 3
    # a vector read by Math: its average, as Cycles converts it ((1.5 - 0.5 + 4) / 3)
    _sun('Placed', GREEN, location=(1.5, -0.5, 4.0),
         strength=lambda nt, i: _math(nt, 'MULTIPLY', i.outputs['Location'], 1.0))
    alpha = _sun('Faded', BLUE, strength=lambda nt, i: _math(nt, 'MULTIPLY', i.outputs['Alpha'], 2.0))
    alpha.color = (1.0, 1.0, 1.0, 0.6)
    _agree(_render(tmp_path, said), said)


def test_color_into_emission_color(tmp_path, said):
    _fresh()
    ob = _sun('Tinted', color=lambda nt, i: i.outputs['Color'])
    ob.color = (0.2, 0.5, 1.0, 1.0)
    means = _render(tmp_path, said)
    _agree(means, said)
    assert means['CYCLES'][2] > 3 * means['CYCLES'][0], means      # the object's colour, not grey


@pytest.mark.parametrize('output', ['Random', 'Location'])
def test_instanced_lamp(tmp_path, said, output):
    """One sun in an excluded collection, instanced twice: each instance's Random (its random id)
    or Location (the instance's) into the Strength and its Object Info Color (the instancer's)
    into the Color."""
    _fresh()
    asset = bpy.data.collections.new('Asset')
    bpy.context.scene.collection.children.link(asset)
    bulb = _sun('Bulb', collection=asset,
                strength=lambda nt, i: _math(nt, 'MULTIPLY', i.outputs[output], 10.0 if output == 'Random' else 1.0),
                color=lambda nt, i: i.outputs['Color'])
    bulb.color = (0.0, 0.0, 1.0, 1.0)         # the instances' colour is their instancer's
    bpy.context.view_layer.layer_collection.children['Asset'].exclude = True
    for name, colour, at in (('InstA', RED, (3.0, 0.0, 0.0)), ('InstB', GREEN, (0.0, 6.0, 1.0))):
        e = bpy.data.objects.new(name, None)
        e.instance_type, e.instance_collection = 'COLLECTION', asset
        e.color, e.location = (*colour, 1.0), at
        bpy.context.scene.collection.objects.link(e)
    means = _render(tmp_path, said)
    c, d = means['CYCLES'], means['DACRT']
    assert c[2] < 1e-4 and d[2] < 1e-4, means
    _agree({k: v[:2] for k, v in means.items()}, said)
