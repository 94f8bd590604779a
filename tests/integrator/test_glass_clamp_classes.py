"""Light behind glass is clamped as indirect light, as Cycles 5.0 clamps it: Cycles picks Clamp
Direct or Clamp Indirect by the path's bounce count, and a pass through glass is a bounce, so a
floor's light samples seen through a pane are indirect. Measured (a point lamp 0.6 m over a white
floor seen through a camera-only IOR-1 pane, Total 2): Clamp Direct 0 / Indirect 1 gives Cycles
1.601, DACRT 10.23 (6.4x); Direct 1 / Indirect 0 gives 10.30 and 1.668 (0.16x); without the pane
both agree. Closed forms here: a straight-down sun lights the floor exactly."""
import numpy as np
import pytest

from .scenes import ALL_VIS, geometry, light, material, quad, render
from .test_total_bounces import _floor_under_ceiling, _reflected
from .test_transparency import sheet_scene

LIT = 0.8 * 3.0 / np.pi            # the floor under a sun of 3, per channel (RGB sum 2.29)


def _floor(panes, direct, indirect):
    sheet = material('glass', (0.0,) * 3, transparency=np.ones(3, np.float32), refraction=np.ones(3, np.float32))
    scene = sheet_scene(sheet, floor=True, lights=[light('SUN', 3.0, np.eye(4))], world=np.zeros(3), sheet_vis=1,
                        sheets=tuple(0.2 + 0.05 * i for i in range(panes)), samples=4,
                        sample_clamp_direct=direct, sample_clamp_indirect=indirect)
    return render(scene).film.combined()[..., :3]


@pytest.mark.parametrize('panes', [0, 1])
@pytest.mark.parametrize('direct,indirect', [(0.0, 0.5), (0.5, 0.0)])
def test_light_sampled_behind_a_pane_is_clamped_as_indirect(panes, direct, indirect):
    """Each sample's RGB sum 2.29 is cut to 3 x 0.5 where its class has that clamp: the
    Indirect one behind the pane, the Direct one without it (DACRT had used Direct for both)."""
    clamp = indirect if panes else direct
    np.testing.assert_allclose(_floor(panes, direct, indirect), 0.5 if clamp else LIT, rtol=1e-5)


def test_a_path_past_glass_and_one_without_are_clamped_apart():
    """A pane over half the view (x > 0): the pixels behind it take Indirect, the others
    Direct, in the same batch."""
    sheet = material('glass', (0.0,) * 3, transparency=np.ones(3, np.float32), refraction=np.ones(3, np.float32))
    scene = sheet_scene(sheet, floor=True, lights=[light('SUN', 3.0, np.eye(4))], world=np.zeros(3), sheet_vis=1,
                        samples=4, sample_clamp_direct=0.0, sample_clamp_indirect=0.5)
    scene.geometry = geometry([(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS),
                               (*quad((100.0, 0.0, 0.2), 100.0, 100.0), 2, 1)])
    img = render(scene).film.combined()[..., :3]
    behind = np.isclose(img, 0.5, rtol=1e-5).all(axis=-1)
    assert np.all(behind | np.isclose(img, LIT, rtol=1e-5).all(axis=-1))
    np.testing.assert_array_equal(behind.sum(axis=1), img.shape[1] // 2)    # the right half


@pytest.mark.parametrize('direct,indirect', [(0.0, 1e-4), (1e-4, 0.0)])
def test_light_found_by_rays_from_behind_a_pane_is_clamped_as_indirect(direct, indirect):
    """The 0.8 floor behind a camera-only pane under an emissive ceiling (E 1), Total 1: the
    floor is Cycles' bounce 1, so both its light samples and the emission its BSDF rays find
    (bounce 2, clamped by bounce - 1) are indirect. With Clamp Indirect 1e-4 each sample has at
    most two contributions of RGB sum 3e-4; with it off (Direct 1e-4) the floor is unclamped,
    0.8 x E. DACRT had clamped the found emission as direct light (the floor 0.8 x E's share
    unclamped, or clamped to nothing)."""
    img = _floor_under_ceiling(True, max_bounces=4, total_max_bounces=1,
                               sample_clamp_direct=direct, sample_clamp_indirect=indirect)
    if indirect:
        assert 0.0 < img <= 2e-4 + 1e-7
    else:
        assert img == pytest.approx(_reflected(1), rel=0.02)
