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


def _tree_choice(cdf, members=MEMBERS):
    """A LightChoice over E point lamps with a tree over members and the given cdf."""
    rng = np.random.default_rng(3)
    K = len(members)
    pos = rng.normal(size=(3, E)) * 2.0 + np.asarray(CENTRE)[:, None]
    recs = lamp_records([make_lamp(light('POINT', 20.0, translation(*pos[:, k]))) for k in range(E)])
    p = np.float64(pos[:, members].astype(F32))
    tree = dacrt.lamps.light_tree(p, p, np.tile([[0.0], [0.0], [1.0]], K), np.full(K, -1.0), np.zeros(K),
                                  rng.uniform(1.0, 100.0, K), np.asarray(members, np.int32))
    return shading.LightChoice(recs, cdf, np.full(E, 0.1, F32), np.zeros(E, bool), np.ones(E, bool), tree=tree)


def _entries(lc, pick, runs):
    """The entries next_event picks at len(pick) points, the kernel given runs (None: it
    builds them from the cdf itself, as every call did before the choice kept them)."""
    rng = np.random.default_rng(5)
    n = len(pick)
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    value, contrib = np.empty((3, n), F32), np.empty(n, bool)
    rays, send = np.empty(n, shading.RAY_DTYPE), np.empty(n, np.int64)
    entry = np.zeros(n, np.int32)
    dacrt._core.next_event(lc.records, lc.cdf, lc.prob, lc.no_mis, lc.shadow, None, None, None, None, P, P_off, ns,
                           ng, th, keys, 1, 2, np.asarray(pick, np.float64), None, float(SHORTEN), False, value,
                           contrib, rays, send, None, None, entry=entry, tree=lc.tree, runs=runs)
    return entry


def test_light_choice_builds_its_runs_once_per_cdf_and_the_kernels_search_them():
    """The runs are the frame's (LightChoice.runs, built on first use from its cdf), not each
    kernel call's: a million emissive triangles in a tree had been a scan of ~1M doubles per
    call. The kernel searches the runs it is given: a cdf unsorted inside a run (which the
    kernel's own build leaves without runs, searching every entry) picks by the runs given."""
    cdf = CDFS['addon']
    lc = _tree_choice(cdf)
    run_cdf, run_entry = lc.runs
    starts = [k for k in range(E) if k == 0 or cdf[k] > cdf[k - 1]]
    assert run_entry.dtype == np.uint32 and list(run_entry) == starts
    assert np.array_equal(run_cdf.view(np.uint64), cdf[starts].view(np.uint64))
    assert lc.runs is lc.runs                       # built once
    # the cdf is the choice's own read-only copy: changed in place it would leave the runs stale
    assert not lc.cdf.flags.writeable and not np.shares_memory(lc.cdf, cdf)
    with pytest.raises(ValueError):
        lc.cdf[3] = 0.5
    # replaced, it gets its runs anew
    lc.cdf = CDFS['leading_zeros']
    assert list(lc.runs[1]) == [0, 3, 5, 6, 8, 9, 11]
    assert list(lc.runs[0]) == list(CDFS['leading_zeros'][[0, 3, 5, 6, 8, 9, 11]])
    assert _core_runs(CDFS['unsorted']) == ([], [])
    assert _core_runs(CDFS['nan']) == ([], [])
    # given runs are what the kernel searches: 0.4 falls in run 1 (entry 1); the whole
    # cdf's upper_bound, past the dip at entry 6, lands on entry 7 (the tree is over 9, 10)
    bent = np.array([0.2, 0.5, 0.5, 0.5, 0.5, 0.5, 0.3, 0.5, 0.5, 0.5, 0.5, 1.0])
    lc = _tree_choice(bent, members=[9, 10])
    whole = [_upper_bound(bent, u) for u in (0.4, 0.1)]
    assert whole == [7, 0]
    runs = (np.array([0.2, 0.5, 1.0]), np.array([0, 1, 11], np.uint32))
    assert list(_entries(lc, [0.4, 0.1], runs)) == [1, 0]
    assert list(_entries(lc, [0.4, 0.1], None)) == whole


def _core_runs(cdf):
    run_cdf, run_entry = dacrt._core.choice_runs(np.asarray(cdf, np.float64))
    return list(run_cdf), list(run_entry)


_C = CDFS['addon']     # runs start at entries 0, 2, 3, 6, 9, 11


@pytest.mark.parametrize('runs,says', [
    ((_C[[0, 2]], np.array([0, 2, 3], np.uint32)), 'run_entry'),
    ((_C[[2, 3]], np.array([2, 3], np.uint32)), 'the first run starts at entry 2, not 0'),
    ((_C[[0, 2, 2]], np.array([0, 2, 2], np.uint32)), "run 2 (entry 2): the runs' entries must increase"),
    ((_C[[0, 2, 11]], np.array([0, 2, 99], np.uint32)), "run 2 (entry 99): the runs' entries must increase"),
    ((np.array([_C[0], 0.35, _C[3]]), np.array([0, 2, 3], np.uint32)), "run 1 (entry 2): its value is not the cdf's"),
    ((_C[[0, 3]], np.array([0, 3], np.uint32)), 'run 1 (entry 3): the previous run does not end'),
    ((_C[[0, 2, 3]], np.array([0, 2, 3], np.uint32)), 'the last run does not reach the last entry'),
    ((_C[[0]], np.array([0], np.uint32), np.array([0])), 'runs is (run_cdf, run_entry)'),
    ((_C[[0, 2, 3, 6, 9, 11, 11]], np.array([0, 2, 3, 6, 9, 11, 12], np.uint32)), 'run 6 (entry 12)'),
])
def test_runs_that_are_not_the_cdfs_are_refused(runs, says):
    """Runs passed to a kernel are checked against its cdf (O(runs)), the message saying which
    run is wrong and how."""
    lc = _tree_choice(CDFS['addon'])
    with pytest.raises(ValueError) as err:
        _entries(lc, [0.5], runs)
    assert says in str(err.value)
    assert list(_entries(lc, [0.5], lc.runs)) == list(_entries(lc, [0.5], None))
