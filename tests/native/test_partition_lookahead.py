"""The run partition (native/cpp/runpartition.h, used by the filter and the chunk cuts) and the
forward sweep (filter.h) take the box-test mask of the next run before the current run's swaps.
Such a mask must be used only while its run is still unclaimed and untouched: near the point
where the two ends meet, a stale mask would send a ray to the wrong side and lose its hit. Rays
laid out in long stretches of rays that hit the scene and rays that start outside its box
pointing away (so the root filter keeps and culls whole stretches, meeting at every offset
within a run) must give hits and occlusion bit-identical to the same rays in shuffled order,
on every ISA, for batch sizes around multiples of the 64-ray run, 1 and 2 threads."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

ISAS = dacrt.supported_isas()
STRETCHES = (61, 64, 97, 200, 1000)
SIZES = (130, 191, 257, 640, 1283, 5000, 40_000)  # the last one sweeps forward at the root


@pytest.fixture(scope="module")
def mesh_and_rays():
    v, t = scenes.generated_100k()
    n = max(SIZES)
    org, dirs, tfar = make_rays("bounce", "mixed", v, t, n, seed=11)
    return (v, t), (org, dirs, tfar)


def _clustered(rays, n, stretch):
    """n rays in stretches: hitting rays, then as many (and a few more) culled at the root."""
    org, dirs, tfar = (a[:n].copy() for a in rays)
    away = (np.arange(n) // stretch) % 2 == 1
    away |= np.arange(n) % (7 * stretch) == 3  # more culled than kept: the root filter is never skipped
    org[away] = np.float32([40.0, 40.0, 40.0]) + org[away]
    dirs[away] = np.abs(dirs[away]) + np.float32(0.1)
    return org, dirs, tfar


@pytest.mark.parametrize("isa", ISAS)
def test_hits_do_not_depend_on_clustered_ray_order(mesh_and_rays, isa, monkeypatch):
    (v, t), rays = mesh_and_rays
    monkeypatch.setenv("DACRT_ISA", isa)
    scene = dacrt.Scene(v, t)
    for n in SIZES:
        for stretch in STRETCHES:
            org, dirs, tfar = _clustered(rays, n, stretch)
            want = harness.intersect(scene, org, dirs, tfar, threads=1, shuffle_seed=1)
            want_occ = harness.occluded(scene, org, dirs, tfar * np.float32(0.5), threads=1, shuffle_seed=2)
            assert np.mean(want["prim"] >= 0) > 0.2, "the kept stretches hit the mesh"
            for threads in (1, 2):
                hits = harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=None)
                occ = harness.occluded(scene, org, dirs, tfar * np.float32(0.5), threads=threads,
                                       shuffle_seed=None)
                diff = np.flatnonzero(np.any(hits.view(np.uint32).reshape(-1, 4) !=
                                             want.view(np.uint32).reshape(-1, 4), axis=1))
                assert len(diff) == 0, \
                    f"{isa}, {n} rays in stretches of {stretch}, {threads} threads: hits differ on " \
                    f"{len(diff)} rays, e.g. id {diff[0]}"
                assert np.array_equal(occ, want_occ), \
                    f"{isa}, {n} rays in stretches of {stretch}, {threads} threads: occlusion " \
                    f"differs on {np.sum(occ != want_occ)} rays"
