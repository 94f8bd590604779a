"""Russian roulette counts glass passes as bounces, as Cycles 5.0 does: Cycles may end a path at
a surface from bounce 2 on (bounce > min_bounce, stored as Min Light Bounces + 1), and a pass
through glass is a bounce, so a floor seen through two panes is rouletted at the floor already.
The estimate is unbiased either way, but the sample clamps see the divided throughputs: a white
box seen through a pane with Cycles' default Clamp Indirect 10 was 1.010-1.014x Cycles (4 seeds)
while the same box without the pane was 1.00x; with the roulette counted 0.9996x. Closed forms
here: a sun lights the floor exactly, so each sample's value is known."""
import numpy as np
import pytest

from .scenes import light, material, render
from .test_transparency import sheet_scene

SUN, FLOOR, TINT = 3.0, 0.8, 0.5


def _floor(panes, clamp):
    """The floor under a straight-down sun of 3 seen through `panes` clear glass panes of colour
    0.5 that camera rays alone see, both clamps `clamp`: the image's mean."""
    sheet = material('glass', (0.0,) * 3, transparency=np.full(3, TINT, np.float32),
                     refraction=np.ones(3, np.float32))
    sun = light('SUN', SUN, np.eye(4))
    scene = sheet_scene(sheet, floor=True, lights=[sun], world=np.zeros(3), sheet_vis=1,
                        sheets=tuple(0.2 + 0.05 * i for i in range(panes)), samples=64,
                        sample_clamp_direct=clamp, sample_clamp_indirect=clamp)
    return render(scene).film.combined()[..., :3]


def _lit(panes):
    """The floor's radiance per sample through `panes` panes, before any clamp or roulette."""
    return FLOOR * SUN / np.pi * TINT ** panes


def test_one_pane_is_not_rouletted():
    """Behind one pane the floor is Cycles' bounce 1: no roulette, every sample the same and
    under the clamp (3 x 0.4 > its RGB sum 1.146)."""
    np.testing.assert_allclose(_floor(1, 0.4), _lit(1), rtol=1e-5)


def test_a_floor_behind_two_panes_is_rouletted_under_the_clamp():
    """Behind two panes (bounce 2) the path survives with q = sqrt(0.25) = 0.5 and its light
    sample is 0.573 / 0.5 = 1.146 (RGB sum), clamped to 3 x 0.3: the mean is 0.5 x 0.3 per
    channel. Without the roulette every sample was 0.191 (1.27x)."""
    lit = _lit(2)                                    # 0.191 per channel, 0.573 summed
    assert 3 * lit / 0.5 > 0.9 > 3 * lit              # the clamp cuts only rouletted samples
    img = _floor(2, 0.3)
    assert img.mean() == pytest.approx(0.5 * 0.3, rel=0.04)
    # unclamped, the roulette changes no mean
    assert _floor(2, 0.0).mean() == pytest.approx(lit, rel=0.04)
