"""lamp_gather through its lamp boxes or BVH (lamps.cpp gather_range_boxes, gather_range_bvh) against the
brute-force loop: every listed lamp gathered on its own, in list order (each call the plain
lamp-by-lamp loop over the rays). The sums must be bit for bit equal: boxes and BVH only narrow
the candidates, so a ray must get the same lamps, added in the same order, with the same emission
and MIS weights. Lists of 2..64 lamps take the flat box test (lampboxes.h, a bit per lamp),
longer ones the BVH and a sorted list; both are covered, at the word's ends (lamp 0, lamp 63) too."""
import dacrt
import numpy as np
import pytest

from addon.lights import lamp_records

from tests.integrator.test_native_lamps import many_lamps, rays_at_lamps

F32 = np.float32


def brute_force(rec, listed, O, D, t_surf, miss, pid, L0, **kw):
    L = L0.copy()
    for j in listed:
        dacrt.lamps.lamp_gather(rec, [int(j)], O, D, t_surf, miss, pid, L, **kw)
    return L


def _gather_inputs(rng, bsdf, n, N, lamps):
    """The n rays' path ids among N paths, the BSDF-sampled rays' MIS inputs (with bsdf) and
    the paths' radiance before the gather (3, N)."""
    pid = rng.permutation(N)[:n]
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=rng.uniform(0.05, 1.0, lamps).astype(F32), clamp=50.0)
    return pid, kw, rng.uniform(0.0, 1.0, (3, N)).astype(F32)


@pytest.mark.parametrize('count', [2, 7, 40, 64, 65, 150])
@pytest.mark.parametrize('bsdf', [False, True])
def test_bvh_gather_equals_brute_force(count, bsdf):
    rng = np.random.default_rng(count * 2 + bsdf)
    lamps = many_lamps(rng, 80, spread=rng.choice([2.0, 20.0]))   # (the background last)
    rec = lamp_records(lamps)
    listed = rng.integers(0, len(lamps), count).astype(np.int32)   # repeats included
    finite = [j for j, lamp in enumerate(lamps) if hasattr(lamp, 'center') and not lamp.delta]
    listed[rng.integers(0, count)] = len(lamps) - 1                 # the background somewhere
    listed[0] = rng.choice(finite)                                  # and a lamp rays can meet
    n, N = 6000, 9000
    O, D, t_surf, miss = rays_at_lamps(rng, [lamps[j] for j in listed if j in finite], n)
    pid, kw, L0 = _gather_inputs(rng, bsdf, n, N, len(lamps))
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L, **kw)
    ref = brute_force(rec, listed, O, D, t_surf, miss, pid, L0, **kw)
    seen = (ref != L0).any(axis=0)[pid]
    assert seen.sum() > n // 20, 'too few rays see a lamp to test it'
    np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))


def test_first_and_last_bit_of_the_candidate_word():
    """64 listed lamps where the first and last positions are lamps every ray meets (big spheres
    around the origins) and the rest delta lamps: both must be added, in order."""
    rng = np.random.default_rng(5)
    lamps = many_lamps(rng, 300)
    finite = [j for j, lamp in enumerate(lamps) if hasattr(lamp, 'center') and not lamp.delta]
    delta = [j for j, lamp in enumerate(lamps) if getattr(lamp, 'delta', False)]
    listed = np.array([finite[0]] + delta[:62] + [finite[1]], np.int32)
    assert len(listed) == 64
    n = 4000
    O, D, t_surf, miss = rays_at_lamps(rng, [lamps[j] for j in (finite[0], finite[1])], n)
    rec = lamp_records(lamps)
    pid = np.arange(n)
    L0 = np.zeros((3, n), F32)
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L)
    ref = brute_force(rec, listed, O, D, t_surf, miss, pid, L0)
    assert (ref > 0).any(axis=0).sum() > 100
    np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))


@pytest.mark.parametrize('where', ['first', 'between', 'last', 'everywhere'])
@pytest.mark.parametrize('bsdf', [False, True])
def test_lamps_at_infinity_add_in_list_order_among_finite_ones(where, bsdf):
    """A list mixing finite lamps with suns and the background: lamp_gather adds the finite ones
    through their boxes ray by ray and those at infinity run by run over a block of rays (in
    lanes), and each ray must still add its lamps in list order. The rays miss (t_surf = inf)
    and meet finite lamps on the way, so most add both kinds; the same lamps added with those
    at infinity last give other bits on some of them, which this test must tell apart."""
    rng = np.random.default_rng({'first': 1, 'between': 2, 'last': 3, 'everywhere': 4}[where] * 2 + bsdf)
    lamps = many_lamps(rng, 80, spread=2.0)
    rec = lamp_records(lamps)
    kinds = rec[:, 0].astype(int)
    finite = [j for j, lamp in enumerate(lamps) if hasattr(lamp, 'center') and not lamp.delta]
    suns = [j for j in np.flatnonzero(kinds == dacrt.lamps.KINDS['SUN']) if rec[j, 1] != 0]
    bg = len(lamps) - 1
    few = list(rng.choice(finite, 6, replace=False))
    listed = {'first': [bg, suns[0]] + few, 'between': few[:3] + [bg] + few[3:] + [suns[0]],
              'last': few + [suns[0], bg], 'everywhere': [bg] + few[:2] + [suns[0], bg] + few[2:4] + [suns[1]]
              + few[4:] + [bg]}[where]
    listed = np.array(listed, np.int32)
    n, N = 64 * 41 + 23, 6000                   # (a short last block and lane group too)
    O, D, _, _ = rays_at_lamps(rng, [lamps[j] for j in few], n, far=0.3)
    sun_dir = rec[suns[0], 5:8]
    aim = rng.random(n) < 0.2                   # some into the first sun's disk
    D[:, aim] = sun_dir[:, None] + rng.normal(size=(3, aim.sum())) * 0.02
    t_surf = np.full(n, np.inf, F32)
    miss = np.ones(n, bool)
    miss[rng.random(n) < 0.1] = False           # (a few hit something far away)
    t_surf[~miss] = 1e3
    pid, kw, L0 = _gather_inputs(rng, bsdf, n, N, len(lamps))
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, t_surf, miss, pid, L, **kw)
    ref = brute_force(rec, listed, O, D, t_surf, miss, pid, L0, **kw)
    np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))
    at_infinity = np.isin(listed, suns + [bg])
    late = brute_force(rec, np.concatenate([listed[~at_infinity], listed[at_infinity]]), O, D, t_surf, miss, pid,
                       L0, **kw)
    met = (brute_force(rec, listed[~at_infinity], O, D, t_surf, miss, pid, L0, **kw) != L0).any(axis=0)[pid]
    assert (met & miss).sum() > n // 10, 'too few rays add both kinds of lamp'
    if where != 'last':
        assert (late != ref).any(), 'the order of the additions changes no bit: the test cannot tell it'


HIT = np.dtype([('t', F32), ('prim', np.int32), ('u', F32), ('v', F32)])   # the tracer's hit record


@pytest.mark.parametrize('count', [1, 7, 150])
@pytest.mark.parametrize('bsdf', [False, True])
def test_lamp_gather_reads_t_surf_of_hit_records_in_place_with_the_same_bits(count, bsdf):
    """t_surf given as the t field of hit records (a view of stride 16 bytes, as the integrator
    passes hits['t']) is read in place (gather_one, gather_area_lanes, LampBoxes, the BVH's walk)
    and must give what its contiguous copy gives, bit for bit; so must the views the binding
    copies first: reversed (negative stride) and unaligned (a packed record with t at byte 1).
    The other fields hold values that would change the sums if read as t."""
    rng = np.random.default_rng(40 + count * 2 + bsdf)
    lamps = many_lamps(rng, 80, spread=2.0)
    rec = lamp_records(lamps)
    finite = [j for j, lamp in enumerate(lamps) if hasattr(lamp, 'center') and not lamp.delta]
    area = [j for j in finite if hasattr(lamps[j], 'normal')]
    listed = rng.choice(finite, count).astype(np.int32)
    listed[0] = rng.choice(area)        # a single lamp: an area lamp, drawn lane by lane
    if count > 1:
        listed[-1] = len(lamps) - 1     # the background
    n, N = 5003, 7000                   # (not a multiple of the lanes: the short last group too)
    O, D, t_surf, miss = rays_at_lamps(rng, [lamps[j] for j in listed if j in finite], n)
    t_surf = t_surf.astype(F32)
    hits = np.zeros(n, HIT)
    hits['t'] = t_surf
    hits['prim'] = rng.integers(0, 1 << 20, n)
    hits['u'] = rng.uniform(0.0, 0.01, n)   # tiny t: a ray that read it would meet no lamp
    hits['v'] = np.inf
    packed = np.zeros(n, np.dtype({'names': ['x', 't'], 'formats': ['u1', F32], 'offsets': [0, 1],
                                   'itemsize': 9}))
    packed['t'] = t_surf
    reversed_t = np.ascontiguousarray(t_surf[::-1])[::-1]
    pid, kw, L0 = _gather_inputs(rng, bsdf, n, N, len(lamps))
    ref = L0.copy()
    dacrt.lamps.lamp_gather(rec, listed, O, D, np.ascontiguousarray(t_surf), miss, pid, ref, **kw)
    assert ((ref != L0).any(axis=0)[pid] & ~miss).sum() > 40, 'too few rays meet a finite lamp'
    for t in (hits['t'], reversed_t, packed['t']):
        assert not t.flags.c_contiguous
        L = L0.copy()
        dacrt.lamps.lamp_gather(rec, listed, O, D, t, miss, pid, L, **kw)
        np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))
    L = L0.copy()   # the binding itself, without the wrapper's conversions
    dacrt.lamps._core.lamp_gather(rec, listed, kw.get('lamp_prob'), O.astype(F32), D.astype(F32), hits['t'], miss,
                                  kw.get('thr'), kw.get('pdf_bsdf'), pid.astype(np.int64), L, kw.get('clamp', np.inf),
                                  None, None, None, None)
    np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32))
