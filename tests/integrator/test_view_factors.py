"""The view a hit carries to the Fresnel and Layer Weight nodes (viewside.Facing: the side
array with the rays' incoming directions, which follow the hits as the integrator splits them)
and the nodes' per-point values (fresnel.fresnel_node, layer_weight) against Fresnel's
equations from Snell's law and the Facing output's closed form."""
from __future__ import annotations

import numpy as np
import pytest

from addon import fresnel
from addon.pathstate import compact
from addon.viewside import Facing, incoming_of, length_of


# float32, as Cycles computes: just past the critical angle of total internal reflection the
# reflectance's square-root edge turns a rounding of the cosine into some 1e-5
ATOL = 5e-5


def _snell(mu, n):
    """Unpolarised reflectance from index 1 into n (n < 1: from inside), float64."""
    sin_t2 = (1.0 - mu * mu) / (n * n)
    out = np.ones_like(mu)
    ok = sin_t2 < 1.0
    ct, ci = np.sqrt(1.0 - sin_t2[ok]), mu[ok]
    out[ok] = 0.5 * (((ci - n * ct) / (ci + n * ct)) ** 2 + ((n * ci - ct) / (n * ci + ct)) ** 2)
    return out


def _facing(k=7):
    back = np.arange(k) % 3 == 0
    incoming = np.arange(3 * k, dtype=np.float32).reshape(3, k)
    return Facing.of(back, incoming, 10.0 + np.arange(k)), back, incoming


def test_the_incoming_directions_follow_take_slices_and_masks():
    f, back, incoming = _facing()
    sel = np.array([5, 0, 3])
    for got, cols in ((np.take(f, sel), sel), (f[2:6], slice(2, 6)), (f[back], back), (f[sel], sel)):
        assert isinstance(got, Facing)
        np.testing.assert_array_equal(np.asarray(got), back[cols])
        np.testing.assert_array_equal(incoming_of(got), incoming[:, cols])
        np.testing.assert_array_equal(length_of(got), (10.0 + np.arange(7))[cols])
    assert length_of(np.take(Facing.of(back, incoming), sel)) is None       # (no lengths given: none)
    # taken twice (a material's hits, then a chunk of them)
    np.testing.assert_array_equal(incoming_of(np.take(f, sel)[1:]), incoming[:, sel[1:]])


def test_other_arrays_made_from_it_carry_no_view():
    f, back, _ = _facing()
    for other in (~f, f & True, f[:, None], np.where(f, 1, 0)):
        assert incoming_of(other) is None and length_of(other) is None
    assert bool(f[0]) is True and np.where(f, -1.0, 1.0).tolist() == np.where(back, -1.0, 1.0).tolist()
    assert incoming_of(np.asarray(back)) is None and incoming_of(None) is None


def test_the_native_take_drops_the_view():
    """(why SurfaceValues._transparency takes a Facing with np.take, not compact)"""
    f, _, _ = _facing()
    assert incoming_of(compact(np.array([1, 2], np.int64), f)[0]) is None


@pytest.mark.parametrize('ior', [1.1, 1.45, 3.0])
def test_fresnel_node_front_and_back(ior):
    mu = np.linspace(0.02, 1.0, 200)
    front = fresnel.fresnel_node(mu, ior, np.zeros(len(mu), bool))
    back = fresnel.fresnel_node(mu, ior, np.ones(len(mu), bool))
    assert front.dtype == np.float32
    np.testing.assert_allclose(front, _snell(mu, ior), atol=ATOL)
    np.testing.assert_allclose(back, _snell(mu, 1.0 / ior), atol=ATOL)      # from inside: 1 / IOR
    # the sign of the cosine does not matter (a smooth normal turned from the view)
    np.testing.assert_array_equal(fresnel.fresnel_node(-mu, ior, np.zeros(len(mu), bool)), front)


@pytest.mark.parametrize('blend', [0.1, 0.3, 0.5, 0.8])
def test_layer_weight_per_point(blend):
    mu = np.linspace(0.02, 1.0, 200)
    none, every = np.zeros(len(mu), bool), np.ones(len(mu), bool)
    eta = 1.0 / (1.0 - blend)
    np.testing.assert_allclose(fresnel.layer_weight(mu, blend, 'Fresnel', none), _snell(mu, eta), atol=ATOL)
    np.testing.assert_allclose(fresnel.layer_weight(mu, blend, 'Fresnel', every), _snell(mu, 1.0 / eta), atol=ATOL)
    p = 2.0 * blend if blend < 0.5 else 0.5 / (1.0 - blend)
    for side in (none, every):
        np.testing.assert_allclose(fresnel.layer_weight(mu, blend, 'Facing', side), 1.0 - mu ** p, atol=ATOL)
    # the per-point values average (by cos) to the averages the evaluation used
    grid = np.linspace(0.0, 1.0, 200_001)
    for out in ('Fresnel', 'Facing'):
        values = fresnel.layer_weight(grid, blend, out, np.zeros(len(grid), bool)).astype(np.float64)
        assert np.trapz(2.0 * values * grid, grid) == pytest.approx(fresnel.layer_weight_average(blend, out), abs=2e-4)
