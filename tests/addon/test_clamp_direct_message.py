"""Clamp Direct with several light sources: each engine clamps its own light samples, and
DACRT picks among lamps, emitters and the world with other probabilities than Cycles, so the
clamped pixels differ (fuzz seed 6705, Clamp Direct 4.21, two point lights and emissive
instances: a spot 0.85x Cycles; 1.0000x unclamped; README, Clamping). That was silent. It is
said where it can change the image: Clamp Direct on and more than one source to sample; not
for one lamp alone (clamped alike: the `clamp` parity scene), Clamp Direct off, a black world,
or an emitter that is not light-sampled (Emission Sampling None)."""
import math

import bpy
import pytest

from . import scenes

SAID = "with several light sources"


def _scene(sc, clamp=1.0, lamps=1, emitter=False, sampling='AUTO', world=0.0):
    scenes.camera(location=(0, -5, 3), rotation=(math.radians(60), 0, 0))
    scenes.plane(size=8, materials=[scenes.diffuse('floor', (0.8, 0.8, 0.8))])
    for i in range(lamps):
        scenes.light('POINT', 100.0, location=(i - 0.5, 0, 2), name=f"Lamp{i}")
    if emitter:
        m = scenes.emission('glow', (1.0, 1.0, 1.0), 5.0)
        m.cycles.emission_sampling = sampling
        scenes.cube('Glow', size=0.5, location=(1.5, 0, 0.25), materials=[m])
    if world > 0:
        scenes.world((0.5, 0.5, 0.5), world, scene=sc)
    else:
        scenes.black_world(sc)
    sc.dacrt.sample_clamp_direct = clamp


def _said(said):
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if SAID in t]


@pytest.mark.parametrize('case, named', [('two_lamps', "2 light(s)"),
                                         ('lamp_and_emitter', "1 light(s), 1 emissive material(s)"),
                                         ('lamp_and_world', "1 light(s), the world"),
                                         ('emitter_and_world', "1 emissive material(s), the world")])
def test_said_naming_the_sources(scene, said, case, named):
    _scene(scene, lamps={'two_lamps': 2, 'emitter_and_world': 0}.get(case, 1), emitter='emitter' in case,
           world=1.0 if 'world' in case else 0.0)
    got = _said(said)
    assert len(got) == 1 and got[0].startswith(f"Clamp Direct 1 with several light sources ({named})"), got


@pytest.mark.parametrize('case', ['one_lamp', 'clamp_off', 'emitter_not_sampled', 'one_emitter'])
def test_not_said_where_it_cannot_differ(scene, said, case):
    _scene(scene, clamp=0.0 if case == 'clamp_off' else 1.0,
           lamps={'clamp_off': 2, 'emitter_not_sampled': 1, 'one_emitter': 0}.get(case, 1),
           emitter=case in ('emitter_not_sampled', 'one_emitter'),
           sampling='NONE' if case == 'emitter_not_sampled' else 'AUTO')
    assert not _said(said)
