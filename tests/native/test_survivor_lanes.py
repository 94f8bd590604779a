"""The survivors' throughputs and hit points computed kSurvivorLanes at a time from the hit-point
records (native survivorlanes.cpp, continue_paths' and shade_bounce's survivor pass) are the
one-at-a-time rows path's bit for bit, on every instruction set: with and without roulette and
throughput, flat, smooth and opposite corner normals, on the inputs the arithmetic branches on
(points on and near edges and corners that inside_edges moves, degenerate, needle and
area-overflowing triangles, t NaN / inf / 0, grazing and opposite directions), and survivor counts
that leave a partial group (run one at a time) or no whole group at all."""
from __future__ import annotations

import dacrt
import numpy as np
import pytest
from dacrt import shading

from tests.native.isaruns import outputs_per_isa
from tests.native.test_hit_records import _bits, _hits, _table

F32 = np.float32

_VARIANTS = [  # (roulette, throughput)
    (True, True), (True, False), (False, True), (False, False)]


def _inputs(seed, m, n, smooth, opposite):
    rng = np.random.default_rng(seed)
    geo, normals = _table(rng, m, smooth, opposite)
    hits, D = _hits(rng, geo, n)
    hit = rng.random(n) < 0.9
    live = rng.random(m) < 0.9
    albedo = rng.random((3, m)).astype(F32)
    thr = (rng.random((3, n)) ** 3).astype(F32)
    thr[:, ::97] = 0.0                                                  # q = 0: no division
    u_rr = rng.random(n).astype(F32)
    return geo, normals, hits, D, hit, live, albedo, thr, u_rr


def _outputs(geo, normals, hits, D, hit, live, albedo, thr, u_rr, records):
    """Every output of continue_paths' survivor pass over each variant, as one uint32 array."""
    parts = []
    for roulette, through in _VARIANTS:
        r = shading.continue_paths(hits, hit, live, albedo, thr if through else None, u_rr if roulette else None,
                                   surface=(geo, normals, D) + ((records,) if records is not None else ()))
        parts += [r[0].astype(np.int64).view(np.uint32), _bits(r[1]).ravel()]
        parts += [_bits(a).ravel() for a in r[4] if a is not None]
        parts.append(r[5].view(np.uint32))
    return np.concatenate(parts)


@pytest.mark.parametrize("smooth, opposite", [(False, False), (True, False), (True, True)])
@pytest.mark.parametrize("n", [50_003, 9])
def test_survivor_lanes_give_the_rows_bits(smooth, opposite, n):
    args = _inputs(40 + smooth + 2 * opposite + n % 7, 400, n, smooth, opposite)
    geo, normals, hits = args[0], args[1], args[2]
    records = shading.hit_records(geo, normals)
    want = _outputs(*args, None)
    got = _outputs(*args, records)
    np.testing.assert_array_equal(got, want)
    if n > 1000:  # the moves inside_edges makes happen in the lanes: P is not the plain interpolation
        k = shading.continue_paths(hits, args[4], args[5], args[6], surface=(geo, normals, args[3], records))
        idx, P = k[0], k[4][0]
        g = geo[:, hits["prim"][idx]]
        plain = g[3:6] * hits["u"][idx]
        plain += g[6:9] * hits["v"][idx]
        plain += g[0:3]
        assert 0.05 < (P != plain).any(axis=0).mean() < 0.9 and len(idx) % 16 != 0


_SCRIPT = """
import sys
import numpy as np
from dacrt import shading
from tests.native.test_survivor_lanes import _outputs
a = [np.load(f) for f in sys.argv[1:-1]]
geo, normals = a[0], (a[1] if a[1].size else None)
np.save(sys.argv[-1], _outputs(geo, normals, *a[2:], shading.hit_records(geo, normals)))
"""


@pytest.mark.parametrize("smooth", [False, True])
def test_survivor_lanes_agree_on_every_instruction_set(smooth):
    args = _inputs(60 + smooth, 300, 20_011, smooth, smooth)
    geo, normals = args[0], args[1]
    want = _outputs(*args, None)
    per_isa = outputs_per_isa(_SCRIPT, geo, normals if smooth else np.zeros(0, F32), *args[2:])
    assert set(per_isa) == set(dacrt.supported_isas()) and len(per_isa) >= 1
    for isa, got in per_isa.items():
        np.testing.assert_array_equal(got, want, err_msg=isa)
