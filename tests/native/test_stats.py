"""Per-call statistics (`Scene.last_stats`), ISA selection, and the empty cases: empty scene,
empty ray batch, a scene of only zero-area triangles."""

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .rays import make_rays

STATS_KEYS = {"rays", "box_tests", "tri_tests", "partition_steps", "median_steps", "sah_steps",
              "leaves", "filter_skips", "threads", "isa", "seconds"}
COUNTERS = STATS_KEYS - {"isa", "seconds"}


def check_stats(stats, n, m, threads=None):
    assert STATS_KEYS <= set(stats), f"last_stats lacks {STATS_KEYS - set(stats)}"
    assert stats["rays"] == n
    for k in COUNTERS:
        assert isinstance(stats[k], (int, np.integer)) and stats[k] >= 0, (k, stats[k])
    assert stats["isa"] in dacrt.supported_isas()
    assert isinstance(stats["seconds"], float) and 0.0 <= stats["seconds"] < 600
    # Object partitioning puts each triangle in one child: a ray meets a triangle at most once.
    assert stats["tri_tests"] <= n * m, f"{stats['tri_tests']} triangle tests for {n}x{m}"
    if threads:
        assert 1 <= stats["threads"] <= threads
    return stats


@pytest.mark.parametrize("query", ["intersect", "occluded"])
@pytest.mark.parametrize("partition", ["adaptive", "median", "sah"])
def test_stats_are_sane(query, partition):
    v, t = scenes.make_scene("nested", 1, 5)
    o, d, tf = make_rays("bounce", "inf", v, t, 5000, 2)
    scene = dacrt.Scene(v, t, partition=partition, leaf_size=4)
    out = getattr(harness, query)(scene, o, d, tf, threads=2)
    assert np.any(out["prim"] >= 0) if query == "intersect" else np.any(out)
    s = check_stats(scene.last_stats, len(o), len(t), threads=2)
    assert s["tri_tests"] > 0 and s["box_tests"] > 0 and s["leaves"] > 0
    assert s["partition_steps"] > 0  # 5000 rays x ~1000 triangles cannot be one leaf of 4
    if partition == "median":
        assert s["sah_steps"] == 0 and s["median_steps"] > 0
    if partition == "sah":
        assert s["sah_steps"] > 0
    assert s["isa"] == dacrt.isa()


def test_filters_are_skipped_only_where_most_rays_hit_the_box(monkeypatch):
    """A node whose box most of its (>= 1024) rays hit keeps them all instead of filtering; the
    children's filters cull the rest. Rays all aimed into a torus from around it skip at least
    the root's filter; rays all aimed away from it, or fewer than 1024 rays, skip none. The hits
    are the same bits as the same rays traced in batches too small to skip, on every ISA."""
    v, t = scenes.make_scene("torus", 3, 6)
    rng = np.random.default_rng(11)
    n = 3000
    o = rng.normal(size=(n, 3)) * 3.0
    target = rng.uniform(-1.0, 1.0, (n, 3)) * np.array([1.2, 1.2, 0.3])
    inward = (target - o).astype(np.float32)
    tf = np.full(n, np.inf, np.float32)
    for isa in dacrt.supported_isas():
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(v, t)
        big = harness.intersect(scene, o, inward, tf, threads=1)
        assert check_stats(scene.last_stats, n, len(t))["filter_skips"] >= 1, isa
        assert (big["prim"] >= 0).mean() > 0.3
        small = np.concatenate([harness.intersect(scene, o[i:i + 500], inward[i:i + 500], tf[i:i + 500],
                                                  threads=1) for i in range(0, n, 500)])
        assert scene.last_stats["filter_skips"] == 0, f"{isa}: 500 rays are too few to skip"
        assert np.array_equal(big.view(np.uint32), small.view(np.uint32)), isa
        occ_big = harness.occluded(scene, o, inward, tf, threads=1)
        occ_small = np.concatenate([harness.occluded(scene, o[i:i + 500], inward[i:i + 500], tf[i:i + 500],
                                                     threads=1) for i in range(0, n, 500)])
        assert np.array_equal(occ_big, occ_small) and occ_big.any(), isa
        # o . away >= 0: each ray heads away from the torus's centre
        away = np.where(np.sum(o * inward, axis=1, keepdims=True) < 0, -inward, inward)
        harness.intersect(scene, o + 1e-3 * away, away, tf, threads=1)
        assert scene.last_stats["filter_skips"] == 0, f"{isa}: rays leaving the torus's box skipped a filter"


def test_stats_follow_the_last_call():
    v, t = scenes.make_scene("sphere", 1, 3)
    scene = dacrt.Scene(v, t)
    o, d, tf = make_rays("random", "inf", v, t, 700, 1)
    harness.intersect(scene, o, d, tf, threads=1)
    assert scene.last_stats["rays"] == 700 and scene.last_stats["threads"] == 1
    harness.occluded(scene, o[:123], d[:123], tf[:123], threads=2)
    assert scene.last_stats["rays"] == 123


def test_isa_selection(monkeypatch):
    isas = dacrt.supported_isas()
    assert "portable" in isas and set(isas) <= {"portable", "avx2", "avx512"}
    monkeypatch.delenv("DACRT_ISA", raising=False)
    best = max(isas, key=["portable", "avx2", "avx512"].index)
    assert dacrt.isa() == best, "without DACRT_ISA the best supported ISA is used"
    v, t = scenes.make_scene("soup", 1, 1)
    o, d, tf = make_rays("random", "inf", v, t, 64, 1)
    for isa in isas:
        monkeypatch.setenv("DACRT_ISA", isa)
        assert dacrt.isa() == isa
        scene = dacrt.Scene(v, t)
        harness.intersect(scene, o, d, tf)
        assert scene.last_stats["isa"] == isa


def test_empty_scene():
    o, d, tf = make_rays("random", "mixed", np.zeros((0, 3), np.float32),
                         np.zeros((0, 3), np.int32), 100, 3)
    for v in (np.zeros((0, 3), np.float32), scenes.icosphere(1)[0]):
        scene = dacrt.Scene(v, np.zeros((0, 3), np.int32))
        assert scene.num_triangles == 0
        hits = harness.intersect(scene, o, d, tf)
        assert np.all(hits["prim"] == -1) and np.all(np.isposinf(hits["t"]))
        assert np.all(hits["u"] == 0) and np.all(hits["v"] == 0)
        assert not harness.occluded(scene, o, d, tf).any()
        check_stats(scene.last_stats, 100, 0)
        assert scene.last_stats["tri_tests"] == 0


def test_empty_ray_batch():
    v, t = scenes.make_scene("torus", 1, 2)
    scene = dacrt.Scene(v, t)
    rays = dacrt.make_rays(np.zeros((0, 3)), np.zeros((0, 3)))
    hits = scene.intersect(rays)
    assert hits.shape == (0,) and hits.dtype == dacrt.HIT_DTYPE
    mask = scene.occluded(rays)
    assert mask.shape == (0,) and mask.dtype == np.bool_
    assert scene.last_stats["rays"] == 0 and scene.last_stats["tri_tests"] == 0
    empty = dacrt.Scene(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32))
    assert empty.intersect(rays).shape == (0,)


def test_all_degenerate_scene():
    rng = np.random.default_rng(5)
    a = np.round(rng.uniform(-1, 1, (300, 3)) * 64) / 64
    step = rng.integers(-4, 5, (300, 3)) / 8
    v = np.stack([a, a + step, a + 2 * step], 1).reshape(-1, 3).astype(np.float32)  # collinear
    t = np.arange(900).reshape(300, 3).astype(np.int32)
    t[::3, 1] = t[::3, 0]  # and some with a repeated vertex index
    scene = dacrt.Scene(v, t)
    assert scene.num_triangles == 300 and scene.num_degenerate == 300
    # rays through the degenerate triangles' points, from every side
    targets = v.astype(np.float64)
    d = rng.normal(size=targets.shape)
    o = targets - 3 * d
    hits = harness.intersect(scene, o, d, np.inf)
    assert np.all(hits["prim"] == -1)
    assert not harness.occluded(scene, o, d, np.inf).any()
