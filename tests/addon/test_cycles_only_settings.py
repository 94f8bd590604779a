"""Cycles-only settings DACRT does not apply are said, as Simplify > Culling is
(test_animated_seed): Light Paths > Fast GI Approximation (Cycles' Cornell box 0.218 with it,
0.413 without; DACRT 0.412 either way, silently) warns, unless its AO bounces are 0 (Cycles then
applies no Fast GI)."""
import pytest

from . import scenes


@pytest.mark.parametrize('fast_gi, ao_bounces, warned', [(True, 1, True), (True, 0, False), (False, 1, False)])
def test_fast_gi_is_said_not_applied(scene, said, fast_gi, ao_bounces, warned):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=10)
    scenes.world((0.5, 0.5, 0.5))
    scene.dacrt.samples = 1
    scene.cycles.use_fast_gi = fast_gi
    scene.cycles.ao_bounces_render = ao_bounces
    scenes.render_rgba(scene)
    hits = [t for t in said if "Fast GI Approximation is not applied" in t]
    assert len(hits) == (1 if warned else 0), said
