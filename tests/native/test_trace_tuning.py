"""Tracer tuning that changes the work, never a hit: the shared top's splits partition their ids
stably (native/cpp/partition.h partition_ids_stable: nodes of >= 1024 ids keep them in ascending
order, so box reads go one way through memory), private nodes in place (Hoare). Hits and
occlusion must be bit-identical to one portable thread whatever the triangles' memory order
(mesh order, shuffled, Morton), the partition mode (median and SAH splits both partition the
shared ids), a kept top reused across calls, 1..4 threads and every ISA."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

ISAS = dacrt.supported_isas()
N_RAYS = 20_000


@pytest.fixture(scope="module")
def mesh():
    return scenes.generated_100k()


@pytest.fixture(scope="module")
def rays(mesh):
    v, t = mesh
    return make_rays("bounce", "mixed", v, t, N_RAYS, seed=5)


def _trace(scene, rays, threads):
    org, dirs, tfar = rays
    hits = harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads)
    occ = harness.occluded(scene, org, dirs, tfar * np.float32(0.5), threads=threads, shuffle_seed=threads + 1)
    return hits, occ


def _assert_same(a, b, what):
    diff = np.flatnonzero(np.any(a[0].view(np.uint32).reshape(-1, 4) != b[0].view(np.uint32).reshape(-1, 4), axis=1))
    assert len(diff) == 0, f"{what}: hits differ on {len(diff)} rays, e.g. id {diff[0]}"
    assert np.array_equal(a[1], b[1]), f"{what}: occlusion differs on {np.sum(a[1] != b[1])} rays"


@pytest.mark.parametrize("partition", ["adaptive", "median", "sah"])
def test_shared_splits_change_no_hit_for_any_triangle_order(mesh, rays, partition, monkeypatch):
    v, t = mesh
    monkeypatch.setenv("DACRT_ISA", "portable")
    base = _trace(dacrt.Scene(v, t, partition=partition), rays, 1)
    assert np.count_nonzero(base[0]["prim"] >= 0) > N_RAYS // 4, "the rays must hit the mesh"
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        for threads in (1, 2, 3, 4):
            for spatial in (False, True):  # mesh order, Morton order: other ids, other box reads
                scene = dacrt.Scene(v, t, partition=partition, spatial_order=spatial)
                _assert_same(base, _trace(scene, rays, threads),
                             f"{partition} {isa} {threads} threads, spatial_order={spatial}")


@pytest.mark.parametrize("threads", [1, 2, 4])
def test_kept_top_reused_across_calls_changes_no_hit(mesh, rays, threads, monkeypatch):
    v, t = mesh
    monkeypatch.setenv("DACRT_ISA", "portable")
    base = _trace(dacrt.Scene(v, t), rays, 1)
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(v, t, keep_top=True)
        org, dirs, tfar = rays
        # a small batch first sets the kept top, the full batch then reuses and extends it
        harness.intersect(scene, org[:500], dirs[:500], tfar[:500], threads=threads)
        for _ in range(2):
            _assert_same(base, _trace(scene, rays, threads), f"kept top {isa} {threads} threads")
