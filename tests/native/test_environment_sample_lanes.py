"""The environment map's samples drawn many points at a time (environment_sample_lanes:
the searches and lookups per point, from_uv and the turn to the world as a lane loop per
instruction set) against one point at a time (environment_sample): the same bits for every
map kind ('Linear' and 'Closest', sRGB, black rows, one-row and one-column maps, rotated and
mirrored worlds, an all-black map, guide buckets that hold long flat runs or nothing), at the
uniforms' edges, for any count (short last lane groups), on every instruction set the CPU runs
(DACRT_ISA); and next_event, which takes the lane path for the points that pick the map, gives
what sampling them one at a time gives."""

import numpy as np

import pytest
from dacrt import lamps, shading

from ..integrator.test_next_event import SHORTEN, _lights, _points
from .isaruns import outputs_per_isa

F32 = np.float32


def _rotation(rng, mirror=False):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if mirror:
        q = q @ np.diag([1.0, -1.0, 1.0])
    return q.astype(F32)


def _maps(rng):
    """(name, EnvironmentMap) over the kinds of map the sampler branches on."""
    out = []
    for closest in (False, True):
        interp = "Closest" if closest else "Linear"
        rgb = (rng.random((24, 40, 3)) ** 4 * 5).astype(F32)
        rgb[3] = 0.0                                       # black rows: flat runs of the row CDF
        rgb[17:19] = 0.0
        rgb[10, 7] = [900.0, 800.0, 700.0]                  # a one-texel sun
        out.append((f"random-{interp}", lamps.environment_map(rgb, _rotation(rng), interp)))
        out.append((f"mirrored-{interp}", lamps.environment_map(rgb, _rotation(rng, True), interp)))
        out.append((f"identity-{interp}", lamps.environment_map(rgb, None, interp)))
        row = (rng.random((1, 33, 3)) * 2).astype(F32)      # 1 x N: every cell wraps over both poles
        out.append((f"one-row-{interp}", lamps.environment_map(row, _rotation(rng), interp)))
        col = (rng.random((17, 1, 3)) * 2).astype(F32)      # N x 1: every cell wraps around in u
        out.append((f"one-column-{interp}", lamps.environment_map(col, _rotation(rng), interp)))
        enc = rng.random((12, 20, 3)).astype(F32)           # sRGB-encoded texels, decoded after the blend
        out.append((f"srgb-{interp}", lamps.environment_map(enc, _rotation(rng), interp, srgb=True,
                                                            scale=[1.5, 2.0, 0.5])))
        out.append((f"black-{interp}", lamps.environment_map(np.zeros((8, 16, 3), F32), _rotation(rng), interp)))
        # Guide buckets that hold thousands of entries (a flat CDF run: black columns) and empty
        # ones (the bright ends' steep rise), rows and columns alike, in maps over 2^20 column-CDF
        # entries (where a lane-group search would pay, README "envcdf"). Each row's column CDF is
        # 3/7 over its black run: u2 = 3/7 (_uniforms) ties with it inside a bucket, and every
        # search must land after the run as std::upper_bound does.
        wide = np.zeros((400, 3000, 3), F32)
        wide[:, :3] = wide[:, -4:] = 1.0
        out.append((f"wide-runs-{interp}", lamps.environment_map(wide, _rotation(rng), interp)))
        tall = np.zeros((2000, 600, 3), F32)
        tall[:7] = tall[-7:] = 2.0
        tall[1000] = 5.0
        out.append((f"tall-runs-{interp}", lamps.environment_map(tall, _rotation(rng), interp)))
    return out


def _uniforms(rng, n):
    u1 = rng.random(n).astype(F32)
    u2 = rng.random(n).astype(F32)
    edges = np.array([0, 2 ** -24, 0.25, 3 / 7, 0.5, 1 - 2 ** -24, 1 - 2 ** -23], F32)
    k = min(n, 300)
    u1[:k] = rng.choice(edges, k)
    u2[k // 2:k + k // 2] = rng.choice(edges, len(u2[k // 2:k + k // 2]))
    return u1, u2


def _bits(*arrays):
    return [np.ascontiguousarray(a).view(np.uint32) for a in arrays]


@pytest.mark.parametrize("n", [0, 1, 127, 128, 129, 5003])
def test_lanes_equal_one_at_a_time(n):
    rng = np.random.default_rng(17 + n)
    u1, u2 = _uniforms(rng, n)
    for name, env in _maps(rng):
        one = env.sample(u1, u2)
        lanes = env.sample_lanes(u1, u2)
        for what, a, b in zip(("wi", "value", "pdf"), _bits(*lanes), _bits(*one)):
            assert a.shape == b.shape
            np.testing.assert_array_equal(a, b, err_msg=f"{name}: {what}")
        if n > 1000 and not name.startswith("black"):
            assert (one[2] > 0).mean() > 0.95, name          # (the comparison covers real samples)


_ISA_RUN = """
import sys
import numpy as np
from dacrt import lamps
rgb, M, u = np.load(sys.argv[1]), np.load(sys.argv[2]), np.load(sys.argv[3])
out = []
for interp in ("Linear", "Closest"):
    env = lamps.environment_map(rgb, M, interp)
    out += list(env.sample_lanes(u[0], u[1])) + list(env.sample(u[0], u[1]))
np.save(sys.argv[4], np.concatenate([np.atleast_2d(a) for a in out]))
"""


def test_every_isa_gives_the_same_bits():
    rng = np.random.default_rng(23)
    rgb = (rng.random((16, 32, 3)) ** 3 * 4).astype(F32)
    u = np.stack(_uniforms(rng, 4099))                     # a short last group of every vector width
    out = outputs_per_isa(_ISA_RUN, rgb, _rotation(rng), u)
    first = out.pop("portable")
    for isa, got in out.items():
        np.testing.assert_array_equal(got.view(np.uint32), first.view(np.uint32), err_msg=isa)


def _with_environment(lc, env, rng):
    """lc's lamps and the map as the last entry (a third of the choice), with random selection
    probabilities."""
    E = len(lc.records) + 1
    p = rng.uniform(0.2, 1.0, E)
    p[-1] = p[:-1].sum() / 2
    p /= p.sum()
    cdf = np.cumsum(p)
    cdf[-1] = 1.0
    no_mis = np.append(lc.no_mis, False)
    shadow = np.append(lc.shadow, True)
    return shading.LightChoice(lc.records, cdf, p.astype(F32), no_mis, shadow, environment=env)


def _composed(lc, P, P_off, ns, thr, keys, ka, kb, pick):
    """next_event's value, contrib and shadow rays from the kernels one at a time: lamp_sample
    for lamps, the map's sample (one point at a time) for the last entry, nee_weight,
    shadow_rays (as tests/integrator/test_next_event.py's reference)."""
    n = P.shape[1]
    R = len(lc.records)
    u1, u2 = shading.uniform2(keys, ka, kb)
    entry = np.minimum(np.searchsorted(lc.cdf, pick, side="right"), lc.entries - 1).astype(np.int32)
    wi, value = np.zeros((3, n), F32), np.zeros((3, n), F32)
    dist, pdf = np.zeros(n, F32), np.zeros(n, F32)
    lamps.lamp_sample(lc.records, np.minimum(entry, R - 1), P, u1, u2, out=(wi, dist, value, pdf))
    e = np.flatnonzero(entry == R)
    wi[:, e], value[:, e], pdf[e] = lc.environment.sample(u1[e], u2[e])
    dist[e] = np.inf
    pdf[lc.no_mis[entry]] = np.inf
    ok = shading.nee_weight(ns, None, wi, pdf, lc.prob[entry], thr, value)
    send = np.flatnonzero(ok & lc.shadow[entry])
    back = (ns[0] * wi[0] + ns[1] * wi[1]) + ns[2] * wi[2] < 0
    O = np.where(back, P + (P - P_off), P_off).astype(F32)
    rays, valid = shading.shadow_rays(O, wi, dist, None, send, SHORTEN)
    contrib = ok.copy()
    contrib[send[~valid]] = False
    rays, send = rays[valid], send[valid]
    rays["id"] = np.arange(len(send), dtype=np.uint32)
    return value, contrib, rays, send, entry


@pytest.mark.parametrize("interp", ["Linear", "Closest"])
def test_next_event_samples_the_map_as_one_at_a_time(interp):
    """Points picking the map among lamps (several 512-point chunks, the map's points scattered
    through them) get the one-at-a-time sample's value and shadow ray, bit for bit."""
    rng = np.random.default_rng(29)
    rgb = (rng.random((24, 48, 3)) ** 4 * 5).astype(F32)
    rgb[20:] = 0.0                                          # a black cap: samples there are rejected
    env = lamps.environment_map(rgb, _rotation(rng), interp)
    lc = _with_environment(_lights(rng, True, False), env, rng)
    n = 9001
    P, P_off, ns, _, th, keys = _points(rng, n, flat=True, thr=True)
    pick = rng.random(n)
    ka, kb = 0x2468ACE, 0x13579BD
    entry = np.empty(n, np.int32)
    got = shading.next_event(lc, P, P_off, ns, None, th, keys, ka, kb, pick=pick, shorten=SHORTEN, entry=entry)
    value, contrib, rays, send, ref_entry = _composed(lc, P, P_off, ns, th, keys, ka, kb, pick)
    np.testing.assert_array_equal(entry, ref_entry)
    on_map = entry == len(lc.records)
    assert 0.1 < on_map.mean() < 0.9 and contrib[on_map].any()
    for name, a, b in zip(("value", "contrib", "rays", "send"), got[:4], (value, contrib, rays, send)):
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f"{name} differs"


def test_gather_blends_equal_eval():
    """environment_gather's lookups and pdfs, blended as lane loops for 'Linear' maps, add what
    eval gives each missed ray (with MIS weights and throughput), on every map kind; rays with no
    direction add nothing."""
    rng = np.random.default_rng(31)
    n = 3001
    D = rng.normal(size=(3, n)).astype(F32)
    D[:, :5] = 0.0                                          # no direction
    D[:, 5:9] = [[0, 0, 0, 0], [0, -0.0, 0, 0], [1, 1, -1, -1]]  # the poles
    D /= np.maximum(np.linalg.norm(D.astype(np.float64), axis=0), 1e-30).astype(F32)
    D = np.ascontiguousarray(D)
    miss = rng.random(n) < 0.7
    miss[:9] = True
    thr = rng.uniform(0.1, 2.0, (3, n)).astype(F32)
    pdf_bsdf = rng.uniform(0.05, 3.0, n).astype(F32)
    pid = np.arange(n, dtype=np.int64)
    for name, env in _maps(rng):
        Le, pdf = env.eval(D)
        w = F32(1.0) / (F32(1.0) + np.square(F32(0.4) * pdf / pdf_bsdf))
        ref = np.where(miss, Le * w * thr, 0).astype(F32)
        L = np.zeros((3, n), F32)
        env.gather(0.4, D, miss, thr, pdf_bsdf, pid, L)
        np.testing.assert_array_equal(L.view(np.uint32), ref.view(np.uint32), err_msg=name)
        L0 = np.zeros((3, n), F32)
        env.gather(0.0, D, miss, None, None, pid, L0)
        np.testing.assert_array_equal(L0.view(np.uint32), np.where(miss, Le, 0).astype(F32).view(np.uint32),
                                      err_msg=name)
        assert not L[:, :5].any()
