"""Shading kernels that skip work for the rays that do not need it must give the bits of the
kernels that did it: here lamp_gather's area-lamp lanes (native/cpp/gatherlanes.cpp), which
leave a group of rays none of which meets the lamp without weighing or adding anything, where
they used to add each ray's selected zero. Rays are made so that most groups meet nothing,
some meet it in one lane only (first, last, middle), and the rays that do not meet it carry
non-finite throughputs and pdfs (a skipped lane must not leak them); the film holds light
already, which must be left as it was. (The speed-up itself is measured, not asserted.)"""
import dacrt
import numpy as np
import pytest
from addon.lights import lamp_records, make_lamp

from ..integrator.scenes import light, translation

F32 = np.float32
LANES = 16          # arealanes.h kLampLanes: rays per group


def _lamp(shape):
    size = dict(RECTANGLE=dict(size_x=0.4, size_y=0.25), SQUARE=dict(size_x=0.3), DISK=dict(size_x=0.3),
                ELLIPSE=dict(size_x=0.4, size_y=0.2))[shape]
    return make_lamp(light('AREA', (40.0, 20.0, 5.0), translation(0.0, 0.0, 2.0),
                           shape=shape, **size))


def _rays(rng, n, hitting):
    """n rays from below a lamp at z = 2 facing down: those in `hitting` aimed at its centre
    (they meet it), the others away from it (they meet nothing)."""
    O = np.stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0.0, 1.0, n)]).astype(F32)
    D = np.stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), -rng.uniform(0.2, 1, n)])
    aim = np.zeros((3, len(hitting))) + [[0.0], [0.0], [2.0]] + rng.normal(size=(3, len(hitting))) * 0.02
    aim[2] = 2.0
    D[:, hitting] = aim - O[:, hitting]
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    return O, D


def _hitting(rng, n):
    """Lanes that meet the lamp: groups with none (most), one lane first / last / in the middle
    of its group, and a few fuller groups; the calls' tail (n not a multiple of LANES) too."""
    groups = n // LANES
    picks = [g * LANES for g in range(1, groups, 7)] + [g * LANES + LANES - 1 for g in range(3, groups, 11)]
    picks += [g * LANES + 7 for g in range(5, groups, 13)] + list(range(20 * LANES, 21 * LANES))
    picks += [n - 2]
    return np.unique(np.asarray(picks))


@pytest.mark.parametrize('shape', ['RECTANGLE', 'SQUARE', 'DISK', 'ELLIPSE'])
@pytest.mark.parametrize('bsdf', [False, True])
def test_groups_that_meet_nothing_add_nothing(shape, bsdf):
    rng = np.random.default_rng(7 + bsdf)
    n = 64 * LANES + 5
    hitting = _hitting(rng, n)
    O, D = _rays(rng, n, hitting)
    rec = lamp_records([_lamp(shape)])
    t_surf = np.full(n, np.inf, F32)
    miss = np.zeros(n, bool)
    kw = {}
    if bsdf:
        thr = rng.uniform(0.1, 2.0, (3, n)).astype(F32)
        pdf = rng.uniform(0.01, 1.0, n).astype(F32)
        away = np.setdiff1d(np.arange(n), hitting)
        thr[:, away[::3]] = np.inf               # a ray that meets nothing adds nothing, whatever
        thr[:, away[1::3]] = np.nan              # its throughput and pdf
        pdf[away[2::3]] = 0.0
        kw = dict(thr=thr, pdf_bsdf=pdf, lamp_prob=np.asarray([0.5], F32), clamp=30.0)
    pid = rng.permutation(n)
    L0 = rng.uniform(0.0, 3.0, (3, n)).astype(F32)     # light the film holds already
    L = L0.copy()
    with np.errstate(invalid='ignore', over='ignore', divide='ignore'):
        dacrt.lamps.lamp_gather(rec, [0], O, D, t_surf, miss, pid, L, **kw)
    met = np.zeros(n, bool)
    met[pid[hitting]] = True
    assert (L[:, met] != L0[:, met]).any(axis=0).sum() >= len(hitting) - 2, 'the aimed rays must meet the lamp'
    np.testing.assert_array_equal(L[:, ~met].view(np.uint32), L0[:, ~met].view(np.uint32))
    # and the rays that meet it add what they add ray by ray (gather_one)
    by_ray = L0.copy()
    for i in hitting:
        sub = {k: (v[..., i:i + 1] if k in ('thr', 'pdf_bsdf') else v) for k, v in kw.items()}
        dacrt.lamps.lamp_gather(rec, [0], O[:, i:i + 1], D[:, i:i + 1], t_surf[i:i + 1], miss[i:i + 1],
                                pid[i:i + 1], by_ray, **sub)
    np.testing.assert_array_equal(L.view(np.uint32), by_ray.view(np.uint32))


def _small_lamps():
    """A sun and lamps a ray passes near far more often than it meets them (the lamp BVH lists
    them as near): small spheres and disks, a spot."""
    return [make_lamp(light('POINT', (30.0, 30.0, 30.0), translation(x, y, 2.0), radius=0.2, soft_falloff=soft))
            for x, y, soft in ((-0.5, 0.0, False), (0.5, 0.3, True), (0.0, -0.5, False))] + [
        make_lamp(light('SPOT', (50.0, 20.0, 5.0), translation(0.2, 0.2, 2.5), radius=0.08,
                        spot_size=np.radians(120.0), spot_blend=0.3)),
        make_lamp(light('SUN', (3.0, 3.0, 3.0), translation(0.0, 0.0, 5.0), angle=np.radians(15.0)))]


@pytest.mark.parametrize('lamps', [[0], [4], [0, 1, 2, 3, 4]])     # one lamp, the sun; several: the BVH
@pytest.mark.parametrize('bsdf', [False, True])
def test_rays_that_see_no_lamp_add_nothing(lamps, bsdf):
    """gather_one returns for a ray that does not see the lamp (the ray-by-ray path of points,
    spots and suns, and of the lamp BVH): its film column keeps its bits whatever the ray's
    throughput and pdf, and the rays that see a lamp add what they add when gathered alone."""
    rng = np.random.default_rng(11 + bsdf + len(lamps))
    rec = lamp_records(_small_lamps())
    n = 4000
    O = np.stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0.0, 1.0, n)]).astype(F32)
    D = np.stack([rng.normal(0, 0.4, n), rng.normal(0, 0.4, n), np.ones(n)])
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    t_surf = np.where(rng.random(n) < 0.2, rng.uniform(0.5, 3.0, n), np.inf).astype(F32)
    miss = ~np.isfinite(t_surf)
    kw = {}
    if bsdf:
        kw = dict(thr=rng.uniform(0.1, 2.0, (3, n)).astype(F32), pdf_bsdf=rng.uniform(0.01, 1.0, n).astype(F32),
                  lamp_prob=np.full(len(rec), 0.2, F32), clamp=40.0)
    pid = rng.permutation(n)
    L0 = rng.uniform(0.0, 3.0, (3, n)).astype(F32)
    L = L0.copy()
    dacrt.lamps.lamp_gather(rec, lamps, O, D, t_surf, miss, pid, L, **kw)
    seen = (L != L0).any(axis=0)
    assert 20 < seen.sum() < n // 3, f'{seen.sum()} of {n} rays see a lamp: the test wants few'
    if bsdf:   # now the same rays with non-finite throughputs and pdfs where they see nothing
        away = np.flatnonzero(~seen[pid])
        thr, pdf = kw['thr'].copy(), kw['pdf_bsdf'].copy()
        thr[:, away[::2]] = np.nan
        pdf[away[1::2]] = 0.0
        L2 = L0.copy()
        with np.errstate(invalid='ignore', divide='ignore'):
            dacrt.lamps.lamp_gather(rec, lamps, O, D, t_surf, miss, pid, L2, **dict(kw, thr=thr, pdf_bsdf=pdf))
        np.testing.assert_array_equal(L2.view(np.uint32), L.view(np.uint32))
    np.testing.assert_array_equal(L[:, ~seen].view(np.uint32), L0[:, ~seen].view(np.uint32))
    by_ray = L0.copy()
    for i in np.flatnonzero(seen[pid]):
        sub = {k: (v[..., i:i + 1] if k in ('thr', 'pdf_bsdf') else v) for k, v in kw.items()}
        dacrt.lamps.lamp_gather(rec, lamps, O[:, i:i + 1], D[:, i:i + 1], t_surf[i:i + 1], miss[i:i + 1],
                                pid[i:i + 1], by_ray, **sub)
    np.testing.assert_array_equal(L.view(np.uint32), by_ray.view(np.uint32))

