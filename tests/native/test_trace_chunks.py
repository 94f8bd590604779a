"""Ray chunks cut at the median origin (native/cpp/chunkorder.cpp) and work stealing (a thread
out of chunks takes a farther child another thread has yet to visit, with a copy of its rays
and hits of its own, merged afterwards: StealBoard, native/cpp/kernel.h) change the work,
never a hit: hits bit-identical to one portable thread for 1..4 threads on every ISA, also on
adversarial ray sets (one origin for all rays, half the rays missing everything, fewer rays
than threads; a batch of one origin is cut by index and steals nothing), with skip arrays, and the rays' in-place contract (tfar = hit distance, or
negative when occluded) kept for rays whose hit a stolen task found (harness checks it)."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

ISAS = dacrt.supported_isas()
N_RAYS = 30_000


@pytest.fixture(scope="module")
def mesh():
    return scenes.generated_100k()


def _rays(mesh, kind):
    v, t = mesh
    org, dirs, tfar = make_rays("bounce", "mixed", v, t, N_RAYS, seed=11)
    if kind == "one_origin":  # camera-like, from the torus' hole: nothing to sort by
        org[:] = 0.0
    elif kind == "half_miss":  # the second half starts far out and points away: a cheap chunk
        half = N_RAYS // 2
        org[half:] = np.float32([40.0, 40.0, 40.0]) + org[half:]
        dirs[half:] = np.abs(dirs[half:]) + np.float32(0.1)
    return org, dirs, tfar


def _both(scene, rays, threads, skip=None):
    org, dirs, tfar = rays
    kw = {} if skip is None else {"skip": skip}
    hits = harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads, **kw)
    steals = scene.last_stats["steals"]
    occ = harness.occluded(scene, org, dirs, tfar * np.float32(0.5), threads=threads,
                           shuffle_seed=threads + 1, **kw)
    return hits, occ, steals + scene.last_stats["steals"]


def _assert_same(a, b, what):
    diff = np.flatnonzero(np.any(a[0].view(np.uint32).reshape(-1, 4) !=
                                 b[0].view(np.uint32).reshape(-1, 4), axis=1))
    assert len(diff) == 0, f"{what}: hits differ on {len(diff)} rays, e.g. id {diff[0]}"
    assert np.array_equal(a[1], b[1]), f"{what}: occlusion differs on {np.sum(a[1] != b[1])} rays"


@pytest.mark.parametrize("kind", ["bounce", "one_origin", "half_miss"])
def test_identical_hits_with_stealing_for_1_to_4_threads_on_every_isa(mesh, kind, monkeypatch):
    v, t = mesh
    rays = _rays(mesh, kind)
    monkeypatch.setenv("DACRT_ISA", "portable")
    base = _both(dacrt.Scene(v, t), rays, 1)
    assert base[2] == 0, "one thread has no one to steal from"
    assert 0.2 < (base[0]["prim"] >= 0).mean() < 1 and 0 < base[1].mean() < 1
    steals = 0
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        for threads in (1, 2, 3, 4):
            # one chunk per thread, 2 and 7 chunks, and a kept top (chunks from 1K rays)
            for kw in ({}, {"chunk_rays": N_RAYS // 2}, {"chunk_rays": N_RAYS // 7}, {"keep_top": True}):
                scene = dacrt.Scene(v, t, **kw)
                for _ in range(2 if kw.get("keep_top") else 1):  # a kept top's second call too
                    got = _both(scene, rays, threads)
                    _assert_same(base, got, f"{kind}, {isa}, {threads} threads, {kw}")
                    steals += got[2]
    if kind == "one_origin":  # chunks cut by index cost alike: no stealing between them
        assert steals == 0, f"{kind}: {steals} steals among chunks of one origin"
    else:  # whether a thread steals depends on timing; over these dozens of calls some do
        assert steals > 0, f"{kind}: no call stole any work"


def test_skip_arrays_follow_stolen_rays(mesh, monkeypatch):
    """A stolen task renumbers its rays: each keeps its own skip entry."""
    v, t = mesh
    org, dirs, tfar = _rays(mesh, "bounce")
    monkeypatch.setenv("DACRT_ISA", "portable")
    base_hits = harness.intersect(dacrt.Scene(v, t), org, dirs, tfar, threads=1)
    # skip the first hit of every other ray: their hits move on to the next triangle
    skip = np.where(np.arange(N_RAYS) % 2 == 0, base_hits["prim"], -1).astype(np.int32)
    ref = _both(dacrt.Scene(v, t), (org, dirs, tfar), 1, skip=skip)
    assert (ref[0]["prim"] != base_hits["prim"]).sum() > N_RAYS // 10
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        for threads in (2, 3):
            got = _both(dacrt.Scene(v, t, chunk_rays=N_RAYS // 5), (org, dirs, tfar), threads, skip=skip)
            _assert_same(ref, got, f"skip, {isa}, {threads} threads")


def test_fewer_rays_than_threads(mesh, monkeypatch):
    v, t = mesh
    org, dirs, tfar = (a[:3] for a in _rays(mesh, "bounce"))
    monkeypatch.setenv("DACRT_ISA", "portable")
    base = _both(dacrt.Scene(v, t), (org, dirs, tfar), 1)
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        for kw in ({}, {"chunk_rays": 1}, {"keep_top": True}):
            got = _both(dacrt.Scene(v, t, **kw), (org, dirs, tfar), 4)
            _assert_same(base, got, f"3 rays, {isa}, 4 threads, {kw}")
