"""A kept top stores the triangles in its own order: after a frame's first call, and again when
its splits have doubled, so that a leaf's triangle records share cache lines. The order only
moves records: every later call returns bit for bit what a fresh scene returns, with skips,
masks, degenerate and duplicate triangles, on 1 and 2 threads, after a settings change that
resets the top, and in agreement with the float64 reference.
"""

import dacrt
import numpy as np

from . import agreement, harness, reference, scenes
from .rays import make_rays


def _fresh(v, t, masks):
    return dacrt.Scene(v, t, masks=masks)


def _same_as_fresh(kept, v, t, masks, org, dirs, tfar, threads, what, **kw):
    got = harness.intersect(kept, org, dirs, tfar, threads=threads, **kw)
    ordered = kept.last_stats["order_seconds"]
    want = harness.intersect(_fresh(v, t, masks), org, dirs, tfar, threads=threads, **kw)
    assert got.tobytes() == want.tobytes(), f"{what}: kept top vs fresh scene (intersect)"
    blocked = harness.occluded(kept, org, dirs, tfar, threads=threads, **kw)
    assert np.array_equal(blocked, harness.occluded(_fresh(v, t, masks), org, dirs, tfar, threads=threads, **kw)), \
        f"{what}: kept top vs fresh scene (occluded)"
    return got, ordered


def test_kept_top_orders_the_triangles_once_it_has_splits_and_hits_do_not_change():
    rng = np.random.default_rng(11)
    v, t = scenes.icosphere(5)                        # 20,480 triangles, a closed surface
    v, t = scenes.add_degenerates_and_duplicates(rng, v, t, 40, 40)
    masks = rng.integers(1, 4, len(t)).astype(np.uint8)
    kept = dacrt.Scene(v, t, keep_top=True, masks=masks)

    org, dirs, tfar = make_rays("camera", "inf", v, t, 20000, 2)      # the frame's first batch
    hits, ordered = _same_as_fresh(kept, v, t, masks, org, dirs, tfar, 2, "camera batch")
    assert (hits["prim"] >= 0).sum() > 5000
    assert ordered > 0.0, "the first call on a kept top with splits stores the triangles in its order"
    assert ordered <= kept.last_stats["seconds"]

    orders = []
    for seed, threads in ((2, 1), (3, 2), (4, 2)):                   # later, smaller bounces
        org, dirs, tfar = make_rays("bounce", "mixed", v, t, 1500, seed)
        skip = np.full(len(org), -1, np.int32)
        skip[::3] = rng.integers(0, len(t), len(skip[::3]))
        _, ordered = _same_as_fresh(kept, v, t, masks, org, dirs, tfar, threads, f"bounce {seed}",
                                    skip=skip, visible=1 + seed % 3)
        orders.append(ordered)
    assert orders[-1] == 0.0, "a call that adds few splits leaves the order as it is"

    # float64 reference on the reordered scene
    org, dirs, tfar = make_rays("random", "finite", v, t, 600, 5)
    got = harness.intersect(kept, org, dirs, tfar, threads=2)
    ref = reference.trace(v, t, org, dirs, tfar)
    agreement.check_hits(v, t, org, dirs, tfar, got, ref, context="ordered kept top")
    agreement.check_occluded(org, dirs, tfar, harness.occluded(kept, org, dirs, tfar, threads=2), ref,
                             context="ordered kept top")

    # other settings reset the top (its ids start again from the valid slots): ordered anew
    kept.partition = "median"
    org, dirs, tfar = make_rays("camera", "finite", v, t, 8000, 6)
    _, ordered = _same_as_fresh(kept, v, t, masks, org, dirs, tfar, 2, "after a reset")
    assert ordered > 0.0


def test_a_scene_without_a_kept_top_never_orders():
    v, t = scenes.icosphere(4)
    scene = dacrt.Scene(v, t)
    for seed in (1, 2):
        harness.intersect(scene, *make_rays("camera", "inf", v, t, 4000, seed), threads=2)
        assert scene.last_stats["order_seconds"] == 0.0
