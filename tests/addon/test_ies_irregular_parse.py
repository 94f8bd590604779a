"""Profiles Cycles 5.0 loads although their angles repeat or are out of order, or a candela is NaN
(addon/lights/ies.py): parse_ies keeps them as Cycles does and ies_interp reads them as Cycles'
kernel_ies_interp does (its linear scans; NaN and the 0/0 of a zero-width first interval give 0),
checked against a line-by-line float32 transcription (tests/iescycles.py). Before, parse_ies
refused them ("not finite and ascending", "non-finite intensities") and the lamp shone 100 x
Strength evenly, 5-73x Cycles. NaN and infinite angles are read as Cycles' tests and scans read
them; only an axis of one NaN angle is refused, said as a profile Cycles reads
(cycles_reads). No Blender needed."""
import numpy as np
import pytest

from addon.lights.ies import IESError, ies_interp, ies_mean, parse_ies
from tests.iescycles import IRREGULAR, cycles_ies_interp
from tests.iesfiles import lm63

F32 = np.float32
DEG = F32(np.pi) / F32(180.0)


def test_tables_kept_as_cycles_keeps_them():
    p = parse_ies(IRREGULAR['dup_vertical'])
    np.testing.assert_array_equal(p.v_angles, np.asarray([0, 10, 10, 30, 45, 60, 75, 90], F32) * DEG)
    p = parse_ies(IRREGULAR['dup_horizontal'])     # the quadrant mirrored with its repeat
    np.testing.assert_array_equal(p.h_angles, np.asarray([0, 45, 45, 90, 135, 135, 180, 225, 225, 270, 315, 315,
                                                          360], F32) * DEG)
    p = parse_ies(IRREGULAR['unsorted_vertical'])
    np.testing.assert_array_equal(p.v_angles, np.asarray([0, 45, 30, 90], F32) * DEG)
    p = parse_ies(IRREGULAR['nan_candela'])
    assert np.isnan(p.intensity[:, 1]).all() and np.isfinite(np.delete(p.intensity, 1, axis=1)).all()


def _angles(p, rng, n=1500):
    """Random angles, the table's own ones and the poles and seams."""
    h = np.concatenate([rng.uniform(0, 2 * np.pi, n), np.resize(p.h_angles, 40), [0.0, 2 * np.pi - 1e-6]])
    v = np.concatenate([rng.uniform(0, np.pi, n), np.resize(p.v_angles, 40), [0.0, np.pi - 1e-6]])
    return h.astype(F32), v.astype(F32)


MORE = {
    'dup_first': lm63([0, 0, 30, 90], [0, 90], [[1000, 800, 300, 0], [500, 400, 100, 0]]),
    # a horizontal axis ending at inf: it wraps (inf > 2 pi) and its last interval's fraction is 0
    'inf_horizontal': lm63([0, 30, 90], [0, 90, float('inf')], [[1000, 800, 0], [500, 400, 0], [300, 200, 0]]),
    'nan_last_vertical': lm63([0, 30, 60, float('nan')], [0, 180], [[1000, 800, 300, 0], [500, 400, 100, 0]]),
}


@pytest.mark.parametrize('name', list(IRREGULAR) + list(MORE))
def test_interp_reads_as_cycles_scans(name):
    text = IRREGULAR.get(name) or MORE[name]
    p = parse_ies(text)
    h, v = _angles(p, np.random.default_rng(7))
    want = np.asarray([cycles_ies_interp(p.h_angles, p.v_angles, p.intensity, a, b) for a, b in zip(h, v)])
    got = ies_interp(p, h, v)
    assert np.isfinite(got).all() and (got >= 0).all()
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=2e-4 * np.nanmax(p.intensity))
    assert want.max() > 0
    assert np.isfinite(ies_mean(p)) and ies_mean(p) > 0


def test_zero_width_first_interval_and_nan_give_zero():
    # straight down on a repeated first angle: Cycles' inverse_lerp is 0/0, its max(NaN, 0) is 0
    p = parse_ies(lm63([0, 0, 30, 90], [0], [[1000, 800, 300, 0]]))
    assert ies_interp(p, [1.0], [0.0])[0] == 0.0 and ies_interp(p, [1.0], [1e-3])[0] > 0
    # a NaN candela darkens the intervals whose cubic reads it (0..30 degrees), not the rest
    p = parse_ies(IRREGULAR['nan_candela'])
    got = ies_interp(p, np.full(3, 1.0), np.radians([5.0, 25.0, 40.0]))
    assert got[0] == 0.0 and got[1] == 0.0 and got[2] > 0


def test_one_nan_angle_refused_as_dacrt_limit():
    # (Cycles' bounds test lets every angle through and its scan reads past the axis)
    with pytest.raises(IESError, match="its only vertical angle is NaN") as e:
        parse_ies(lm63([float('nan')], [0], [[1000]]))
    assert e.value.cycles_reads


def test_one_infinite_angle_is_dark():
    # Cycles' bounds test fails every angle against it (measured: Cycles renders the lamp black)
    for bad in (float('inf'), float('-inf')):
        p = parse_ies(lm63([bad], [0], [[1000]]))
        assert not ies_interp(p, np.linspace(0, 6.28, 50), np.linspace(0, 3.14, 50)).any()


def test_what_cycles_cannot_load_is_not_a_dacrt_limit():
    with pytest.raises(IESError) as e:
        parse_ies("")
    assert not e.value.cycles_reads
