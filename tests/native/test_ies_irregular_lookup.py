"""Profiles Cycles 5.0 loads with repeated or unordered angles or a NaN candela, in the native
lookup (native/cpp/ies.cpp): registered as they come and read as Cycles' kernel_ies_interp reads
them (its linear scans, 0 for NaN: the 0/0 of a zero-width first interval, a NaN value's
neighbourhood), against a float32 transcription of it (tests/iescycles.py); a lamp with such a
profile gives finite samples. Before, ies_register refused them ("must be finite and ascending",
"intensities must be finite"). Only an axis of one NaN angle is refused (Cycles' bounds test would
let every angle through to a scan past the axis)."""
import dacrt
import numpy as np
import pytest

from addon.lights import make_lamp
from addon.lights.ies import ies_interp, parse_ies
from addon import scenedata as sd
from tests.iescycles import IRREGULAR, cycles_ies_interp
from tests.iesfiles import lm63
from tests.iesrays import profile_factor, sampled

F32 = np.float32
CASES = dict(IRREGULAR, inf_horizontal=lm63([0, 30, 90], [0, 90, float('inf')], [[1000, 800, 0], [500, 400, 0],
                                                                                  [300, 200, 0]]),
             dup_first=lm63([0, 0, 30, 90], [0, 90, 90, 180], [[1000, 800, 300, 0], [500, 400, 100, 0],
                                                                           [900, 600, 50, 0], [200, 200, 20, 0]]))


@pytest.mark.parametrize('name', list(CASES))
def test_lookup_reads_as_cycles(name):
    p = parse_ies(CASES[name])
    pid = dacrt.lamps.ies_register(p.h_angles, p.v_angles, p.intensity)
    rng = np.random.default_rng(3)
    h = np.concatenate([rng.uniform(0, 2 * np.pi, 1500), np.resize(p.h_angles, 60), [0.0]]).astype(F32)
    v = np.concatenate([rng.uniform(0, np.pi, 1500), np.resize(p.v_angles, 60), [0.0]]).astype(F32)
    got = dacrt.lamps.ies_lookup(pid, h, v)
    want = np.asarray([cycles_ies_interp(p.h_angles, p.v_angles, p.intensity, a, b) for a, b in zip(h, v)])
    scale = float(np.nanmax(p.intensity))
    np.testing.assert_allclose(got, want, rtol=0, atol=2e-6 * scale)
    np.testing.assert_allclose(got, ies_interp(p, h, v), rtol=0, atol=2e-5 * scale)
    assert np.isfinite(got).all() and (got >= 0).all() and got.max() > 0


def test_zero_width_and_nan_give_zero():
    p = parse_ies(CASES['dup_first'])
    pid = dacrt.lamps.ies_register(p.h_angles, p.v_angles, p.intensity)
    got = dacrt.lamps.ies_lookup(pid, np.full(2, 1.0, F32), np.asarray([0.0, 1e-3], F32))
    assert got[0] == 0.0 and got[1] > 0          # straight down on the repeated 0: 0/0
    p = parse_ies(IRREGULAR['nan_candela'])
    pid = dacrt.lamps.ies_register(p.h_angles, p.v_angles, p.intensity)
    got = dacrt.lamps.ies_lookup(pid, np.full(3, 1.0, F32), np.radians([5.0, 25.0, 40.0]).astype(F32))
    assert got[0] == 0.0 and got[1] == 0.0 and got[2] > 0
    inf = p.intensity.copy()
    inf[:, 1] = np.inf
    pid = dacrt.lamps.ies_register(p.h_angles, p.v_angles, inf)      # (Cycles' film: 0)
    assert dacrt.lamps.ies_lookup(pid, [1.0], [np.radians(5.0)])[0] == 0.0


def test_one_nan_angle_refused_one_infinite_dark():
    # (Cycles' bounds test would let every angle through to a scan past the axis)
    with pytest.raises(ValueError, match="vertical axis of one angle must not have it NaN"):
        dacrt.lamps.ies_register([0.0, 6.3], [np.nan], [[1.0], [1.0]])
    with pytest.raises(ValueError, match="horizontal axis of one angle must not have it NaN"):
        dacrt.lamps.ies_register([np.nan], [0.0, 3.2], [[1.0, 1.0]])
    for bad in (np.inf, -np.inf):   # (its bounds test fails every angle: 0)
        pid = dacrt.lamps.ies_register([0.0, 6.3], [bad], [[1.0], [1.0]])
        assert not dacrt.lamps.ies_lookup(pid, np.linspace(0, 6.28, 50), np.linspace(0, 3.14, 50)).any()


@pytest.mark.parametrize('kind', ['POINT', 'AREA'])
def test_nan_profile_lamp_samples_finite(kind):
    p = parse_ies(IRREGULAR['nan_candela'])
    kw = dict(radius=0.2) if kind == 'POINT' else dict(shape='SQUARE', size_x=0.5)
    m = np.eye(4)
    m[:3, 3] = (0.0, 0.0, 2.0)
    lamps = [make_lamp(sd.Light(kind, np.asarray((40.0, 30.0, 20.0), F32), m, ies=prof, **kw)) for prof in (p, None)]
    n = 4000
    rng = np.random.default_rng(5)
    P = np.stack([rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), np.zeros(n)]).astype(F32)
    u1, u2 = rng.random(n, dtype=F32), rng.random(n, dtype=F32)
    (wi, value, _), (_, value0, _) = sampled(lamps, P, u1, u2)
    assert np.isfinite(value).all()
    f = profile_factor(p, m, wi)
    np.testing.assert_allclose(value, value0 * f, rtol=2e-4, atol=1e-6 * float(np.abs(value0).max()))
    assert (f == 0).any() and (f > 0).any()
