"""Clamp Direct with light-sampled emitters: each engine clamps its own light samples, and
DACRT picks an emitter's triangles with other probabilities than Cycles' light tree, so the
light they cast differs where clamped (fuzz seed 6705, Clamp Direct 4.21, two point lights and
emissive instances: a spot 0.85x Cycles, 1.0000x unclamped; here, 0 bounces at Clamp Direct 1,
48x36, 256 spp: an emissive cube over a floor 0.947x Cycles' mean, rows to 0.80x; with a lamp
0.965x; with the Light Tree off the cube alone 1.000x, with a lamp 0.989x). That was silent.
It is said, naming the materials, where it can change the image; not for Clamp Direct off,
lamps or the world alone (measured alike: two or three lamps, a lamp and a grey world,
1.000x / 0.996x), an emitter not light-sampled (Emission Sampling None), nor one emitter alone
with the Light Tree off.

A world light-sampled from a map (an image, sky or procedural world) beside a lamp is shared
with other probabilities too (fuzz seeds 7437, 7428, 7540: a spot or point lamp and an image
world, Clamp Direct 1.55-1.89, 0.975-0.984x Cycles' mean, a ball 0.89x, a patch 0.63-0.77x,
1.000x unclamped; a point lamp and an image world with a hot spot at Clamp Direct 1, 0
bounces, 48x36, 64 spp x 8: 0.94x without the Light Tree, 1.005x with it and 4x4 blocks
0.94-1.03x). So are lamps in separate groups of DACRT's split: each lamp without the Light
Tree, each sun with it. That was silent; it is said, not for the world alone (0.993x) nor
for lamps of one tree.
"""
import math

import bpy
import numpy as np
import pytest

from . import scenes

SAID = "Clamp Direct 1 with light-sampled emissive material(s)"


def _scene(sc, clamp=1.0, lamps=1, emitter=False, sampling='AUTO', world=0.0, tree=True):
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    scenes.plane(size=8, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    for i in range(lamps):
        scenes.light('POINT', 100.0, location=(i - 0.5, 0, 2), name=f"Lamp{i}")
    if emitter:
        m = scenes.emission('glow', (1.0, 1.0, 1.0), 5.0)
        m.cycles.emission_sampling = sampling
        scenes.cube('Glow', size=0.5, location=(1.5, 0, 0.25), materials=[m])
    if world == 'image':
        px = np.full((16, 32, 4), 0.3, np.float32)
        px[12, 5, :3] = 40.0            # a hot spot: light samples toward it are clamped
        px[..., 3] = 1.0
        scenes.environment_world(scenes.float_image('env', px), 1.0, scene=sc).name = 'Sky'
    elif world > 0:
        scenes.world((0.5, 0.5, 0.5), world, scene=sc)
    else:
        scenes.black_world(sc)
    sc.dacrt.sample_clamp_direct = clamp
    sc.dacrt.use_light_tree = tree


def _said(said):
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if "Clamp Direct" in t]


@pytest.mark.parametrize('case', ['emitter', 'lamp_and_emitter', 'tree_off_lamp_and_emitter'])
def test_said_naming_the_emitters(scene, said, case):
    _scene(scene, lamps=0 if case == 'emitter' else 1, emitter=True, tree=not case.startswith('tree_off'))
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"{SAID} 'glow': DACRT"), got
    assert ("picks their triangles" in got[0]) == (not case.startswith('tree_off')), got


@pytest.mark.parametrize('case', ['lamp', 'tree_off_lamp', 'lamp_and_emitter'])
def test_said_naming_a_mapped_world_beside_lamps(scene, said, case):
    _scene(scene, world='image', emitter=case == 'lamp_and_emitter', tree=not case.startswith('tree_off'))
    got = _said(said)
    assert len(got) == 1, got
    first = f"{SAID} 'glow'" if case == 'lamp_and_emitter' else "Clamp Direct 1 with a lamp"
    assert got[0].startswith(f"{first} and the world 'Sky' (light-sampled): DACRT shares light samples among "
                             "the light sources"), got


@pytest.mark.parametrize('case', ['tree_off_two_lamps', 'lamp_and_sun'])
def test_said_for_lamps_in_separate_groups(scene, said, case):
    """Without the tree each lamp is a group of DACRT's split; with it each sun is (fuzz 7428:
    a spot and a sun without the tree, a patch 0.51-0.64x Cycles; 7452: a spot, a sun and an
    area light with it, 1.08-1.10x the mean)."""
    _scene(scene, lamps=2 if case.startswith('tree_off') else 1, tree=not case.startswith('tree_off'))
    if case == 'lamp_and_sun':
        scenes.light('SUN', 2.0, name="Sun")
    got = _said(said)
    assert len(got) == 1 and got[0].startswith("Clamp Direct 1 with 2 lamps: DACRT shares light samples among "
                                               "the light sources"), got


@pytest.mark.parametrize('case', ['image_world_alone', 'image_world_clamp_off'])
def test_not_said_for_a_mapped_world_alone_or_unclamped(scene, said, case):
    _scene(scene, clamp=0.0 if case.endswith('clamp_off') else 1.0, lamps=0 if case.endswith('alone') else 1,
           world='image')
    assert not _said(said)


@pytest.mark.parametrize('case', ['clamp_off', 'two_lamps', 'lamp_and_world', 'emitter_not_sampled',
                                  'tree_off_one_emitter'])
def test_not_said_where_it_cannot_differ(scene, said, case):
    _scene(scene, clamp=0.0 if case == 'clamp_off' else 1.0,
           lamps={'two_lamps': 2, 'tree_off_one_emitter': 0}.get(case, 1),
           emitter=case in ('clamp_off', 'emitter_not_sampled', 'tree_off_one_emitter'),
           sampling='NONE' if case == 'emitter_not_sampled' else 'AUTO',
           world=1.0 if case == 'lamp_and_world' else 0.0, tree=case != 'tree_off_one_emitter')
    assert not _said(said)
