"""The fused next-event kernel (dacrt.shading.next_event) against the kernels it replaces,
composed as the integrator used to compose them: uniform2 for the light position, the light
choice by searchsorted on the CDF, lamp_sample for lamps, sample_triangles (value = emission /
pdf) for emissive triangles, pdf = inf for entries without MIS, nee_weight (without the
geometric-normal test: Cycles leaves samples below it to the shadow ray), shadow_rays. Both
run the same float32 arithmetic, so the results must be bit for bit the same. Also
accumulate_masked, and the argument checks."""
import dacrt
import numpy as np
import pytest
from dacrt import shading

from addon.lights import lamp_records, make_lamp
from addon.lights.base import RECORD_WIDTH

from ..native.test_shading import _geo, _unit
from .scenes import light, translation
from .test_native_lamps import CENTRE, NAMES, TILT, make, points

F32 = np.float32
SHORTEN = F32(1.0 - 2.0 ** -16)


def _lights(rng, lamps: bool, triangles: bool):
    """A LightChoice over every lamp variant and/or 40 emissive triangles near the lamps, with
    random selection probabilities and no-MIS / shadow flags."""
    recs = lamp_records([make(name) for name in NAMES]) if lamps else np.zeros((0, RECORD_WIDTH), F32)
    T = 40 if triangles else 0
    geo, area = _geo(rng, T, scale=0.8) if T else (None, None)
    if T:
        geo[0:3] += np.array([0.3, -0.7, 1.2], F32)[:, None]      # around the lamps' centre
    emission = rng.uniform(0.5, 20.0, (3, T)).astype(F32) if T else None
    E = len(recs) + T
    p = rng.uniform(0.2, 1.0, E)
    p /= p.sum()
    cdf = np.cumsum(p)
    cdf[-1] = 1.0
    no_mis = rng.random(E) < 0.3
    shadow = rng.random(E) < 0.8
    no_mis[len(recs):] = False                                      # as the integrator: triangles use MIS
    shadow[len(recs):] = True
    return shading.LightChoice(recs, cdf, p.astype(F32), no_mis, shadow, geo, area, emission)


def _composed(lc, P, P_off, ns, ng, thr, keys, ka, kb, pick, prim, skip_work):
    """The pre-fusion integrator code path (value, contrib, rays, send, skip, skipped)."""
    n = P.shape[1]
    R = len(lc.records)
    u1, u2 = shading.uniform2(keys, ka, kb)
    entry = np.zeros(n, np.int32) if pick is None else \
        np.minimum(np.searchsorted(lc.cdf, pick, side='right'), lc.entries - 1).astype(np.int32)
    wi, value = np.zeros((3, n), F32), np.zeros((3, n), F32)
    dist, pdf = np.zeros(n, F32), np.zeros(n, F32)
    target = np.full((3, n), np.nan, F32)
    if R:
        dacrt.lamps.lamp_sample(lc.records, entry, P, u1, u2, out=(wi, dist, value, pdf))
    tri = np.flatnonzero(entry >= R)
    if len(tri):
        w = entry[tri] - R
        twi, tdist, tpdf, ttarget = shading.sample_triangles(lc.tri_geo, lc.tri_area, w, P[:, tri], u1[tri], u2[tri])
        with np.errstate(divide='ignore'):
            scale = np.where(tpdf > 0, F32(1.0) / tpdf, F32(0.0))
        wi[:, tri], dist[tri], pdf[tri], target[:, tri] = twi, tdist, tpdf, ttarget
        value[:, tri] = lc.tri_emission[:, w] * scale
    pdf[lc.no_mis[entry]] = np.inf
    # no geometric-normal test (ng None): as Cycles, the shadow ray decides below ng
    ok = shading.nee_weight(ns, None, wi, pdf, lc.prob[entry], thr, value)
    if not skip_work:
        value[:, ~ok] = 0.0
        ok = np.ones(n, bool)
    shadow = lc.shadow[entry]
    send = np.flatnonzero(ok & shadow)
    # a ray toward the back of the geometric surface leaves from the mirrored step P + (P - P_off)
    g = ns if ng is None else ng
    back = (g[0] * wi[0] + g[1] * wi[1]) + g[2] * wi[2] < 0
    O = np.where(back, P + (P - P_off), P_off).astype(F32)
    rays, valid = shading.shadow_rays(O, wi, dist, target, send, SHORTEN)
    contrib = ok.copy()
    contrib[send[~valid]] = False
    rays, send = rays[valid], send[valid]
    rays['id'] = np.arange(len(send), dtype=np.uint32)
    return value, contrib, rays, send, None if prim is None else prim[send], n - int(np.count_nonzero(ok))


def _points(rng, n, *, flat: bool, thr: bool):
    P = points(rng, n)
    ng = _unit(rng, n)
    ns = ng if flat else _unit(rng, n)
    P_off = P + F32(1e-4) * ng
    keys = np.stack([rng.integers(0, 2**32, n, dtype=np.uint32), rng.integers(0, 4096, n, dtype=np.uint32)])
    return P, P_off, ns, None if flat else ng, rng.uniform(0.0, 1.5, (3, n)).astype(F32) if thr else None, keys


@pytest.mark.parametrize('lamps,triangles', [(True, True), (True, False), (False, True)])
@pytest.mark.parametrize('flat,thr,skip_work', [(False, True, True), (True, False, True), (False, True, False)])
def test_next_event_equals_the_composed_kernels(lamps, triangles, flat, thr, skip_work):
    rng = np.random.default_rng(11 + 2 * lamps + triangles)
    lc = _lights(rng, lamps, triangles)
    n = 30_000
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=flat, thr=thr)
    pick = rng.random(n)
    prim = rng.integers(0, 1000, n).astype(np.int32)
    ka, kb = 0x1234567, 0x89ABCDE
    got = shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick, prim=prim, shorten=SHORTEN,
                             skip_work=skip_work)
    ref = _composed(lc, P, P_off, ns, ng, th, keys, ka, kb, pick, prim, skip_work)
    for name, a, b in zip(('value', 'contrib', 'rays', 'send', 'skip'), got[:5], ref[:5]):
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f'{name} differs'
    assert got[5] == ref[5]
    # the case mix the comparison covers: every outcome occurs
    value, contrib, rays, send, skip, skipped = got
    assert len(send) and contrib.any()
    if skip_work:
        assert skipped > 0 and (~contrib).any() and len(send) < n
    else:
        assert skipped == 0
    if lamps:
        assert (contrib & ~np.isin(np.arange(n), send)).any(), 'no sample that needs no shadow ray'


def test_point_is_each_triangle_samples_target():
    """point (3, n) gets, for the points that picked an emissive triangle, the sampled point's
    target (what an image emission is read at): sample_triangles' target for the same uniforms,
    bit for bit; other columns are left as they were. The rest of the outputs do not change."""
    rng = np.random.default_rng(5)
    lc = _lights(rng, True, True)
    n = 20_000
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    ka, kb = 0x1234567, 0x89ABCDE
    entry = np.empty(n, np.int32)
    point = np.full((3, n), 7.0, F32)
    got = shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick, entry=entry, point=point)
    plain = shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick)
    for a, b in zip(got[:4], plain[:4]):
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8))
    R = len(lc.records)
    tri = np.flatnonzero(entry >= R)
    assert 0 < len(tri) < n
    u1, u2 = shading.uniform2(keys, ka, kb)
    target = shading.sample_triangles(lc.tri_geo, lc.tri_area, entry[tri] - R, P[:, tri], u1[tri], u2[tri])[3]
    assert np.array_equal(point[:, tri], target)
    assert np.all(np.delete(point, tri, axis=1) == 7.0)
    with pytest.raises(ValueError, match="point must be a writeable C-contiguous float32"):
        shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick, point=np.zeros((3, n)))


def test_a_point_on_an_emissive_triangle_is_not_lit_by_it():
    """tri_prim names the triangle each emissive entry is: a point whose prim is the triangle it
    picked adds nothing and traces no ray (value 0, contrib False, counted as skipped); every
    other point's outputs are those of the call without tri_prim, bit for bit."""
    rng = np.random.default_rng(8)
    lc = _lights(rng, True, True)
    R, T = len(lc.records), lc.tri_geo.shape[1]
    n = 20_000
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    ka, kb = 0x1234567, 0x89ABCDE
    tri_prim = rng.permutation(1000)[:T].astype(np.int32)          # the emitters among 1000 triangles
    entry = np.empty(n, np.int32)
    plain = shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick,
                               prim=rng.integers(0, 1000, n).astype(np.int32), entry=entry)
    # half the points that pick a triangle lie on it; the rest, and those picking lamps, elsewhere
    own = (entry >= R) & (rng.random(n) < 0.5)
    prim = np.where(own, tri_prim[np.clip(entry - R, 0, T - 1)], 1000 + rng.integers(0, 1000, n)).astype(np.int32)
    base = shading.next_event(lc, P, P_off, ns, ng, th, keys, ka, kb, pick=pick, prim=prim)
    mine = shading.LightChoice(lc.records, lc.cdf, lc.prob, lc.no_mis, lc.shadow, lc.tri_geo, lc.tri_area,
                               lc.tri_emission, tri_prim=tri_prim)
    got = shading.next_event(mine, P, P_off, ns, ng, th, keys, ka, kb, pick=pick, prim=prim)
    assert own.sum() > 100 and (base[1] & own).any()
    assert not got[0][:, own].any() and not got[1][own].any() and not np.isin(np.flatnonzero(own), got[3]).any()
    assert np.array_equal(got[0][:, ~own], base[0][:, ~own]) and np.array_equal(got[1][~own], base[1][~own])
    assert got[5] == base[5] + int(np.count_nonzero(base[1] & own))
    assert plain[1].any()
    with pytest.raises(ValueError, match="tri_prim"):
        shading.next_event(shading.LightChoice(lc.records, lc.cdf, lc.prob, lc.no_mis, lc.shadow, lc.tri_geo,
                                               lc.tri_area, lc.tri_emission, tri_prim=tri_prim[:-1]),
                           P, P_off, ns, ng, th, keys, ka, kb, pick=pick, prim=prim)


def test_light_linking_rejects_the_samples_of_lights_a_point_does_not_receive():
    """linking = (light set per entry, receiver mask per point): a sample of an entry whose set
    the point does not receive adds nothing and traces no ray; every other sample, and its
    shadow ray, is bit for bit what the unlinked call gives (the same pick, the same numbers)."""
    rng = np.random.default_rng(17)
    lc = _lights(rng, True, True)
    n = 20_000
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    prim = rng.integers(0, 1000, n).astype(np.int32)
    light_set = rng.integers(0, 3, lc.entries).astype(np.uint8)
    light_set[5] = 63
    receivers = rng.integers(0, 2 ** 63, n, dtype=np.uint64) | np.uint64(1)      # set 0: everyone
    args = (lc, P, P_off, ns, ng, th, keys, 7, 9)
    kw = dict(pick=pick, prim=prim, shorten=SHORTEN)
    free = shading.next_event(*args, **kw)
    linked = shading.next_event(*args, **kw, linking=(light_set, receivers))
    entry = np.minimum(np.searchsorted(lc.cdf, pick, side='right'), lc.entries - 1)
    reached = ((receivers >> light_set[entry].astype(np.uint64)) & np.uint64(1)) == 1
    assert 0.2 < reached.mean() < 0.95
    assert np.array_equal(linked[0][:, reached], free[0][:, reached]) and not linked[0][:, ~reached].any()
    assert np.array_equal(linked[1], free[1] & reached)
    keep = reached[free[3]]
    assert np.array_equal(linked[3], free[3][keep]) and np.array_equal(linked[4], free[4][keep])
    same = free[2][keep].copy()
    same['id'] = np.arange(len(same), dtype=np.uint32)
    assert np.array_equal(linked[2], same)
    picked = np.full(n, -7, np.int32)                        # the entries, for light groups
    shading.next_event(*args, **kw, entry=picked)
    assert np.array_equal(picked, entry)
    with pytest.raises(ValueError, match='entry'):
        shading.next_event(*args, **kw, entry=np.empty(n, np.int64))
    everyone = shading.next_event(*args, **kw, linking=(np.zeros(lc.entries, np.uint8), np.ones(n, np.uint64)))
    for a, b in zip(everyone[:5], free[:5]):
        assert np.array_equal(a, b)
    with pytest.raises(ValueError, match='light set'):
        shading.next_event(*args, **kw, linking=(np.full(lc.entries, 64, np.uint8), receivers))
    with pytest.raises(ValueError, match='receivers'):
        shading.next_event(*args, **kw, linking=(light_set, receivers[:10]))


def test_single_light_needs_no_pick_and_more_lights_do():
    rng = np.random.default_rng(5)
    rec = lamp_records([make('area_square')])
    one = shading.LightChoice(rec, [1.0], [1.0], [False], [True])
    n = 2000
    P, P_off, ns, ng, thr, keys = _points(rng, n, flat=True, thr=True)
    got = shading.next_event(one, P, P_off, ns, ng, thr, keys, 3, 4)
    ref = _composed(one, P, P_off, ns, ng, thr, keys, 3, 4, None, None, True)
    assert got[4] is None
    for a, b in zip(got[:4], ref[:4]):
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8))
    lc = _lights(rng, True, True)
    with pytest.raises(ValueError, match='pick'):
        shading.next_event(lc, P, P_off, ns, ng, thr, keys, 3, 4)


@pytest.mark.parametrize('name', ['area_square', 'area_rectangle', 'area_disk', 'area_ellipse',
                                  'area_rectangle_unnormalized', 'area_square_spread', 'sheared'])
@pytest.mark.parametrize('thr,no_mis', [(True, False), (False, True)])
def test_one_area_lamp_drawn_lane_by_lane_equals_the_composed_kernels(name, thr, no_mis):
    """next_event draws the samples of points that picked an area lamp and weights them
    eight points at a time (native/cpp/arealanes.h): bit for bit lamp_sample + nee_weight +
    shadow_rays, where the lamp looks small (drawn by area) and large (by solid angle), for
    points behind it, on its plane, at its centre, at its corners, far off or not finite, and a
    point count that is no multiple of eight (the last group repeats its last point)."""
    rng = np.random.default_rng(len(name) + 7 * thr)
    lamp = make(name) if name != 'sheared' else make_lamp(light('AREA', (4.0, 2.0, 1.0),
                                                                 np.diag([1.0, 2.5, 0.4, 1.0]) @ TILT, shape='SQUARE'))
    rec = lamp_records([lamp])
    one = shading.LightChoice(rec, [1.0], [1.0], [no_mis], [True])
    n = 20_003
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=thr)
    r = rec[0]
    pos, ax, ay, normal = r[5:8], r[14:17], r[17:20], r[26:29]
    special = [pos, pos + 0.5 * ax + 0.5 * ay, pos + 0.3 * ax, pos + 0.5 * ax + 1e-3 * normal,
               pos + 1e-6 * normal, pos - 0.2 * normal, pos + 1e6 * normal + 3e5 * ax, pos + 0.01 * normal,
               [np.nan, 0.0, 0.0], [np.inf, 1.0, 2.0], pos + 40.0 * ay + 0.1 * normal]
    P[:, :len(special)] = np.asarray(special, F32).T
    P_off[:, :len(special)] = P[:, :len(special)]
    # near the lamp, where it is large: sampled by solid angle there
    near = slice(len(special), 4000)
    P[:, near] = (pos[:, None] + ax[:, None] * rng.uniform(-1, 1, 4000 - len(special)).astype(F32)
                  + normal[:, None] * rng.uniform(-0.05, 0.6, 4000 - len(special)).astype(F32))
    P_off[:, near] = P[:, near]
    with np.errstate(invalid='ignore', over='ignore'):
        got = shading.next_event(one, P, P_off, ns, ng, th, keys, 3, 4)
        ref = _composed(one, P, P_off, ns, ng, th, keys, 3, 4, None, None, True)
        picked = shading.next_event(one, P, P_off, ns, ng, th, keys, 3, 4, pick=rng.random(n))  # by the table
    for name_, a, b, c in zip(('value', 'contrib', 'rays', 'send'), got[:4], ref[:4], picked[:4]):
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f'{name_} differs from the composed kernels'
        assert np.array_equal(a.view(np.uint8), c.view(np.uint8)), f'{name_} differs when picked by the table'
    assert got[5] == ref[5] and 0 < got[5] < n
    if getattr(lamp, 'solid_angle', False) and lamp.tan_half_spread is None:   # both draws occurred
        with np.errstate(invalid='ignore', over='ignore'):
            use = lamp._sph_rect(P, -0.5, 0.5, -0.5, 0.5)['use']
        assert 0.05 < use.mean() < 0.95


@pytest.mark.parametrize('flat', [True, False])
@pytest.mark.parametrize('shadow,skip_work', [(True, True), (True, False), (False, True)])
def test_chunks_drawn_whole_in_lanes_equal_the_composed_kernels(flat, shadow, skip_work):
    """A chunk whose every point drew its sample in lanes (one area lamp without spread) takes a
    loop of its own without a branch per point (nextevent.cpp drawn_points: a ray written at the
    next place for every point, counted where it is traced): bit for bit the composed kernels, for
    a lamp with and without shadow rays, with and without skip_work, flat and smooth points, the
    skip triangles, points toward the back of their surface, on the lamp (zero-length rays) and
    behind it, over several blocks of shadow rays."""
    rng = np.random.default_rng(71 + 2 * flat + 4 * shadow + 8 * skip_work)
    rec = lamp_records([make('area_rectangle')])
    one = shading.LightChoice(rec, [1.0], [1.0], [False], [shadow])
    n = 3 * 4096 + 517
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=flat, thr=True)
    r = rec[0]
    pos, ax, normal = r[5:8], r[14:17], r[26:29]
    special = [pos, pos + 0.3 * ax, pos + 1e-6 * normal, pos - 0.2 * normal, pos + 0.01 * normal]
    P[:, :len(special)] = np.asarray(special, F32).T
    P_off[:, :len(special)] = P[:, :len(special)]
    prim = rng.integers(0, 1000, n).astype(np.int32)
    with np.errstate(invalid='ignore', over='ignore'):
        got = shading.next_event(one, P, P_off, ns, ng, th, keys, 3, 4, prim=prim, skip_work=skip_work)
        ref = _composed(one, P, P_off, ns, ng, th, keys, 3, 4, None, prim, skip_work)
    for name, a, b in zip(('value', 'contrib', 'rays', 'send', 'skip'), got[:5], ref[:5]):
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f'{name} differs'
    assert got[5] == ref[5]
    value, contrib, rays, send, skip, skipped = got
    assert contrib.any() and (len(send) > 0) == shadow
    if shadow and not flat:   # some rays leave from the mirrored step (toward the back of their surface)
        assert (rays['org'] != P_off[:, send].T).any(axis=1).any()
    if skip_work:
        assert 0 < skipped < n and (~contrib).any()
    else:
        assert skipped == 0


def test_next_event_checks_its_arguments():
    rng = np.random.default_rng(6)
    lc = _lights(rng, True, True)
    n = 100
    P, P_off, ns, ng, thr, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    call = lambda lights=lc, **kw: shading.next_event(lights, **{**dict(
        P=P, P_off=P_off, ns=ns, ng=ng, thr=thr, keys=keys, ka=1, kb=2, pick=pick), **kw})
    with pytest.raises(ValueError, match='P_off'):
        call(P_off=P_off[:, :50])
    with pytest.raises(ValueError, match='pick'):
        call(pick=pick[:50])
    with pytest.raises(ValueError, match='keys'):
        call(keys=keys[:1])
    bad = shading.LightChoice(lc.records, lc.cdf[:-1], lc.prob, lc.no_mis, lc.shadow, lc.tri_geo, lc.tri_area,
                              lc.tri_emission)
    with pytest.raises(ValueError, match='cdf'):
        call(bad)
    half = shading.LightChoice(lc.records, lc.cdf, lc.prob, lc.no_mis, lc.shadow, lc.tri_geo, None, None)
    with pytest.raises(ValueError, match='go together'):
        call(half)
    broken = lc.records.copy()
    broken[0, 0] = 99.0                                             # not a lamp kind
    with pytest.raises(ValueError, match='records\\[0\\]'):
        call(shading.LightChoice(broken, lc.cdf, lc.prob, lc.no_mis, lc.shadow, lc.tri_geo, lc.tri_area,
                                 lc.tri_emission))
    empty = shading.LightChoice(np.zeros((0, RECORD_WIDTH), F32), [], [], [], [])
    with pytest.raises(ValueError, match='no light'):
        call(empty, pick=None)


def test_accumulate_masked_adds_selected_columns():
    rng = np.random.default_rng(8)
    N, n = 500, 300
    L = rng.random((3, N)).astype(F32)
    pid = rng.permutation(N)[:n].astype(np.int64)
    values = rng.random((3, n)).astype(F32)
    mask = rng.random(n) < 0.6
    want = L.copy()
    want[:, pid[mask]] += values[:, mask]
    shading.accumulate_masked(L, pid, values, mask)
    assert np.array_equal(L, want)
    before = L.copy()
    for column in (N, -1):
        bad = pid.copy()
        bad[np.flatnonzero(~mask)[0]] = column                     # even where the mask is clear
        with pytest.raises(ValueError, match='outside'):
            shading.accumulate_masked(L, bad, values, mask)
        assert np.array_equal(L, before), 'a refused call changed L'


@pytest.mark.parametrize('where', [0, 1, 8, 4097, -2, -1])
@pytest.mark.parametrize('column', ['N', -1, 'huge'])
def test_accumulate_masked_refuses_any_id_out_of_range_wherever_it_sits(where, column):
    """The id check (one vectorised pass on the calling thread, nextevent.cpp ids_in_range)
    finds a bad id at the start, inside and at the tail of its vectors, on every batch size of
    a render (here 2^15 + 3 ids: split over the threads for the adds), and leaves L as it was."""
    rng = np.random.default_rng(12)
    N, n = 70000, 2 ** 15 + 3
    L = rng.random((3, N)).astype(F32)
    pid = rng.permutation(N)[:n].astype(np.int64)
    values = rng.random((3, n)).astype(F32)
    mask = rng.random(n) < 0.5
    before = L.copy()
    pid[where] = {'N': N, -1: -1, 'huge': 2 ** 62}[column]
    with pytest.raises(ValueError, match='outside'):
        shading.accumulate_masked(L, pid, values, mask)
    assert np.array_equal(L, before), 'a refused call changed L'
    pid[where] = np.setdiff1d(np.arange(N), pid)[0]            # a column no other id holds: accepted
    want = L.copy()
    want[:, pid[mask]] += values[:, mask]
    shading.accumulate_masked(L, pid, values, mask)
    assert np.array_equal(L, want)


def test_accumulate_masked_threads_blocks_and_refuses_copies():
    """Enough columns for the threaded path; L may be the rows of a larger block (the integrator
    adds into rgba[:3]); an L that would have to be converted is refused, not silently copied."""
    rng = np.random.default_rng(10)
    N = 300_000
    L = rng.random((3, N)).astype(F32)
    pid = rng.permutation(N).astype(np.int64)
    values = rng.random((3, N)).astype(F32)
    mask = rng.random(N) < 0.5
    want = L.copy()
    want[:, pid[mask]] += values[:, mask]
    shading.accumulate_masked(L, pid, values, mask)
    np.testing.assert_array_equal(L, want)
    rgba = np.zeros((4, 10), F32)
    shading.accumulate_masked(rgba[:3], np.array([3]), np.ones((3, 1), F32), np.array([True]))
    assert rgba[:3, 3].tolist() == [1, 1, 1] and rgba[3].sum() == 0
    with pytest.raises(ValueError, match="L must be a C-contiguous"):
        shading.accumulate_masked(np.zeros((3, 10)), np.array([0]), np.ones((3, 1), F32), np.array([True]))


def test_bump_shadowing_closed_form_and_native_agree():
    """Cycles' bump_shadowing_term for a normal bent 45 degrees from the smooth one, light 35
    degrees off the smooth normal: 2 / (1 + sqrt(1 + tan^2(35) / 8)) = 0.98513 (measured in
    Cycles: 0.98514), at 60 degrees 0.92055 (Cycles 0.92051); 1 without correction or an
    unbent normal, 0 with the light past the smooth surface. next_event's bump input gives
    light samples the same factor as the integrator's numpy function gives bounces."""
    from addon.integrator import bump_shadowing
    from addon.lights import make_lamp
    from .scenes import light, rotation_x
    s45, c45 = np.sin(np.pi / 4), np.cos(np.pi / 4)
    Ns = np.array([[0.0], [0.0], [1.0]], F32)
    N = np.array([[s45], [0.0], [c45]], F32)
    at = lambda deg: np.array([[np.sin(np.radians(deg))], [0.0], [np.cos(np.radians(deg))]], F32)
    assert bump_shadowing(Ns, N, at(35), np.array([True]))[0] == pytest.approx(0.98513, abs=2e-5)
    assert bump_shadowing(Ns, N, at(60), np.array([True]))[0] == pytest.approx(0.92055, abs=2e-5)
    assert bump_shadowing(Ns, N, at(35), np.array([False]))[0] == 1.0
    assert bump_shadowing(Ns, Ns, at(80), np.array([True]))[0] == 1.0
    assert bump_shadowing(Ns, N, at(-60), np.array([True]))[0] == 0.0   # above the smooth surface, below N
    # native, on a delta sun: the ratio of samples with and without bump is the factor
    rng = np.random.default_rng(3)
    n = 5000
    sun = make_lamp(light('SUN', 2.0, rotation_x(0.6)))
    lc = shading.LightChoice(lamp_records([sun]), [1.0], np.ones(1, F32), [True], [True])
    P = rng.normal(size=(3, n)).astype(F32)
    smooth = _unit(rng, n)
    bent = smooth + F32(0.6) * _unit(rng, n)
    bent /= np.linalg.norm(bent, axis=0)
    keys = np.stack([rng.integers(0, 2**32, n, dtype=np.uint32), rng.integers(0, 4096, n, dtype=np.uint32)])
    corr = (rng.random(n) < 0.7).astype(F32)
    bump = np.concatenate([smooth, corr[None]]).astype(F32)
    plain = shading.next_event(lc, P, P, bent, None, None, keys, 1, 2)[0]
    bumped = shading.next_event(lc, P, P, bent, None, None, keys, 1, 2, bump=bump)[0]
    wi = np.repeat(np.asarray(sun.sample(P[:, :1], *np.zeros((2, 1), F32)).wi), n, axis=1)   # a delta sun's one direction
    g = bump_shadowing(smooth, bent, wi, corr != 0)
    lit = plain[0] > 0
    assert lit.sum() > 1000 and ((g > 0) & (g < 1) & lit).sum() > 100
    np.testing.assert_allclose(bumped[0][lit], plain[0][lit] * g[lit], rtol=2e-6, atol=0)


@pytest.mark.parametrize('area', [True, False])
@pytest.mark.parametrize('linked', [False, True])
def test_light_tree_walks_side_by_side_pick_as_tree_sample(linked, area):
    """With a light tree the light choice runs per chunk, the chunk's tree walks stop by stop
    (LightTree::sample_rows): every point's entry and selection probability (in its
    sample's value) are bit for bit the composed choice, one walk per point by tree.sample, for
    walks of different depths (an unbalanced tree of 23 lamps), groups with picks beside the tree
    (an area lamp's), NaN picks, a chunk tail of one point and, with light linking, receiver
    masks that exclude some of the tree's lamps."""
    rng = np.random.default_rng(23)
    K, A = 23, int(area)
    pos = np.concatenate([rng.normal(size=(3, 16)) * 0.3, rng.normal(size=(3, K - 16)) * 4.0], axis=1) \
        + np.asarray(CENTRE)[:, None]
    recs = lamp_records([make('area_square')] * A + [
        make_lamp(light('POINT', rng.uniform(5, 50), translation(*pos[:, k]))) for k in range(K)])
    energy = rng.uniform(1.0, 100.0, K)
    sets = rng.integers(0, 3, K).astype(np.uint8) if linked else None
    p = np.float64(pos.astype(F32))
    tree = dacrt.lamps.light_tree(p, p, np.tile([[0.0], [0.0], [1.0]], K), np.full(K, -1.0), np.zeros(K), energy,
                                  np.arange(A, K + A), set=sets)
    lo = 0.25 * A                                        # the tree's slot: [lo, 1)
    cdf = np.concatenate([[lo] * A, np.full(K, 1.0)])
    prob = np.concatenate([[lo] * A, np.full(K, 1.0 - lo)]).astype(F32)
    lc = shading.LightChoice(recs, cdf, prob, np.zeros(K + A, bool), np.ones(K + A, bool), tree=tree)
    n = 30_001
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    pick = rng.random(n)
    pick[rng.integers(0, n, 40)] = np.nan
    receivers = rng.integers(1, 8, n).astype(np.uint64) if linked else None
    linking = (np.concatenate([[0] * A, sets]).astype(np.uint8), receivers | np.uint64(1)) if linked else None
    entry = np.zeros(n, np.int32)
    got = shading.next_event(lc, P, P_off, ns, ng, th, keys, 0x1234567, 0x89ABCDE, pick=pick, shorten=SHORTEN,
                             skip_work=False, linking=linking, entry=entry)
    # the composed choice: the entry the pick falls in; a pick in the tree's slot, rescaled to
    # it, goes on to tree.sample at P_off with ns
    want = np.minimum(np.searchsorted(cdf, pick, side='right'), K + A - 1).astype(np.int32)
    p_sel = prob[want].copy()
    member = want >= A
    u = (pick[member] - lo) / (1.0 - lo)
    key, pt = tree.sample(P_off[:, member], u, N=ns[:, member],
                          **({'receivers': linking[1][member]} if linked else {}))
    want[member] = key
    p_sel[member] = (prob[key].astype(np.float64) * pt).astype(F32)
    assert np.array_equal(entry, want)
    assert len(np.unique(want[member])) == K and (want == 0).any()
    u1, u2 = shading.uniform2(keys, 0x1234567, 0x89ABCDE)
    wi, value = np.zeros((3, n), F32), np.zeros((3, n), F32)
    dist, pdf = np.zeros(n, F32), np.zeros(n, F32)
    dacrt.lamps.lamp_sample(lc.records, want, P, u1, u2, out=(wi, dist, value, pdf))
    ok = shading.nee_weight(ns, None, wi, pdf, p_sel, th, value)
    if linked:
        ok &= ((linking[1] >> linking[0][want].astype(np.uint64)) & np.uint64(1)) == 1
    value[:, ~ok] = 0.0
    lamp = want >= A       # (the area lamp's lanes round their own way: checked by the tests above)
    assert np.array_equal(got[0][:, lamp].view(np.uint32), value[:, lamp].view(np.uint32))


def _light_set(rng, kind):
    """LightChoices that take each of next_event's four loops: area lamps drawn in lanes or not
    (areas: every lamp variant; points: those that are no area lamp), with or without an
    environment map, each with emissive triangles (some the points' own)."""
    from ..native.test_environment_sample_lanes import _rotation
    names = NAMES if kind.startswith('areas') else [k for k in NAMES if not k.startswith('area')]
    recs = lamp_records([make(name) for name in names])
    T = 40
    geo, area = _geo(rng, T, scale=0.8)
    geo[0:3] += np.array([0.3, -0.7, 1.2], F32)[:, None]
    emission = rng.uniform(0.5, 20.0, (3, T)).astype(F32)
    env = None
    if kind.endswith('env'):
        rgb = (rng.random((12, 24, 3)) ** 4 * 5).astype(F32)
        env = dacrt.lamps.environment_map(rgb, _rotation(rng), 'Linear')
    E = len(recs) + T + (env is not None)
    p = rng.uniform(0.2, 1.0, E)
    p /= p.sum()
    cdf = np.cumsum(p)
    cdf[-1] = 1.0
    no_mis = rng.random(E) < 0.3
    no_mis[len(recs):] = False
    shadow = rng.random(E) < 0.8
    shadow[len(recs):] = True
    return shading.LightChoice(recs, cdf, p.astype(F32), no_mis, shadow, geo, area, emission, environment=env,
                               tri_prim=rng.integers(0, 50, T).astype(np.int32))


@pytest.mark.parametrize('kind', ['areas', 'points', 'areas_env', 'points_env'])
@pytest.mark.parametrize('flat,thr,skip_work', [(False, True, True), (True, False, True), (False, True, False)])
def test_plain_points_loop_gives_the_general_loops_bits(kind, flat, thr, skip_work):
    """Points with none of bump, rough, terminator, light linking, entry or point output take
    next_event's loop compiled without that code (event_block's PLAIN); asking for the entries
    or the sampled points takes the general loop. Both give every output bit alike (value,
    contrib, rays, send, skip, skipped) for each of the loops (area lanes, environment map
    lanes, both, neither), points on their own emissive triangle, a NaN and an infinite point,
    not-finite picks and a count no multiple of a chunk."""
    rng = np.random.default_rng(len(kind) + 5 * flat + 3 * skip_work)
    lc = _light_set(rng, kind)
    n = 12_289
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=flat, thr=thr)
    P[:, 7], P[:, 8] = np.nan, np.inf
    pick = rng.random(n)
    pick[[11, 12]] = np.nan, np.inf
    prim = rng.integers(0, 50, n).astype(np.int32)
    ka, kb = 0x7654321, 0x0FEDCBA
    args = (lc, P, P_off, ns, ng, th, keys, ka, kb)
    kw = dict(pick=pick, prim=prim, shorten=SHORTEN, skip_work=skip_work)
    with np.errstate(invalid='ignore', over='ignore'):
        plain = shading.next_event(*args, **kw)
        entry = np.empty(n, np.int32)
        general = shading.next_event(*args, entry=entry, **kw)
        point = np.zeros((3, n), F32)
        pointed = shading.next_event(*args, point=point, **kw)
    def bits(a):
        # a NaN's sign is the compiler's operand order (main's one loop already flips it when
        # GCC unswitches it on the entry output): NaN is compared as NaN, the rest bit for bit
        if a.dtype == F32:
            a = np.where(np.isnan(a), F32(np.nan), a)
        return a.view(np.uint8)

    for name, a, b, c in zip(('value', 'contrib', 'rays', 'send', 'skip'), plain[:5], general[:5], pointed[:5]):
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(bits(a), bits(b)), f'{name} differs from the general loop'
        assert np.array_equal(bits(a), bits(c)), f'{name} differs with point output'
    assert plain[5] == general[5] == pointed[5]
    # the case mix: lamps, triangles (the points' own among them) and the map all picked, rays sent
    R, T = len(lc.records), lc.entries - len(lc.records) - (lc.environment is not None)
    tri = (entry >= R) & (entry < R + T)
    assert (entry < R).any() and tri.any() and len(plain[3]) > n // 4
    assert (lc.tri_prim[entry[tri] - R] == prim[tri]).any()
    if lc.environment is not None:
        assert (entry == R + T).any()


def test_area_lamps_picked_in_runs_are_drawn_as_the_composed_kernels():
    """A chunk's points are drawn in lanes per area lamp, at most four lamps a chunk (the rest one
    at a time), the lamp looked up once per run of points that picked the same entry, the picks
    read by the table in the chunk's own loop (no tree; NaN, infinite and edge picks among them):
    runs of 1..700 points over six area lamps (five drawn in lanes, one with spread), a point
    lamp and an emissive triangle, runs crossing the 512-point chunks, the fifth area lamp first
    met in a chunk that already drew four, a lamp coming back after another. Every output bit
    equals the composed kernels'."""
    rng = np.random.default_rng(41)
    names = ['area_square', 'area_rectangle', 'area_disk', 'area_ellipse', 'area_rectangle_unnormalized',
             'area_square_spread', 'point_sphere']
    recs = lamp_records([make(name) for name in names])
    geo, area = _geo(rng, 1, scale=0.8)
    E = len(recs) + 1
    prob = np.full(E, 1.0 / E)
    cdf = np.cumsum(prob)
    cdf[-1] = 1.0
    lc = shading.LightChoice(recs, cdf, prob.astype(F32), np.zeros(E, bool), np.ones(E, bool), geo, area,
                             np.full((3, 1), 4.0, F32))
    runs, n = [], 0
    while n < 9000:
        length = int(rng.choice([1, 2, 3, 17, 90, 700]))
        runs.append((int(rng.integers(0, E)), length))
        n += length
    runs[:6] = [(0, 100), (1, 100), (2, 100), (3, 100), (4, 50), (0, 62)]   # chunk 0: a fifth area lamp
    entry = np.concatenate([np.full(k, e) for e, k in runs])
    n = len(entry)
    pick = ((cdf - prob)[entry] + prob[entry] * rng.uniform(0.1, 0.9, n))    # inside each entry's slot
    pick[[5, 600, 1300, 2000, 2001]] = np.nan, np.inf, 1.0, 0.0, -np.inf     # the table's edges
    P, P_off, ns, ng, th, keys = _points(rng, n, flat=False, thr=True)
    with np.errstate(invalid='ignore', over='ignore'):
        got = shading.next_event(lc, P, P_off, ns, ng, th, keys, 5, 6, pick=pick, shorten=SHORTEN)
        ref = _composed(lc, P, P_off, ns, ng, th, keys, 5, 6, pick, None, True)
    for name, a, b in zip(('value', 'contrib', 'rays', 'send'), got[:4], ref[:4]):
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f'{name} differs'
    assert got[5] == ref[5]
    for e in range(E):
        assert got[1][entry == e].any(), f'entry {e} never adds'
