"""Total Max Bounces (Cycles' Light Paths > Total) against closed forms: every bounce counts
against it, a pass through glass (Glass, Refraction, Principled transmission, see-through here)
as a diffuse reflection does, as Cycles 5.0 counts them: a floor seen through one pane at Total 4
renders as without the pane at Total 3 (a white box, 0.4468 and 0.4471), and glass counts
against neither Diffuse (Total 12, Diffuse 2: 0.4106 with the pane, 0.4100 without) nor, past
the pane, does the path lose a diffuse bounce it is owed. DACRT had counted glass passes
against Transmission alone, so a path behind glass kept a bounce more (1.19x Cycles at Total 2)."""
import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, ortho_down, quad, render
from .test_transparency import WORLD, sheet_scene

ONES = np.ones(3, np.float32)
GLASS = material('glass', (0.0,) * 3, transparency=ONES, refraction=ONES)


@pytest.mark.parametrize('total', [0, 1, 3])
def test_a_path_passes_total_plus_one_panes(total):
    """n clear glass sheets over the world, Transmission 12: Cycles refracts at a pane while
    its bounces so far are at most Total, so the world is seen (each sample exactly) through
    Total + 1 panes and not through Total + 2."""
    def image(panes):
        scene = sheet_scene(GLASS, samples=4, max_bounces=4, total_max_bounces=total,
                            sheets=tuple(0.05 + 0.04 * i for i in range(panes)))
        return render(scene).film.combined()[..., :3]
    np.testing.assert_allclose(image(total + 1), np.broadcast_to(WORLD, image(1).shape), rtol=1e-5)
    assert np.all(image(total + 2) == 0.0)


ALBEDO, CEILING, E = 0.8, 0.5, 1.0


def _floor_under_ceiling(pane, **settings):
    """A 0.8 floor at z = 0 under an emissive (1) and diffuse (0.5) ceiling at z = 1 that camera
    rays do not see, both 200 m wide, a black world; looking down from z = 0.5 through a clear
    glass pane at z = 0.25 that only camera rays see (or none). Its mean."""
    parts = [(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS),
             (*quad((0.0, 0.0, 1.0), 100.0, 100.0, up=False), 2, sd.VIS_DIFFUSE | sd.VIS_SHADOW)]
    if pane:
        parts.append((*quad((0.0, 0.0, 0.25), 100.0, 100.0), 3, sd.VIS_CAMERA))
    mats = [material('default'), material('floor', (ALBEDO,) * 3),
            material('ceiling', (CEILING,) * 3, (E,) * 3), GLASS]
    scene = sd.SceneData(ortho_down(), geometry(parts), mats, [], np.zeros(3, np.float32),
                         sd.Settings(samples=128, filter_type='BOX', **settings))
    return float(render(scene).film.combined()[..., :3].mean())


def _reflected(vertices):
    """The floor's radiance when path vertices 0 .. vertices - 1 are shaded (the next one only
    emits): the ceiling's emission found at vertices 1, 3, 5, ..., each after a floor and a
    ceiling reflection more."""
    return ALBEDO * E * sum((CEILING * ALBEDO) ** j for j in range((vertices - 1) // 2 + 1))


@pytest.mark.parametrize('total,max_bounces,vertices', [
    (2, 4, 2),      # the pane takes one of Total's 2: floor and ceiling shaded (1.19x before)
    (4, 4, 4),      # Total 4: one bounce fewer than without the pane
    (12, 2, 3),     # Total 12, Diffuse 2: the pane takes none of the diffuse ones
])
def test_a_pass_through_glass_counts_against_total_bounces(total, max_bounces, vertices):
    through = _floor_under_ceiling(True, max_bounces=max_bounces, total_max_bounces=total)
    assert through == pytest.approx(_reflected(vertices), rel=0.02)
    # without the pane the same budget shades one vertex more, unless Diffuse stops it first
    bare = _floor_under_ceiling(False, max_bounces=max_bounces, total_max_bounces=total)
    assert bare == pytest.approx(_reflected(min(total, max_bounces) + 1), rel=0.02)


@pytest.mark.parametrize('lamp_limit,lit', [(0, False), (1, True)])
def test_a_lamps_max_bounces_counts_glass_passes(lamp_limit, lit):
    """Cycles' Light > Max Bounces compares the path's bounce count, a glass pass included: a
    sun of Max Bounces 0 lights no floor seen through a pane (Cycles 0, with the floor lit
    without the pane), one of 1 lights it as without the pane. DACRT had compared the vertex
    index alone, the floor lit at 0 (1.00 where Cycles gives 0). The floor under a straight-down
    sun of 3 is exactly 0.8 x 3 / pi per sample; the pane is seen by camera rays alone."""
    sun = light('SUN', 3.0, np.eye(4), max_bounces=lamp_limit)
    img = render(sheet_scene(GLASS, floor=True, lights=[sun], world=np.zeros(3), sheet_vis=sd.VIS_CAMERA,
                             sheets=(0.3,), samples=4)).film.combined()[..., :3]
    np.testing.assert_allclose(img, 0.8 * 3.0 / np.pi if lit else 0.0, rtol=1e-5, atol=0.0)
