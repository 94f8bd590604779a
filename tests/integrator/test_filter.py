"""Pixel filter importance sampling (reference blender-cycles.md 2.4): table shape, and the
half-plane edge profile, checked against an independent integral of the filter formula and
against Cycles' measured profile."""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.filter import TABLE_SIZE, PixelFilter

from .scenes import ALL_VIS, geometry, material, quad, render

# (filter, width) -> Cycles 5.0.1 edge profile: pixels whose centres are 2.5, 1.5, 0.5 px before
# the edge and 0.5, 1.5, 2.5 px after it (white side after).
CYCLES_PROFILE = {
    ('BLACKMAN_HARRIS', 1.5): [0.0, 0.0, 0.119, 0.882, 1.0, 1.0],
    ('GAUSSIAN', 1.5): [0.0, None, 0.092, 0.909, 0.999, 1.0],
    ('BLACKMAN_HARRIS', 3.0): [None, 0.035, 0.28, 0.721, 0.965, None],
}


def formula_share_beyond(kind, width, d):
    """Share of the filter's mass beyond offset d, by direct quadrature of the section 2.4
    formulas (independent of the table)."""
    if kind == 'GAUSSIAN':
        R, f = 1.5 * width, (lambda t: np.exp(-8 * t * t / width ** 2))
    else:
        R = width
        f = (lambda t: 0.35875 - 0.48829 * np.cos(2 * np.pi * (t / (2 * width) + 0.5))
             + 0.14128 * np.cos(4 * np.pi * (t / (2 * width) + 0.5))
             - 0.01168 * np.cos(6 * np.pi * (t / (2 * width) + 0.5)))
    t = np.linspace(-R, R, 400001)
    w = f(t)
    return float(w[t > d].sum() / w.sum())


def edge_scene(kind, width, samples):
    """Emission 1 for x > 10 (a pixel boundary), black elsewhere, 1 unit per pixel, seen from above."""
    W, H = 20, 32
    cam = sd.Camera('ORTHO', np.eye(4) @ np.diag([1, 1, 1, 1.0]), (0.0, float(W), 0.0, float(H)), 0.0,
                    0.01, 100.0, W, H)
    cam.matrix[:3, 3] = (0.0, 0.0, 5.0)
    v, t = quad((510.0, 0.0, 0.0), 500.0, 500.0)
    mats = [material('default'), material('white', (0.0,) * 3, (1.0, 1.0, 1.0))]
    return sd.SceneData(cam, geometry([(v, t, 1, ALL_VIS)]), mats, [], np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=0, filter_type=kind, filter_width=width))


def test_table_is_cycles_monotone_symmetric_about_entry_511():
    """As Cycles' util_cdf_inverted builds it: entries 0..1022 monotone and symmetric about
    entry 511 (the pixel centre, 0.5), spanning the support; entry 1023 left 0. So u = 0.5 (sample
    0) reads half a step right of the centre, as in Cycles (tests/parity/test_filter_table.py)."""
    for kind, width in [('BOX', 1.0), ('GAUSSIAN', 1.5), ('BLACKMAN_HARRIS', 1.5), ('BLACKMAN_HARRIS', 3.0)]:
        f = PixelFilter(kind, width)
        t = f.table
        assert t.shape == (TABLE_SIZE,)
        assert np.all(np.diff(t[:TABLE_SIZE - 1]) >= 0)
        i = np.arange(TABLE_SIZE // 2)
        assert np.allclose(t[511 - i] + t[511 + i], 1.0, atol=1e-5)
        assert t[511] == pytest.approx(0.5, abs=1e-6) and t[TABLE_SIZE - 1] == 0.0
        assert t[0] == pytest.approx(0.5 - f.radius, abs=1e-5)
        assert f.offsets(np.float32([0.5]))[0] == pytest.approx(0.5 * (t[511] + t[512]), abs=1e-7)


def test_box_ignores_width():
    assert PixelFilter('BOX', 3.0).radius == 0.5


def test_bad_filter_settings_are_named():
    with pytest.raises(ValueError, match='filter_type'):
        PixelFilter('MITCHELL', 1.5)
    with pytest.raises(ValueError, match='filter_width'):
        PixelFilter('GAUSSIAN', 0.0)


@pytest.mark.parametrize('kind,width', list(CYCLES_PROFILE))
def test_table_share_matches_formula(kind, width):
    """Dense uniform input through the table: the share of offsets beyond d is the formula's."""
    f = PixelFilter(kind, width)
    u = ((np.arange(1 << 20) + 0.5) / (1 << 20)).astype(np.float32)
    off = f.offsets(u) - 0.5
    for d in (0.5, 1.5, 2.5):
        assert np.mean(off > d) == pytest.approx(formula_share_beyond(kind, width, d), abs=2e-3)


@pytest.mark.parametrize('kind,width', list(CYCLES_PROFILE))
def test_rendered_edge_profile(kind, width):
    integ = render(edge_scene(kind, width, samples=1024))
    img = integ.film.combined()[..., 0]
    profile = img.mean(axis=0)[7:13]                         # pixels 7..12, edge between 9 and 10
    dist = np.array([-2.5, -1.5, -0.5, 0.5, 1.5, 2.5])
    predicted = [formula_share_beyond(kind, width, -x) for x in dist]
    assert np.allclose(profile, predicted, atol=0.01)
    for got, cycles in zip(profile, CYCLES_PROFILE[(kind, width)]):
        if cycles is not None:
            assert got == pytest.approx(cycles, abs=0.015)


def test_box_edge_is_sharp():
    img = render(edge_scene('BOX', 1.0, samples=16)).film.combined()[..., 0]
    assert np.all(img[:, :10] == 0.0) and np.all(img[:, 10:] == 1.0)
