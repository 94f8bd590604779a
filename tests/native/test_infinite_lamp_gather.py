"""lamp_gather of lists of lamps at infinity only (suns and the background: lamps.cpp
gather_infinite, the rays that see a lamp listed 64 at a time, then added) against a float32
numpy reference of gather_one's operations: seen where the ray missed and, for a sun with an
angle, dot(D, pos) >= cos_half (a delta sun never); then the power heuristic
w = 1 / ((p_sel pdf / pdf_bsdf)^2 + 1), v = emit x thr x w, the clamp (|v|_1 > limit: scaled
to it), added to the path's column, lamp after lamp in list order. The sums must be bit for bit
equal: the listing only skips rays that add nothing."""
import dacrt
import numpy as np
import pytest

from addon.lights import lamp_records

from tests.integrator.test_native_lamps import many_lamps

F32 = np.float32
SUN, BACKGROUND = dacrt.lamps.KINDS['SUN'], dacrt.lamps.KINDS['BACKGROUND']


def reference(rec, listed, D, miss, pid, L0, thr=None, pdf_bsdf=None, lamp_prob=None, clamp=np.inf):
    L = L0.copy()
    lay = dacrt.lamps.record_layout()
    field = lambda r, name: r[lay[name][0]:lay[name][0] + lay[name][1]]   # noqa: E731
    for j in listed:
        r = rec[j]
        kind, shape = int(r[lay['kind'][0]]), int(r[lay['shape'][0]])
        pos, cos_half = field(r, 'pos'), field(r, 'cos_half')[0]
        if kind == SUN:
            seen = miss & (shape != 0) & (((D[0] * pos[0] + D[1] * pos[1]) + D[2] * pos[2]) >= cos_half)
        else:
            seen = miss.copy()
        v = np.repeat(field(r, 'emit')[:, None], len(pid), axis=1)
        if thr is not None:
            v = v * thr
        if lamp_prob is not None:
            x = lamp_prob[j] * field(r, 'pdf')[0] / pdf_bsdf
            x = x * x + F32(1.0)
            v = v * (F32(1.0) / x)
        s = (np.abs(v[0]) + np.abs(v[1])) + np.abs(v[2])
        over = s > F32(clamp)
        v[:, over] *= (F32(clamp) / s[over])
        cols = pid[seen]
        L[:, cols] += v[:, seen]
    return L


@pytest.mark.parametrize('listing', ['background', 'sun', 'sun_background', 'many'])
@pytest.mark.parametrize('bsdf', [False, True])
def test_infinite_lamps_gather_as_gather_one(listing, bsdf):
    rng = np.random.default_rng(7 + 2 * len(listing) + bsdf)
    lamps = many_lamps(rng, 60)
    rec = lamp_records(lamps)
    kinds = rec[:, 0].astype(int)
    suns = np.flatnonzero(kinds == SUN)
    cones = [j for j in suns if rec[j, 1] != 0]
    bg = int(np.flatnonzero(kinds == BACKGROUND)[0])
    listed = {'background': [bg], 'sun': [cones[0]], 'sun_background': [cones[1], bg],
              'many': list(suns) + [bg, cones[0]]}[listing]
    listed = np.array(listed, np.int32)
    n, N = 64 * 97 + 13, 9000                      # (a short last group of rays too)
    D = rng.normal(size=(3, n))
    # a third aimed into the listed suns' disks and around their rims
    aim = rng.random(n) < 0.33
    at = rec[rng.choice([j for j in listed if j in cones] or cones, aim.sum()), 5:8].T.astype(np.float64)
    D[:, aim] = at + rng.normal(size=(3, aim.sum())) * rng.choice([0.01, 0.1, 0.5], aim.sum())
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    O = rng.uniform(-5, 5, (3, n)).astype(F32)
    miss = rng.random(n) < 0.6
    t_surf = np.where(miss, np.inf, rng.uniform(0.1, 10.0, n)).astype(F32)
    pid = rng.permutation(N)[:n]
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=rng.uniform(0.05, 1.0, len(lamps)).astype(F32), clamp=3.0)
    L0 = rng.uniform(0.0, 1.0, (3, N)).astype(F32)
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L, **kw)
    ref = reference(rec, listed, D, miss, pid, L0, **kw)
    changed = (ref != L0).any(axis=0)[pid]
    assert changed.sum() > n // 20 and not changed[~miss].any()
    np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))
