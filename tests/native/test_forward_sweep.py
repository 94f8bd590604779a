"""Filter sweeps of at least 2^15 rays (kForwardSweepRays, native/cpp/filter.h) partition the
records in one forward pass, smaller ones from both ends: only the order of the records may
change, never a hit. A batch traced as one chunk whose root filter sweeps all its rays (half of
them start outside the scene box and point away, so the sampled filter skip, 20 of 32, never
skips it) gives hits and occlusion bit-identical to the same rays traced in batches too small
for a forward sweep, on every ISA, with the rays' in-place contract kept (harness)."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

ISAS = dacrt.supported_isas()
FORWARD_RAYS = 1 << 15
N_RAYS = 2 * FORWARD_RAYS + 20_000  # forward sweeps at the top, two-ended ones below
SMALL = 20_000  # a batch below FORWARD_RAYS: every sweep two-ended


@pytest.fixture(scope="module")
def rays_and_mesh():
    v, t = scenes.generated_100k()
    org, dirs, tfar = make_rays("bounce", "mixed", v, t, N_RAYS, seed=5)
    half = N_RAYS // 2
    org[half:] = np.float32([40.0, 40.0, 40.0]) + org[half:]
    dirs[half:] = np.abs(dirs[half:]) + np.float32(0.1)
    return (v, t), (org, dirs, tfar)


def _trace(scene, rays, step):
    org, dirs, tfar = rays
    hits, occ = [], []
    for i in range(0, len(org), step):
        s = slice(i, i + step)
        hits.append(harness.intersect(scene, org[s], dirs[s], tfar[s], threads=1, shuffle_seed=3))
        occ.append(harness.occluded(scene, org[s], dirs[s], tfar[s] * np.float32(0.5), threads=1,
                                    shuffle_seed=4))
    return np.concatenate(hits), np.concatenate(occ)


def test_hits_of_forward_sweeps_equal_those_of_two_ended_sweeps(rays_and_mesh, monkeypatch):
    (v, t), rays = rays_and_mesh
    monkeypatch.setenv("DACRT_ISA", "portable")
    small_hits, small_occ = _trace(dacrt.Scene(v, t), rays, SMALL)
    assert 0.2 < np.mean(small_hits["prim"] >= 0) < 0.5, "half the rays miss, most others hit"
    assert 0.1 < np.mean(small_occ) < 0.5
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(v, t)
        hits, occ = _trace(scene, rays, N_RAYS)
        diff = np.flatnonzero(np.any(hits.view(np.uint32).reshape(-1, 4) !=
                                     small_hits.view(np.uint32).reshape(-1, 4), axis=1))
        assert len(diff) == 0, f"{isa}: hits differ on {len(diff)} rays, e.g. id {diff[0]}"
        assert np.array_equal(occ, small_occ), f"{isa}: occlusion differs on {np.sum(occ != small_occ)} rays"
