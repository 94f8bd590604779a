"""A Translucent BSDF's bounce against the bounce budgets, as Cycles 5.0 counts it
(kernel/integrator/path_state.h path_state_next: a diffuse transmission is a transmission
bounce): against Transmission and Total, not Diffuse Max Bounces (rays off it read Diffuse Depth
0 in Cycles). Measured: three white translucent sheets over an emissive floor, 0.504 at Diffuse
0, 1 and 12 alike (Total 12); DACRT had counted each against Max Bounces too, black at 0 and 1.
Closed forms: white translucent sheets (no reflection) pass the world below them whole;
diffuse reflections stay cut at Max Bounces."""
import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, material, ortho_down, quad, render
from .test_total_bounces import ALBEDO, CEILING, E, _reflected

ONES = np.ones(3, np.float32)
WORLD = 0.6


def _sheets_over_the_world(sheets, **settings):
    """`sheets` white translucent sheets (translucency 1, no reflection) at z = 0.1, 0.2, ...,
    200 m wide, under a uniform world of 0.6, seen from above: the world below passes them
    whole (each sample's expectation 0.6) while the path may bounce through all; its mean."""
    parts = [(*quad((0.0, 0.0, 0.1 * (i + 1)), 100.0, 100.0), 1, ALL_VIS) for i in range(sheets)]
    mats = [material('default'), material('sheet', (0.0,) * 3, translucency=ONES)]
    scene = sd.SceneData(ortho_down(height=0.1 * sheets + 0.3), geometry(parts), mats, [],
                         np.full(3, WORLD, np.float32), sd.Settings(samples=64, filter_type='BOX', **settings))
    return float(render(scene).film.combined()[..., :3].mean())


@pytest.mark.parametrize('max_bounces', [0, 1])
def test_translucent_bounces_do_not_count_as_diffuse_ones(max_bounces):
    seen = _sheets_over_the_world(3, max_bounces=max_bounces, total_max_bounces=12)
    assert seen == pytest.approx(WORLD, rel=0.02)


@pytest.mark.parametrize('limit', ['total_max_bounces', 'transmission_max_bounces'])
def test_translucent_bounces_count_against_total_and_transmission(limit):
    """Three sheets: shaded at vertices 0, 1, 2, so a limit of 2 passes the floor's light and
    1 does not (the third sheet then only emits)."""
    assert _sheets_over_the_world(3, max_bounces=0, **{limit: 2}) == pytest.approx(WORLD, rel=0.02)
    assert _sheets_over_the_world(3, max_bounces=0, **{limit: 1}) == 0.0


def test_diffuse_reflections_stay_cut_at_max_bounces_beside_translucent_surfaces():
    """The floor under an emissive ceiling (test_total_bounces), with a translucent sheet far
    away that lets translucent paths run to Total: the floor's own diffuse paths still stop at
    Max Bounces, its closed form unchanged."""
    parts = [(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS),
             (*quad((0.0, 0.0, 1.0), 100.0, 100.0, up=False), 2, sd.VIS_DIFFUSE | sd.VIS_SHADOW),
             (*quad((500.0, 0.0, 0.5), 1.0, 1.0), 3, ALL_VIS)]
    mats = [material('default'), material('floor', (ALBEDO,) * 3),
            material('ceiling', (CEILING,) * 3, (E,) * 3), material('leaf', (0.0,) * 3, translucency=ONES)]
    for max_bounces in (1, 2):
        scene = sd.SceneData(ortho_down(), geometry(parts), mats, [], np.zeros(3, np.float32),
                             sd.Settings(samples=128, filter_type='BOX', max_bounces=max_bounces,
                                         total_max_bounces=12))
        mean = float(render(scene).film.combined()[..., :3].mean())
        assert mean == pytest.approx(_reflected(max_bounces + 1), rel=0.02)
