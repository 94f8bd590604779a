"""Determinism and the API's data contract: bit-identical results across thread counts, ISAs,
partition modes and leaf sizes; rays returned as a permutation of the input records; the
dtypes, make_rays, input conversions and Scene properties as the API describes them."""

import itertools

import dacrt
import numpy as np
import pytest

from . import harness, scenes
from .cases import build_case
from .rays import HIT_DTYPE, RAY_DTYPE, make_rays

ISAS = dacrt.supported_isas()

# Fixed cases covering the scene and ray kinds (built once, shared by the tests below).
FIXED = [("soup_dirty", 1, 6, "random", "mixed", 4000, 1),
         ("nested", 2, 4, "bounce", "inf", 4000, 2),
         ("cube", 3, 6, "axis", "mixed", 4000, 3),
         ("grid", 4, 6, "camera", "inf", 4000, 4),
         ("torus", 5, 6, "bounce", "finite", 4000, 5),
         ("soup_far", 6, 6, "camera", "mixed", 4000, 6)]


def results(monkeypatch, case, isa, threads, partition="adaptive", leaf_size=None, leaf_rays=32,
            spatial_order=False):
    monkeypatch.setenv("DACRT_ISA", isa)
    scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy(), partition=partition,
                        leaf_size=leaf_size, leaf_rays=leaf_rays, spatial_order=spatial_order)
    hits = harness.intersect(scene, case.org, case.dirs, case.tfar, threads=threads,
                             shuffle_seed=threads)
    mask = harness.occluded(scene, case.org, case.dirs, case.tfar, threads=threads,
                            shuffle_seed=threads + 7)
    return hits, mask


def assert_identical(a, b, what):
    ha, ma = a
    hb, mb = b
    diff = np.flatnonzero(np.any(ha.view(np.uint32).reshape(len(ha), 4) !=
                                 hb.view(np.uint32).reshape(len(hb), 4), axis=1))
    assert len(diff) == 0, (f"{what}: hits differ bit-for-bit on {len(diff)} rays, e.g. id "
                            f"{diff[0]}: {ha[diff[0]]} vs {hb[diff[0]]}")
    assert np.array_equal(ma, mb), f"{what}: occluded masks differ on {np.sum(ma != mb)} rays"


@pytest.mark.parametrize("key", FIXED, ids=[k[0] + "-" + k[3] for k in FIXED])
def test_identical_across_isas_and_threads(monkeypatch, key):
    case = build_case(*key)
    base = results(monkeypatch, case, "portable", 1)
    assert (base[0]["prim"] >= 0).any()
    for isa, threads in itertools.product(ISAS, [1, 2, 0]):
        if (isa, threads) != ("portable", 1):
            assert_identical(base, results(monkeypatch, case, isa, threads),
                             f"{key}: portable/1 thread vs {isa}/{threads} threads")


@pytest.mark.parametrize("key", FIXED, ids=[k[0] + "-" + k[3] for k in FIXED])
def test_identical_across_partition_modes_and_leaf_sizes(monkeypatch, key):
    """The closest hit is a function of the triangle set; conservative box tests and a
    deterministic tie rule make it independent of how the set is split."""
    case = build_case(*key)
    isa = ISAS[-1]
    base = results(monkeypatch, case, isa, 2)
    # (triangles, rays) leaf thresholds: both tiny, both huge, the defaults of both SIMD
    # widths, and one of each
    leaves = [(1, 1), (3, 3), (8, 8), (32, 32), (10**6, 10**6), (8, 32), (16, 32), (3, 1000), (1000, 3)]
    for partition, (leaf, rays) in itertools.product(["adaptive", "median", "sah"], leaves):
        assert_identical(base, results(monkeypatch, case, isa, 2, partition, leaf, rays),
                         f"{key}: adaptive/default/32 vs {partition}/{leaf}/{rays}")


@pytest.mark.parametrize("key", FIXED, ids=[k[0] + "-" + k[3] for k in FIXED])
def test_spatial_order_changes_nothing_but_memory(monkeypatch, key):
    """Morton-ordered storage reorders the triangles in memory only: hits report the caller's
    triangle index, ties still go to the lowest of those, and skip names the caller's index."""
    case = build_case(*key)
    for isa in ISAS:
        base = results(monkeypatch, case, isa, 2)
        assert_identical(base, results(monkeypatch, case, isa, 2, spatial_order=True),
                         f"{key}: {isa} in input order vs spatial order")
    # skip: each ray ignores the triangle the input-order scene says it hits first
    skip = np.where(base[0]["prim"] >= 0, base[0]["prim"], -1).astype(np.int32)
    got = [harness.intersect(dacrt.Scene(case.vertices, case.triangles, spatial_order=so),
                             case.org, case.dirs, case.tfar, threads=2, skip=skip)
           for so in (False, True)]
    assert_identical((got[0], base[1]), (got[1], base[1]), f"{key}: skip, input vs spatial order")
    assert not np.any((got[1]["prim"] == skip) & (skip >= 0)), "a skipped triangle was hit"


def test_spatial_order_is_independent_of_the_input_order(monkeypatch):
    """A shuffled mesh in spatial order hits the same triangles (mapped back through the
    shuffle), in the same place, as the mesh in its own order."""
    case = build_case(*FIXED[3])
    perm = np.random.default_rng(8).permutation(len(case.triangles))
    plain = harness.intersect(dacrt.Scene(case.vertices, case.triangles), case.org, case.dirs,
                              case.tfar, threads=2)
    shuffled = harness.intersect(dacrt.Scene(case.vertices, case.triangles[perm], spatial_order=True),
                                 case.org, case.dirs, case.tfar, threads=2)
    hit = plain["prim"] >= 0
    assert hit.sum() > len(hit) // 4
    np.testing.assert_array_equal(shuffled["prim"] >= 0, hit)
    np.testing.assert_array_equal(perm[shuffled["prim"][hit]], plain["prim"][hit])
    np.testing.assert_array_equal(shuffled["t"][hit], plain["t"][hit])


@pytest.mark.parametrize("key", FIXED[:4], ids=[k[0] + "-" + k[3] for k in FIXED[:4]])
def test_rays_alone_hit_what_they_hit_in_a_big_batch(monkeypatch, key):
    """A ray traced alone or in a batch of 2-5 takes another path through the recursion (other
    splits in adaptive mode, leaves closed by the ray count, mostly empty SIMD lanes) than in a
    batch of thousands; the hit must be the same bits, on every ISA, for closest and any hits."""
    case = build_case(*key)
    big_hits, big_occ = results(monkeypatch, case, ISAS[0], 1)
    picks = np.random.default_rng(5).choice(len(case.org), 40, replace=False)
    for isa in ISAS:
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy())
        for size in (1, 2, 3, 5):
            for start in range(0, 40, size):
                idx = picks[start:start + size]
                hits = harness.intersect(scene, case.org[idx], case.dirs[idx], case.tfar[idx], threads=1)
                occ = harness.occluded(scene, case.org[idx], case.dirs[idx], case.tfar[idx], threads=1)
                assert np.array_equal(hits.view(np.uint32), big_hits[idx].view(np.uint32)), \
                    f"{key} {isa}: rays {idx.tolist()} alone: {hits} vs in the batch: {big_hits[idx]}"
                assert np.array_equal(occ, big_occ[idx]), f"{key} {isa}: occluded of rays {idx.tolist()}"
    assert (big_hits["prim"][picks] >= 0).any()


def test_dtypes_match_the_spec():
    assert dacrt.RAY_DTYPE == RAY_DTYPE and dacrt.RAY_DTYPE.itemsize == 32
    assert dacrt.HIT_DTYPE == HIT_DTYPE and dacrt.HIT_DTYPE.itemsize == 16


def test_make_rays():
    rng = np.random.default_rng(0)
    o, d = rng.normal(size=(2, 50, 3))
    r = dacrt.make_rays(o, d)
    assert r.dtype == RAY_DTYPE and r.shape == (50,) and r.flags.c_contiguous
    np.testing.assert_array_equal(r["id"], np.arange(50))
    np.testing.assert_array_equal(r["org"], o.astype(np.float32))
    np.testing.assert_array_equal(r["dir"], d.astype(np.float32))
    assert np.all(np.isposinf(r["tfar"]))
    assert np.all(dacrt.make_rays(o, d, 2.5)["tfar"] == 2.5)
    tf = rng.uniform(0, 3, 50)
    np.testing.assert_array_equal(dacrt.make_rays(o, d, tf)["tfar"], tf.astype(np.float32))
    assert dacrt.make_rays(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


def test_rays_are_a_permutation_and_ids_need_not_be_positions():
    case = build_case("sphere", 1, 3, "random", "mixed", 2000, 11)
    scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy())
    base = harness.intersect(scene, case.org, case.dirs, case.tfar, shuffle_seed=None)
    for seed in (1, 2, 3):  # the harness checks the permutation and tfar contract each time
        np.testing.assert_array_equal(
            harness.intersect(scene, case.org, case.dirs, case.tfar, shuffle_seed=seed), base)
        harness.occluded(scene, case.org, case.dirs, case.tfar, shuffle_seed=seed)


def test_scene_copies_its_inputs_and_converts_types():
    case = build_case("torus", 2, 4, "camera", "inf", 2000, 12)
    v, t = case.vertices.copy(), case.triangles.copy()
    scene = dacrt.Scene(v, t)
    base = harness.intersect(scene, case.org, case.dirs, case.tfar)
    v[:] = 1e6
    t[:] = 0  # the scene must not look at the caller's arrays any more
    del v, t
    np.testing.assert_array_equal(harness.intersect(scene, case.org, case.dirs, case.tfar), base)
    variants = {
        "float64 vertices": (case.vertices.astype(np.float64), case.triangles),
        "uint32 triangles": (case.vertices, case.triangles.astype(np.uint32)),
        "int64 triangles": (case.vertices, case.triangles.astype(np.int64)),
        "read-only inputs": (case.vertices, case.triangles),  # the cached arrays are read-only
        "Fortran-ordered inputs": (np.asfortranarray(case.vertices),
                                   np.asfortranarray(case.triangles)),
    }
    for name, (vv, tt) in variants.items():
        got = harness.intersect(dacrt.Scene(vv, tt), case.org, case.dirs, case.tfar)
        np.testing.assert_array_equal(got, base, err_msg=name)


def test_scene_properties():
    v, t = scenes.make_scene("soup_dirty", 5, 2)
    zero_area = np.linalg.norm(np.cross(v[t[:, 1]].astype(float) - v[t[:, 0]],
                                        v[t[:, 2]].astype(float) - v[t[:, 0]]), axis=1) == 0
    scene = dacrt.Scene(v, t)
    assert scene.num_triangles == len(t)
    assert scene.num_degenerate == zero_area.sum() > 0
    assert (scene.partition, scene.leaf_size, scene.leaf_rays) == ("adaptive", None, 32)
    assert scene.sah_ratio == pytest.approx(128.0)
    o, d, tf = make_rays("random", "inf", v, t, 1000, 1)
    base = harness.intersect(scene, o, d, tf)
    # the default leaf size: 8 triangles on every kernel
    assert scene.last_stats["leaf_size"] == 8
    for mode in ("median", "sah", "adaptive"):
        scene.partition = mode
        assert scene.partition == mode
        np.testing.assert_array_equal(harness.intersect(scene, o, d, tf), base)
    scene.leaf_size = 3
    scene.leaf_rays = 5
    scene.sah_ratio = 0.5
    assert (scene.leaf_size, scene.leaf_rays, scene.sah_ratio) == (3, 5, 0.5)
    harness.intersect(scene, o, d, tf)
    assert scene.last_stats["leaf_size"] == 3
    scene.leaf_size = None
    assert scene.leaf_size is None
    np.testing.assert_array_equal(harness.intersect(scene, o, d, tf), base)


def test_degenerate_triangles_are_never_hit():
    v, t = scenes.make_scene("soup_dirty", 8, 4)
    area = np.linalg.norm(np.cross(v[t[:, 1]].astype(float) - v[t[:, 0]],
                                   v[t[:, 2]].astype(float) - v[t[:, 0]]), axis=1)
    # rays aimed exactly at vertices of the degenerate triangles
    targets = v[t[area == 0].ravel()].astype(np.float64)
    rng = np.random.default_rng(3)
    d = rng.normal(size=targets.shape)
    o = targets - d * 2
    hits = harness.intersect(dacrt.Scene(v, t), o, d, np.inf)
    hit = hits["prim"] >= 0
    assert not np.any(area[hits["prim"][hit]] == 0), "a zero-area triangle was hit"


def assert_kept_matches_fresh(kept, fresh, org, dirs, tfar, threads, what):
    """A keep_top scene returns, bit for bit, what a fresh scene returns for the same batch."""
    a = (harness.intersect(kept, org, dirs, tfar, threads=threads),
         harness.occluded(kept, org, dirs, tfar, threads=threads))
    b = (harness.intersect(fresh, org, dirs, tfar, threads=threads),
         harness.occluded(fresh, org, dirs, tfar, threads=threads))
    assert (a[0]["prim"] >= 0).any()
    assert_identical(a, b, f"{what}: kept top vs fresh scene")


@pytest.mark.parametrize("partition", ["adaptive", "median", "sah"])
def test_kept_top_levels_give_identical_results(partition):
    """keep_top reuses the partition's top splits across calls (a frame's batches): every call
    must return what a fresh scene returns, for several ray batches, thread counts, and a
    settings change in between (which resets what is kept); a batch under 64K rays (the third)
    uses what a bigger one kept."""
    rng = np.random.default_rng(41)
    m = 20000                                        # deep enough for ~6 shared levels
    centres = rng.normal(size=(m, 1, 3)) * 4
    v = (centres + rng.normal(size=(m, 3, 3)) * 0.15).reshape(-1, 3).astype(np.float32)
    t = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    kept = dacrt.Scene(v, t, partition=partition, keep_top=True)
    batches = [make_rays(kind, "inf", v, t, n, seed) for kind, n, seed in
               (("camera", 70000, 1), ("bounce", 100000, 2), ("random", 800, 3), ("bounce", 66000, 4))]
    for i, (org, dirs, tfar) in enumerate(batches):
        threads = (1, 2, 0, 2)[i]
        assert_kept_matches_fresh(kept, dacrt.Scene(v, t, partition=partition), org, dirs, tfar, threads,
                                  f"{partition} batch {i}")
        if i == 1:                                   # a settings change resets what is kept
            kept.partition = "sah" if partition != "sah" else "median"
            partition = kept.partition


def test_a_small_first_batch_sets_the_kept_top():
    """A frame whose batches are all small (a 1-sample render of a big scene, a renderer's probe
    rays) still keeps its splits: the first small batch sets the kept top and a later batch
    reuses it instead of partitioning the whole scene again, with results identical to a fresh
    scene's."""
    v, t = scenes.random_soup(np.random.default_rng(5), 40000, spread=1.0, size=0.02)
    kept = dacrt.Scene(v, t, keep_top=True)
    probe = make_rays("camera", "inf", v, t, 2000, 21)
    steps = []
    for threads in (1, 2):
        harness.intersect(kept, *probe, threads=threads)
        steps.append(kept.last_stats["partition_steps"])
    assert steps[0] > 100, "the first small batch partitions"
    assert steps[1] * 10 < steps[0], f"the same batch again partitions almost nothing: {steps}"
    assert_kept_matches_fresh(kept, dacrt.Scene(v, t), *probe, 2, "the probe")
    bigger = make_rays("bounce", "inf", v, t, 20000, 22)
    assert_kept_matches_fresh(kept, dacrt.Scene(v, t), *bigger, 2, "a later batch")


def test_kept_top_on_a_very_uneven_scene():
    """A kept top follows the tree down to small nodes however deep it is: on geometry whose
    density grows geometrically towards a point (spatial-median splits then cut one triangle
    cluster at a time, far deeper than log2 of the triangle count), every batch still returns
    what a fresh scene returns."""
    rng = np.random.default_rng(7)
    m = 30000
    scale = 2.0 ** -rng.integers(0, 40, size=(m, 1, 1))      # clusters at 1, 1/2, ... 2^-39
    v = (rng.normal(size=(m, 1, 3)) * scale + rng.normal(size=(m, 3, 3)) * scale * 0.2)
    v = v.reshape(-1, 3).astype(np.float32)
    t = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    kept = dacrt.Scene(v, t, keep_top=True)
    depth = 0
    for i, (kind, n, threads) in enumerate((("camera", 70000, 2), ("bounce", 90000, 1), ("random", 5000, 2))):
        org, dirs, tfar = make_rays(kind, "inf", v, t, n, 10 + i)
        assert_kept_matches_fresh(kept, dacrt.Scene(v, t), org, dirs, tfar, threads, f"batch {i}")
        depth = max(depth, kept.last_stats["max_depth"])
    assert depth > 2 * np.log2(m / 32)          # far deeper than a balanced tree
