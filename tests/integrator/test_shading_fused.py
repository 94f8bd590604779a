"""The fused shading kernels against the steps they replace, bit for bit, on random inputs
with dead rays (misses, black surfaces, roulette) and empty batches:

- shade_bounce (survival, light sample, bounce in one pass) equals continue_paths, next_event
  and cosine_scatter called one after another; its shadow rays are written in place block by
  block and then moved together (no buffer of their own), so batches of several blocks with
  skipped samples are where it could go wrong;
- next_event's shadow rays of a batch are its blocks' rays, each block shaded alone, in order;
- camera_rays' pinhole lane loop gives the float32 operations of its scalar mapping (numpy's,
  one rounding per operation)."""
import numpy as np
import pytest

import dacrt
from dacrt import shading

from ..native.test_shading import _geo, _unit
from .test_next_event import _lights

F32 = np.float32
BLOCK = 4096                     # nextevent.h kEventBlock: points per block of shadow rays
SHORTEN = F32(1.0 - 2.0 ** -16)


def _bounce_inputs(rng, n, M=40, thr=True, roulette=True, pick=True):
    """A vertex's arriving paths: hits on M random triangles near the lamps, a fifth missing,
    some on black triangles; their throughput, roulette and pick uniforms, keys and ids."""
    geo, _ = _geo(rng, M, scale=1.5)
    geo[0:3] += np.array([0.3, -0.7, 1.2], F32)[:, None]
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits['prim'] = rng.integers(0, M, n)
    hits['t'] = rng.uniform(0.0, 3.0, n)
    u = rng.random(n, F32)
    hits['u'], hits['v'] = u, (1.0 - u) * rng.random(n, F32)
    miss = rng.random(n) < 0.2
    hits['prim'][miss] = -1
    hits['t'][miss] = np.inf
    live = rng.random(M) < 0.85
    albedo = rng.uniform(0.0, 0.9, (3, M)).astype(F32)
    return dict(hits=hits, hit=~miss, live=live, albedo=albedo,
                thr=rng.uniform(0.0, 1.5, (3, n)).astype(F32) if thr else None,
                u_rr=rng.random(n, F32) if roulette else None, geo=geo, normals=None, D=_unit(rng, n),
                pid=rng.permutation(3 * n)[:n].astype(np.int64),
                keys=rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32),
                pick=rng.random(n) if pick else None)


def _steps(lc, x, nee_words, skip_work, scatter_words):
    """continue_paths, next_event and cosine_scatter, as the general integrator calls them."""
    idx, thr, black, rr, (P, ng, ns, P_off), prim, (pid, keys, pick) = shading.continue_paths(
        x['hits'], x['hit'], x['live'], x['albedo'], x['thr'], x['u_rr'], surface=(x['geo'], x['normals'], x['D']),
        take=(x['pid'], x['keys'], x['pick']))
    nee = shading.next_event(lc, P, P_off, ns, None if ns is ng else ng, thr, keys, *nee_words, pick=pick, prim=prim,
                             shorten=SHORTEN, skip_work=skip_work)
    bsdf = shading.cosine_scatter(keys, *scatter_words, ns, None if ns is ng else ng, origins=P_off)
    return black, rr, (thr, (P, ng, ns, P_off), prim, pid, keys, pick), nee, bsdf


def _equal(a, b, where=''):
    """a and b the same nested results, arrays bit for bit."""
    if isinstance(a, (tuple, list)):
        assert isinstance(b, (tuple, list)) and len(a) == len(b), where
        for i, (p, q) in enumerate(zip(a, b)):
            _equal(p, q, f'{where}[{i}]')
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, where
        assert a.tobytes() == b.tobytes(), where
    else:
        assert a == b, where


@pytest.mark.parametrize('n', [0, 1, 7, 3 * BLOCK + 1234])
@pytest.mark.parametrize('skip_work', [True, False])
def test_shade_bounce_equals_its_steps(n, skip_work):
    rng = np.random.default_rng(n + 17 * skip_work)
    lc = _lights(rng, lamps=True, triangles=True)
    x = _bounce_inputs(rng, n)
    fused = shading.shade_bounce(lc, x['hits'], x['hit'], x['live'], x['albedo'], x['thr'], x['u_rr'], x['geo'],
                                 x['normals'], x['D'], x['pid'], x['keys'], x['pick'], (11, 12), SHORTEN, skip_work,
                                 (21, 22))
    steps = _steps(lc, x, (11, 12), skip_work, (21, 22))
    _equal(fused, steps)
    if n > BLOCK:                # several blocks, some samples without a ray: rays moved together
        rays = fused[3][2]
        assert len(rays) < len(fused[2][3])
        assert np.array_equal(rays['id'], np.arange(len(rays)))


@pytest.mark.parametrize('first_bounce', [True, False])
def test_shade_bounce_without_roulette_or_throughput(first_bounce):
    """Bounce 0 (no throughput yet) and 1 (no roulette), one light, no pick."""
    rng = np.random.default_rng(5)
    lc = _lights(rng, lamps=True, triangles=False)
    one = shading.LightChoice(lc.records[:1], [1.0], [1.0], [False], [True])
    x = _bounce_inputs(rng, 2 * BLOCK + 99, thr=not first_bounce, roulette=False, pick=False)
    fused = shading.shade_bounce(one, x['hits'], x['hit'], x['live'], x['albedo'], x['thr'], x['u_rr'], x['geo'],
                                 x['normals'], x['D'], x['pid'], x['keys'], x['pick'], (3, 4), SHORTEN, True, (5, 6))
    _equal(fused, _steps(one, x, (3, 4), True, (5, 6)))


@pytest.mark.parametrize('n', [1, 600, 2 * BLOCK + 777])
@pytest.mark.parametrize('pick,roulette', [(True, True), (True, False), (False, True)])
def test_shade_bounce_draws_uniform_picks_uniforms(n, pick, roulette):
    """draw=(ka, kb, pick, roulette): the pass draws the roulette uniforms (of every arriving
    path) and the light-choice uniforms (of the survivors) from the keys, which the integrator
    had drawn with uniform_pick and handed over as arrays: every output bit the same, in chunks
    of words that start inside a block and across blocks."""
    rng = np.random.default_rng(n + 3 * pick + roulette)
    lc = _lights(rng, lamps=True, triangles=True)
    if not pick:                  # one light: no choice to draw
        lc = shading.LightChoice(lc.records[:1], [1.0], [1.0], [False], [True])
    x = _bounce_inputs(rng, n, roulette=False, pick=False)
    ka, kb = 0x9E3779B9, 77
    u_pick, u_rr = shading.uniform_pick(x['keys'], ka, kb)
    args = (x['hits'], x['hit'], x['live'], x['albedo'], x['thr'])
    rest = (x['geo'], x['normals'], x['D'], x['pid'], x['keys'])
    given = shading.shade_bounce(lc, *args, u_rr if roulette else None, *rest, u_pick if pick else None, (11, 12),
                                 SHORTEN, True, (21, 22))
    drawn = shading.shade_bounce(lc, *args, None, *rest, None, (11, 12), SHORTEN, True, (21, 22),
                                 draw=(ka, kb, pick, roulette))
    _equal(drawn, given)
    if roulette:
        assert 0 < given[1] and len(given[2][3]) > 0 or n == 1
    with pytest.raises(ValueError, match='draw takes the place of u_rr and pick'):
        shading.shade_bounce(lc, *args, u_rr, *rest, None, (11, 12), SHORTEN, True, (21, 22),
                             draw=(ka, kb, pick, roulette))


@pytest.mark.parametrize('n', [0, 7, 3 * BLOCK + 1234])
@pytest.mark.parametrize('drawn', [False, True])
def test_shade_bounce_without_flags_takes_the_records_with_a_triangle(n, drawn):
    """hit None: the paths whose record holds a triangle (prim >= 0) are the hits, as the
    integrator's flags prim >= 0 had said (it now makes none where nothing else reads them):
    every output bit the same, with the roulette and pick uniforms given or drawn; all missed,
    nothing shaded."""
    rng = np.random.default_rng(n + 5 * drawn)
    lc = _lights(rng, lamps=True, triangles=True)
    x = _bounce_inputs(rng, n, roulette=not drawn, pick=not drawn)
    draw = dict(draw=(0x9E3779B9, 77, True, True)) if drawn else {}
    for missed in (False, True):
        hits = x['hits'].copy()
        if missed:
            hits['prim'] = -1
        args = lambda hit: (lc, hits, hit, x['live'], x['albedo'], x['thr'], x['u_rr'], x['geo'], x['normals'],
                            x['D'], x['pid'], x['keys'], x['pick'], (11, 12), SHORTEN, True, (21, 22))
        flagged = shading.shade_bounce(*args(hits['prim'] >= 0), **draw)
        _equal(shading.shade_bounce(*args(None), **draw), flagged)
        if n > BLOCK and not missed:
            assert len(flagged[2][3]) > n // 3
    assert len(flagged[2][3]) == 0


def test_all_paths_dead():
    """Every ray missed or ended: nothing shaded, empty outputs of the right kinds."""
    rng = np.random.default_rng(9)
    lc = _lights(rng, lamps=True, triangles=True)
    x = _bounce_inputs(rng, 500)
    x['hit'][:] = False
    fused = shading.shade_bounce(lc, x['hits'], x['hit'], x['live'], x['albedo'], x['thr'], x['u_rr'], x['geo'],
                                 x['normals'], x['D'], x['pid'], x['keys'], x['pick'], (1, 2), SHORTEN, True, (3, 4))
    _equal(fused, _steps(lc, x, (1, 2), True, (3, 4)))
    assert len(fused[2][3]) == 0 and len(fused[3][2]) == 0


@pytest.mark.parametrize('skip_work', [True, False])
def test_next_event_rays_are_its_blocks_rays_in_order(skip_work):
    rng = np.random.default_rng(3 + skip_work)
    lc = _lights(rng, lamps=True, triangles=True)
    n = 3 * BLOCK + 777
    P = (np.array([0.3, -0.7, 1.2], F32)[:, None] + rng.normal(size=(3, n)) * 1.5).astype(F32)
    ns = _unit(rng, n)
    P_off = (P + ns * F32(1e-4)).astype(F32)
    thr = rng.uniform(0.0, 1.0, (3, n)).astype(F32)
    keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
    pick, prim = rng.random(n), rng.integers(0, 40, n).astype(np.int32)

    def call(s):
        return shading.next_event(lc, P[:, s], P_off[:, s], ns[:, s], None, thr[:, s], keys[:, s], 7, 8,
                                  pick=pick[s], prim=prim[s], shorten=SHORTEN, skip_work=skip_work)
    value, contrib, rays, send, skip, skipped = call(slice(0, n))
    parts = [(b, call(slice(b, min(n, b + BLOCK)))) for b in range(0, n, BLOCK)]
    _equal(value, np.concatenate([p[0] for _, p in parts], axis=1))
    _equal(contrib, np.concatenate([p[1] for _, p in parts]))
    _equal(send, np.concatenate([p[3] + b for b, p in parts]))
    _equal(skip, np.concatenate([p[4] for _, p in parts]))
    assert skipped == sum(p[5] for _, p in parts)
    whole = np.concatenate([p[2] for _, p in parts])
    whole['id'] = np.arange(len(whole))
    _equal(rays, whole)


def _frame(rng):
    """A perspective camera's 27 frame numbers (shading.camera_rays), no aperture."""
    a = rng.normal(size=(3, 3))
    rot, _ = np.linalg.qr(a)
    f = np.zeros(27, F32)
    f[0:9] = rot.ravel()
    f[9:12] = rng.normal(size=3) * 3.0
    f[15:19] = [-1.0, 2.0 / 160, 0.75, -1.5 / 120]
    f[19:22] = [np.tan(np.radians(20.0)), 0.1, 99.9]
    return f


@pytest.mark.parametrize('n', [0, 1, 17, 70_001])
def test_pinhole_camera_rays_are_the_scalar_float32_mapping(n):
    rng = np.random.default_rng(n)
    f = _frame(rng)
    rx, ry = (rng.uniform(-2.0, 162.0, n).astype(F32), rng.uniform(-2.0, 122.0, n).astype(F32))
    O, D, tmax, rays = shading.camera_rays(False, f, rx, ry, records=True)
    rot, pos = f[0:9].reshape(3, 3), f[9:12]
    sx0, sxs, sy0, sys_, tf, cs, cr = f[15], f[16], f[17], f[18], f[19], f[20], f[21]
    sx = (sx0 + rx * sxs) * tf
    sy = (sy0 + ry * sys_) * tf
    inv_len = F32(1.0) / np.sqrt(sx * sx + sy * sy + F32(1.0))
    start = cs / inv_len
    d = np.stack([(rot[a, 0] * sx + rot[a, 1] * sy - rot[a, 2]) * inv_len for a in range(3)])
    _equal(D, d.astype(F32))
    _equal(O, (d * start + pos[:, None]).astype(F32))
    _equal(tmax, (cr / inv_len).astype(F32))
    assert np.array_equal(rays['org'], O.T) and np.array_equal(rays['dir'], D.T)
    assert np.array_equal(rays['tfar'], tmax) and np.array_equal(rays['id'], np.arange(n))
