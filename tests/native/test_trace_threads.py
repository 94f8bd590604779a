"""A trace call split into several ray chunks (threads, or `chunk_rays` on one thread, the
chunks then traced in turn) gives hits bit-identical to one chunk, for 1..4 threads on every
ISA: the chunks share the partition's top (native/cpp/kernel.h SharedTop), each follows its
own rays below it, and which thread splits a shared node, or how the rays are cut into
chunks, changes the work, never a hit."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

ISAS = dacrt.supported_isas()
N_RAYS = 40_000


@pytest.fixture(scope="module")
def case():
    v, t = scenes.generated_100k()
    org, dirs, tfar = make_rays("bounce", "inf", v, t, N_RAYS, seed=3)
    return v, t, org, dirs, tfar


def _scene(case, **kw):
    v, t = case[0], case[1]
    return dacrt.Scene(v.copy(), t.copy(), **kw)


def _both(scene, case, threads):
    org, dirs, tfar = case[2:]
    hits = harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads)
    occ = harness.occluded(scene, org, dirs, tfar * np.float32(0.5), threads=threads,
                           shuffle_seed=threads + 1)
    return hits, occ


def _assert_same(a, b, what):
    diff = np.flatnonzero(np.any(a[0].view(np.uint32).reshape(-1, 4) !=
                                 b[0].view(np.uint32).reshape(-1, 4), axis=1))
    assert len(diff) == 0, f"{what}: hits differ on {len(diff)} rays, e.g. id {diff[0]}"
    assert np.array_equal(a[1], b[1]), f"{what}: occlusion differs on {np.sum(a[1] != b[1])} rays"


def test_identical_hits_for_1_to_4_threads_and_chunks_on_every_isa(case, monkeypatch):
    monkeypatch.setenv("DACRT_ISA", "portable")
    base = _both(_scene(case), case, 1)
    assert (base[0]["prim"] >= 0).mean() > 0.3 and 0 < base[1].mean() < 1
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        for threads in (1, 2, 3, 4):
            # default chunks (one per thread at >= 64K rays: here one), then 2..40 chunks
            for chunk_rays in (0, N_RAYS // 2, N_RAYS // 3 + 1, 1000):
                got = _both(_scene(case, chunk_rays=chunk_rays), case, threads)
                _assert_same(base, got, f"{isa}, {threads} threads, chunk_rays {chunk_rays}")
