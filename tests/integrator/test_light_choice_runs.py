"""The light choice with a light tree searches its cdf by runs of equal values (LightChoice::
run_cdf, native/cpp/choiceruns.h) instead of entry by entry: every point must pick the entry
std::upper_bound over the whole cdf picks (written out below as libstdc++ runs it, so that even
a cdf that is not sorted, where the runs are not used, is checked), then the tree's member at
the point, with the same selection probability, bit for bit."""
import dacrt
import numpy as np
import pytest
from dacrt import shading

from addon.lights import lamp_records, make_lamp

from .scenes import light, translation
from .test_native_lamps import CENTRE
from .test_next_event import SHORTEN, _points

F32 = np.float32


def _upper_bound(cdf, u):
    """std::upper_bound's halving (libstdc++), comparison for comparison: the first position
    whose value u is below, on any sequence."""
    first, n = 0, len(cdf)
    while n > 0:
        half = n >> 1
        if u < cdf[first + half]:
            n = half
        else:
            first, n = first + half + 1, n - half - 1
    return first


# Entries 0..E-1: point lamps; the tree's members are `members`, the first of which holds the
# tree's mass. Each cdf is one way a light choice's cdf can look.
E = 12
MEMBERS = np.array([3, 4, 5, 7, 8, 10])
_SORTED = np.cumsum([0.1, 0.0, 0.2, 0.3, 0.0, 0.0, 0.15, 0.0, 0.0, 0.1, 0.0, 0.15])
CDFS = {
    # as the add-on builds it (zero-mass lamps and members between lamps with mass), last = 1
    'addon': np.concatenate([_SORTED[:-1], [1.0]]),
    # leading entries without mass, and a last value below 1 (picks past it take the last entry)
    'leading_zeros': np.concatenate([[0.0, 0.0, 0.0], np.cumsum([0.2, 0.0, 0.1, 0.1, 0.0, 0.2, 0.1, 0.0, 0.2])]),
    # one run: all mass on the first entry
    'one_run': np.ones(E),
    # not sorted: no runs, the whole cdf searched as before
    'unsorted': np.array([0.1, 0.4, 0.3, 0.5, 0.5, 0.9, 0.6, 0.7, 0.7, 0.8, 1.0, 1.0]),
    # a NaN in it: no runs either
    'nan': np.concatenate([_SORTED[:5], [np.nan], _SORTED[6:-1], [1.0]]),
}


@pytest.mark.parametrize('name', sorted(CDFS))
def test_light_choice_by_runs_picks_the_whole_cdfs_entry(name):
    cdf = CDFS[name]
    rng = np.random.default_rng(7)
    K = len(MEMBERS)
    pos = rng.normal(size=(3, E)) * 2.0 + np.asarray(CENTRE)[:, None]
    recs = lamp_records([make_lamp(light('POINT', rng.uniform(5, 50), translation(*pos[:, k]))) for k in range(E)])
    p = np.float64(pos[:, MEMBERS].astype(F32))
    tree = dacrt.lamps.light_tree(p, p, np.tile([[0.0], [0.0], [1.0]], K), np.full(K, -1.0), np.zeros(K),
                                  rng.uniform(1.0, 100.0, K), MEMBERS.astype(np.int32))
    prob = rng.uniform(0.05, 0.5, E).astype(F32)
    lc = shading.LightChoice(recs, cdf, prob, np.zeros(E, bool), np.ones(E, bool), tree=tree)
    n = 20_003
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    # the cdf's own values and their neighbours, ends, out of range, signed zero, NaN
    finite = cdf[np.isfinite(cdf)]
    edges = np.concatenate([finite, np.nextafter(finite, -np.inf), np.nextafter(finite, np.inf),
                            [0.0, -0.0, -1.0, 1.0, 2.0, np.inf, -np.inf, np.nan]])
    at = rng.choice(n, 4 * len(edges), replace=False)
    pick[at] = np.repeat(edges, 4)
    entry = np.zeros(n, np.int32)
    got = shading.next_event(lc, P, P_off, ns, ng, th, keys, 0x1234567, 0x89ABCDE, pick=pick, shorten=SHORTEN,
                             skip_work=False, entry=entry)
    want = np.array([min(_upper_bound(cdf, u), E - 1) for u in pick], np.int32)
    p_sel = prob[want].copy()
    member = np.isin(want, MEMBERS)
    e = want[member]
    lo = np.where(e > 0, cdf[np.maximum(e - 1, 0)], 0.0)
    mass = cdf[e] - lo
    with np.errstate(invalid='ignore'):
        u = np.where(mass > 0, (pick[member] - lo) / np.where(mass > 0, mass, 1.0), 0.0)
    key, pt = tree.sample(P_off[:, member], u, N=ns[:, member])
    want[member] = key
    p_sel[member] = (prob[key].astype(np.float64) * pt).astype(F32)
    assert np.array_equal(entry, want)
    # on a sorted cdf every run is picked somewhere: its first entry, or the tree's members
    if (np.diff(cdf) >= 0).all():
        starts = {k for k in range(E) if k == 0 or cdf[k] > cdf[k - 1]}
        assert set(want[~member]) >= starts - set(MEMBERS)
        assert member.any() == bool(starts & set(MEMBERS))
    # the selection probability, as the sample's value carries it
    u1, u2 = shading.uniform2(keys, 0x1234567, 0x89ABCDE)
    wi, value = np.zeros((3, n), F32), np.zeros((3, n), F32)
    dist, pdf = np.zeros(n, F32), np.zeros(n, F32)
    dacrt.lamps.lamp_sample(lc.records, want, P, u1, u2, out=(wi, dist, value, pdf))
    ok = shading.nee_weight(ns, None, wi, pdf, p_sel, th, value)
    value[:, ~ok] = 0.0
    assert np.array_equal(got[0].view(np.uint32), value.view(np.uint32))
