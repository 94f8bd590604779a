"""The native Voronoi Texture (dacrt.shading.voronoi_texture, used by addon/procedural.py) of one
octave against a float32 numpy reference of Cycles' F1 (voronoi_reference.py): the same bits in
2D and 3D for each metric, randomness per point (clamped to [0, 1] as Cycles does) and cells far
from the origin; Scale and the fractal octaves composed from that reference. Cycles itself
checks both in tests/parity/test_procedural.py."""
import dacrt
import numpy as np
import pytest

from . import voronoi_reference as ref


def f1(p, randomness, metric='EUCLIDEAN', scale=1.0):
    """The node's F1 of one octave (Detail 0): distance, colour and position (n, 3)."""
    d, color, position, _ = dacrt.shading.voronoi_texture(p, scale, 0.0, 0.5, 2.0, 1.0, 1.0, randomness, 'F1', metric)
    return d, color, position[:, :3]


@pytest.mark.parametrize('metric', ['EUCLIDEAN', 'MANHATTAN', 'CHEBYCHEV'])
@pytest.mark.parametrize('dims', [2, 3])
def test_native_voronoi_matches_the_reference_bit_for_bit(metric, dims):
    rng = np.random.default_rng(dims)
    p = ((rng.random((20000, dims)) - 0.5) * 60).astype(np.float32)
    p[:50] *= 1e5                                   # cells far from the origin (int wrap in the hash)
    r = rng.uniform(-0.5, 1.5, len(p)).astype(np.float32)
    want = ref.voronoi_f1(p, r, metric)
    got = f1(p, r, metric)
    for name, g, w in zip(('distance', 'colour', 'position'), got, want):
        np.testing.assert_array_equal(g, w, err_msg=name)
    assert np.ptp(got[1]) > 0.9 and (got[0] >= 0).all()


def test_randomness_zero_puts_each_point_at_its_cell_corner():
    """Randomness 0: every feature point is its cell's corner, so F1 is the distance to the
    nearest integer lattice point, in closed form."""
    p = np.random.default_rng(4).uniform(-5, 5, (1000, 3)).astype(np.float32)
    d, _, position = f1(p, 0.0)
    nearest = np.round(p.astype(np.float64))
    np.testing.assert_allclose(d, np.linalg.norm(p - nearest, axis=1), atol=1e-5)
    np.testing.assert_allclose(position, nearest, atol=1e-5)


@pytest.mark.parametrize('metric', ['EUCLIDEAN', 'MANHATTAN', 'CHEBYCHEV'])
@pytest.mark.parametrize('dims', [2, 3])
def test_the_node_of_one_octave_is_f1(metric, dims):
    """Scale: the node with Detail 0 is the reference's F1 of the scaled points: the same
    distance and colour bits; the position divided back by Scale."""
    rng = np.random.default_rng(10 + dims)
    p = ((rng.random((5000, dims)) - 0.5) * 20).astype(np.float32)
    r = rng.uniform(-0.5, 1.5, len(p)).astype(np.float32)
    scale = np.float32(2.5)
    d, color, position, radius = dacrt.shading.voronoi_texture(p, scale, 0.0, 0.5, 2.0, 1.0, 1.0, r, 'F1', metric)
    want = ref.voronoi_f1(p * scale, r, metric)
    np.testing.assert_array_equal(d, want[0])
    np.testing.assert_array_equal(color, want[1])
    np.testing.assert_allclose(position[:, :3], want[2] / scale, rtol=1e-6, atol=1e-6)
    assert (position[:, 3] == 0).all() and (radius == 0).all()


def test_octaves_sum_as_cycles_fbm():
    """Detail 1, Roughness 0.5, Lacunarity 2 (not normalized): F1 at the point plus half F1 at
    twice the point, as Cycles' fractal_voronoi_x_fx sums its octaves."""
    p = np.random.default_rng(3).uniform(-4, 4, (4000, 3)).astype(np.float32)
    got = dacrt.shading.voronoi_texture(p, 1.5, 1.0, 0.5, 2.0, 1.0, 1.0, 1.0)[0]
    one = ref.voronoi_f1(p * np.float32(1.5), 1.0)[0]
    two = ref.voronoi_f1(p * np.float32(1.5) * np.float32(2.0), 1.0)[0]
    np.testing.assert_allclose(got, one + np.float32(0.5) * two, rtol=1e-6)


def test_bad_node_arguments_are_refused():
    with pytest.raises(ValueError, match="feature must be one of"):
        dacrt.shading.voronoi_texture(np.zeros((3, 3), np.float32), 1, 0, 0.5, 2, 1, 1, 1, 'F3')
    with pytest.raises(ValueError, match="points must have shape"):
        dacrt.shading.voronoi_texture(np.zeros((3, 5), np.float32), 1, 0, 0.5, 2, 1, 1, 1)
