"""The Noise Texture kernel in 1D (W alone) and 4D (x, y, z, W), as Cycles' perlin_1d and
perlin_4d (grad1's slopes 1..8, grad4's three offsets of four, hash_uint / hash_uint4 with
lookup3's mix, quad_mix's two tri_mix mixed along w, scales 0.25 and 0.8344) and its fractal sums,
distortion and colour at random_float_offset (1D: the seed's own hash) / random_float4_offset
seeds. Property: every lane gives the bits of the float32 reference written from Cycles'
formulas (tests/integrator/noise_reference.py), for every type, on any input (far, huge,
non-finite points, extreme parameters, per-point parameters), and every instruction set the same
bits. Cycles itself checks both in tests/parity/test_noise_1d_4d.py."""

import dacrt
import numpy as np

import pytest

from tests.integrator import noise_reference as ref
from tests.native.isaruns import outputs_per_isa
from tests.native.test_noise_lanes import _params, _points, _same

F32 = np.float32
KINDS = ['FBM', 'MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN']


def _native(p, w, dims, *args):
    """dacrt.shading.noise_texture of points p (n, 3) and W w (n,): 1D reads w, 4D p and w."""
    pts = w[:, None] if dims == 1 else np.concatenate([p, w[:, None]], axis=1)
    return dacrt.shading.noise_texture(np.ascontiguousarray(pts, F32), *args)


@pytest.mark.parametrize('normalize', [True, False])
@pytest.mark.parametrize('dims', [1, 4])
@pytest.mark.parametrize('kind', KINDS)
def test_lanes_give_the_reference_bits_on_any_input(kind, dims, normalize):
    rng = np.random.default_rng([dims, KINDS.index(kind), normalize, 14])
    n = 2001                                                    # 125 blocks of 16 and one of 1
    p = _points(rng, n)
    w = _points(rng, n)[:, 0].copy()
    scale, detail, rough, lac, dist, offset, gain = _params(rng, n)
    with np.errstate(all='ignore'):
        f0, c0 = ref.noise_texture(p, scale, detail, rough, lac, dist, normalize, dims, True, kind, offset, gain, w)
    f1, c1 = _native(p, w, dims, scale, detail, rough, lac, dist, normalize, True, kind, offset, gain)
    _same(f1, f0)
    _same(c1, c0)
    # one value for all points, Fac alone
    with np.errstate(all='ignore'):
        g0, _ = ref.noise_texture(p, 3.0, 6.5, 0.5, 2.0, 0.4, normalize, dims, False, kind, 0.5, 2.0, w)
    g1, none = _native(p, w, dims, 3.0, 6.5, 0.5, 2.0, 0.4, normalize, False, kind, 0.5, 2.0)
    assert none is None
    _same(g1, g0)


@pytest.mark.parametrize('dims', [1, 4])
def test_near_points_vary_and_match_the_reference(dims):
    """Ordinary points (a plane, W a few frames): the noise varies smoothly in W, its colour's
    channels differ from each other, and every bit is the reference's."""
    rng = np.random.default_rng(dims)
    n = 5000
    p = ((rng.random((n, 3)) - 0.5) * 4).astype(F32)
    w = rng.uniform(-3, 3, n).astype(F32)
    f0, c0 = ref.noise_texture(p, 5.0, 2.5, 0.5, 2.0, 0.3, True, dims, True, 'FBM', 0.0, 1.0, w)
    f1, c1 = _native(p, w, dims, 5.0, 2.5, 0.5, 2.0, 0.3, True, True)
    _same(f1, f0)
    _same(c1, c0)
    assert np.ptp(f1) > 0.3 and 0.3 < f1.mean() < 0.7
    assert np.abs(c1[:, 1] - c1[:, 0]).mean() > 0.05 and np.abs(c1[:, 2] - c1[:, 1]).mean() > 0.05
    # a small step in W moves the noise a little (continuous), a whole unit much more
    f2, _ = _native(p, w + F32(1e-3), dims, 5.0, 2.5, 0.5, 2.0, 0.3, True, False)
    f3, _ = _native(p, w + F32(1.0), dims, 5.0, 2.5, 0.5, 2.0, 0.3, True, False)
    assert np.abs(f2 - f1).mean() < 0.02 < np.abs(f3 - f1).mean()


@pytest.mark.parametrize('dims', [1, 4])
def test_lattice_points_read_zero_noise(dims):
    """Perlin noise is 0 on its lattice (every gradient times a zero offset): one octave at
    scale 1 on whole coordinates gives the normalised 0.5, independently of the reference."""
    rng = np.random.default_rng(3)
    p = rng.integers(-50, 50, (100, 3)).astype(F32)
    w = rng.integers(-50, 50, 100).astype(F32)
    f, _ = _native(p, w, dims, 1.0, 0.0, 0.5, 2.0, 0.0, True, False)
    assert (f == F32(0.5)).all()


@pytest.mark.parametrize('dims', [1, 4])
def test_one_octave_is_the_double_precision_noise_within_float32_rounding(dims):
    """One octave, unnormalised, scale 1: Fac is snoise itself; the float64 evaluation of the
    same formulas (noise_reference.snoise(dtype=float64)) is within 1e-5 (float32's roundings,
    no lost precision in Cycles' order of operations)."""
    rng = np.random.default_rng(dims + 20)
    p = ((rng.random((20000, 4)) - 0.5) * 200).astype(F32)
    pts = p[:, 3:] if dims == 1 else p
    f, _ = dacrt.shading.noise_texture(np.ascontiguousarray(pts), 1.0, 0.0, 0.5, 2.0, 0.0, False, False)
    exact = ref.snoise(pts.astype(np.float64), np.float64)
    assert exact.dtype == np.float64 and np.ptp(exact) > 0.5
    assert np.abs(f - exact).max() < 1e-5, float(np.abs(f - exact).max())


def test_4d_differs_from_3d_and_1d_ignores_the_vector():
    """4D reads W (not a 3D noise with W ignored); 1D reads W alone."""
    rng = np.random.default_rng(4)
    p = ((rng.random((2000, 3)) - 0.5) * 4).astype(F32)
    w = np.full(2000, 0.37, F32)
    f4, _ = _native(p, w, 4, 5.0, 2.0, 0.5, 2.0, 0.0, True, False)
    f4b, _ = _native(p, w + F32(0.5), 4, 5.0, 2.0, 0.5, 2.0, 0.0, True, False)
    assert np.abs(f4 - f4b).mean() > 0.02
    f1, _ = _native(p, w, 1, 5.0, 2.0, 0.5, 2.0, 0.0, True, False)
    assert np.ptp(f1) == 0


_ISA_RUN = """
import sys, numpy as np, dacrt
a = np.load(sys.argv[1])
out = []
for cols in ((3,), (0, 1, 2, 3)):
    for kind in ('FBM', 'MULTIFRACTAL', 'HYBRID_MULTIFRACTAL', 'RIDGED_MULTIFRACTAL', 'HETERO_TERRAIN'):
        for normalize in (True, False):
            f, c = dacrt.shading.noise_texture(np.ascontiguousarray(a[:, cols]), *a[:, 4:9].T.copy(), normalize,
                                               True, kind, a[:, 9].copy(), a[:, 10].copy())
            out += [f, c.ravel()]
np.save(sys.argv[2], np.concatenate(out))
"""


def test_every_instruction_set_gives_the_same_bits():
    """DACRT_ISA picks the kernel's portable, AVX2 or AVX-512 copy in a new process."""
    rng = np.random.default_rng(12)
    n = 1003
    p = _points(rng, n)
    w = _points(rng, n)[:, :1]
    scale, detail, rough, lac, dist, offset, gain = _params(rng, n)
    for v in (detail, rough, lac, offset, gain, scale, dist):
        v[rng.random(n) < 0.02] = np.nan
    # columns: x y z w scale detail rough lac dist | offset gain
    a = np.concatenate([p, w, np.stack([scale, detail, rough, lac, dist, offset, gain], 1)], 1).astype(F32)
    out = outputs_per_isa(_ISA_RUN, a)
    first = out['portable']
    assert np.isfinite(first).mean() > 0.5
    for isa, v in out.items():
        assert v.tobytes() == first.tobytes(), isa


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="points must have shape"):
        dacrt.shading.noise_texture(np.zeros((4, 5), np.float32), 1.0, 2.0, 0.5, 2.0, 0.0, True, False)
    with pytest.raises(ValueError, match="points must have shape"):
        dacrt.shading.noise_texture(np.zeros((4, 0), np.float32), 1.0, 2.0, 0.5, 2.0, 0.0, True, False)
