"""The Noise Texture kernel runs 16 points per step (native/cpp/noise.cpp: lane loops compiled
for portable x86-64, AVX2 and AVX-512; fmod in vector code below 1e14, a floor from the
truncated integer, gradients as bit selects). Property: every lane's result has the bits of the
point-by-point float32 formulas, for any input: the numpy reference written operation by
operation from Cycles (tests/integrator/noise_reference.py) on random points far and near
(multiples of 100000 and their neighbours, past 1e6, 1e14 and 2^31, inf, NaN, denormals),
every type, 2D and 3D, Detail 0 to 15 whole and fractional, extreme Roughness and Lacunarity,
distortion, normalisation off, per-point parameters and point counts that leave a short last
block; and the same bits from every instruction set the CPU runs (DACRT_ISA picks one)."""

import dacrt
import numpy as np

import pytest

from tests.integrator import noise_reference as ref
from tests.native.isaruns import outputs_per_isa

F32 = np.float32
KINDS = ['FBM', 'MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN']


def _points(rng, n):
    """n x 3 coordinates mixing every range the kernel treats apart."""
    kinds = rng.integers(0, 8, (n, 3))
    near = (rng.random((n, 3)) - 0.5) * 20
    wide = (rng.random((n, 3)) - 0.5) * 8e6                     # fmod's wrap, and past 1e6
    huge = np.sign(rng.random((n, 3)) - 0.5) * 10.0 ** rng.uniform(5, 20, (n, 3))   # past 1e14 and 2^31
    mult = rng.integers(-3000, 3000, (n, 3)) * 1e5              # exact multiples of 100000 ...
    bits = rng.integers(0, 2 ** 32, (n, 3), dtype=np.uint64).astype(np.uint32).view(F32)   # NaN, inf, denormals
    special = rng.choice(np.array([0.0, -0.0, 0.5, -0.5, 1e5, -1e5, 1e6, -1e6, 2.0 ** 31, -2.0 ** 31, 1e14, -1e14,
                                   np.inf, -np.inf, np.nan, 2.0 ** 24, 1e-40], F32), (n, 3))
    # (float32 throughout: a cast would quieten the signalling NaNs among the random bits)
    p = np.choose(kinds, [v.astype(F32) for v in (near, near, wide, huge, mult)] + [bits, special, near.astype(F32)])
    step = rng.integers(-2, 3, (n, 3))                          # ... and their float neighbours
    nbr = (kinds == 4) & (step != 0)
    p[nbr] = np.nextafter(p[nbr], np.where(step[nbr] > 0, np.inf, -np.inf).astype(F32))
    return p


def _params(rng, n):
    """Per-point scale, Detail (whole 0..15 on half the points), Roughness, Lacunarity,
    Distortion (0 on some), Offset, Gain: finite, as wide as they go."""
    detail = rng.uniform(-1, 17, n).astype(F32)
    detail[::2] = rng.integers(0, 16, n)[::2]
    scale = rng.choice(np.array([1.0, 5.0, -2.5, 0.0, 1e-3, 3e4], F32), n)
    rough = rng.choice(np.array([0.0, 0.5, 1.0, 2.0, -1.0, 1e-30, 7.5], F32), n)
    lac = rng.choice(np.array([2.0, 0.0, -2.0, 1e-3, 8.0, 1000.0, 1.99], F32), n)
    dist = np.where(rng.random(n) < 0.4, 0.0, rng.uniform(-5, 5, n)).astype(F32)
    offset = rng.uniform(-2, 2, n).astype(F32)
    gain = rng.choice(np.array([1.0, 0.0, 3.0, -2.0, 1e6], F32), n)
    return scale, detail, rough, lac, dist, offset, gain


def _same(a, b):
    """Equal bits, where the reference's NaNs may carry another payload: any NaN equals a NaN."""
    a, b = np.asarray(a), np.asarray(b)
    nan = np.isnan(a)
    assert (nan == np.isnan(b)).all()
    assert (a[~nan].view(np.uint32) == b[~nan].view(np.uint32)).all()


@pytest.mark.parametrize('normalize', [True, False])
@pytest.mark.parametrize('dims', [2, 3])
@pytest.mark.parametrize('kind', KINDS)
def test_lanes_give_the_reference_bits_on_any_input(kind, dims, normalize):
    rng = np.random.default_rng([dims, KINDS.index(kind), normalize])
    n = 4001                                                    # 250 blocks of 16 and one of 1
    p = _points(rng, n)
    scale, detail, rough, lac, dist, offset, gain = _params(rng, n)
    with np.errstate(all='ignore'):
        f0, c0 = ref.noise_texture(p, scale, detail, rough, lac, dist, normalize, dims, True, kind, offset, gain)
    f1, c1 = dacrt.shading.noise_texture(p[:, :dims], scale, detail, rough, lac, dist, normalize, True, kind,
                                         offset, gain)
    _same(f1, f0)
    _same(c1, c0)
    # one value for all points (the kernel's other read), Fac alone, a block count of 16
    with np.errstate(all='ignore'):
        g0, _ = ref.noise_texture(p[:4000], 3.0, 15.0, 0.5, 2.0, 0.0, normalize, dims, False, kind, 0.5, 2.0)
    g1, none = dacrt.shading.noise_texture(p[:4000, :dims], 3.0, 15.0, 0.5, 2.0, 0.0, normalize, False, kind, 0.5,
                                           2.0)
    assert none is None
    _same(g1, g0)


def test_far_coordinates_wrap_as_fmod_does():
    """One octave at scale 1, no distortion: the noise of a point past 100000 is that of
    fmod(x, 100000) (+ 0.5 past 1e6), which the kernel computes in vector code below 1e14."""
    rng = np.random.default_rng(5)
    n = 200000
    p = (np.sign(rng.random((n, 3)) - 0.5) * 10.0 ** rng.uniform(4.9, 14.2, (n, 3))).astype(F32)
    p[::3] = (rng.integers(-10 ** 9, 10 ** 9, (len(p[::3]), 3)) * 1e5).astype(F32)
    p[1::3] = np.nextafter(p[::3], F32(np.inf))[:len(p[1::3])]
    with np.errstate(all='ignore'):
        f0, _ = ref.noise_texture(p, 1.0, 0.0, 0.5, 2.0, 0.0, False, 3, False)
    f1, _ = dacrt.shading.noise_texture(p, 1.0, 0.0, 0.5, 2.0, 0.0, False, False)
    _same(f1, f0)


_ISA_RUN = """
import sys, numpy as np, dacrt
a = np.load(sys.argv[1])
out = []
for dims in (2, 3):
    for kind in ('FBM', 'MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN'):
        for normalize in (True, False):
            f, c = dacrt.shading.noise_texture(np.ascontiguousarray(a[:, :dims]), *a[:, 3:8].T.copy(), normalize, True,
                                               kind, a[:, 8].copy(), a[:, 9].copy())
            out += [f, c.ravel()]
np.save(sys.argv[2], np.concatenate(out))
"""


def test_every_instruction_set_gives_the_same_bits():
    """DACRT_ISA picks the kernel's portable, AVX2 or AVX-512 copy in a new process; NaN
    parameters included (no reference reads them as the kernel does: they clamp to 0)."""
    rng = np.random.default_rng(11)
    n = 3003
    p = _points(rng, n)
    scale, detail, rough, lac, dist, offset, gain = _params(rng, n)
    for v in (detail, rough, lac, offset, gain, scale, dist):
        v[rng.random(n) < 0.02] = np.nan
    lac[rng.random(n) < 0.02] = np.inf
    # columns: x y z scale detail rough lac dist | offset gain (read by the script by position)
    a = np.concatenate([p, np.stack([scale, detail, rough, lac, dist, offset, gain], 1)], 1).astype(F32)
    out = outputs_per_isa(_ISA_RUN, a)
    first = out['portable']
    assert np.isfinite(first).mean() > 0.5
    for isa, v in out.items():
        assert v.tobytes() == first.tobytes(), isa
