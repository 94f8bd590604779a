"""A frame's small late batches on a kept top: few rays at a shared node of more than 32 triangles
split it for the frame instead of testing all its triangles brute force.

The last bounces of a low-sample frame (1-10K rays against 100K triangles) reach most nodes with
one to three rays. With nodes of up to 256 triangles left unsplit for them, every such visit was
a leaf of up to 256 triangles (a 4-spp dragon frame: 90-180 triangle tests a ray); split once for
the frame, they test a few leaves of at most 32.
"""

import dacrt
import numpy as np

from . import harness, scenes
from .rays import make_rays


def test_few_ray_batches_on_a_kept_top_meet_small_leaves():
    v, t = scenes.icosphere(6)                        # 81,920 triangles, a closed surface
    kept = dacrt.Scene(v, t, keep_top=True)
    harness.intersect(kept, *make_rays("camera", "inf", v, t, 20000, 1), threads=1)  # the frame's first batch
    per_ray = []
    for seed in (2, 3, 4):                            # later bounces of 1,000 rays each
        org, dirs, tfar = make_rays("bounce", "inf", v, t, 1000, seed)
        got = harness.intersect(kept, org, dirs, tfar, threads=1)
        per_ray.append(kept.last_stats["tri_tests"] / kept.last_stats["rays"])
        want = harness.intersect(dacrt.Scene(v, t), org, dirs, tfar, threads=1)
        assert (got["prim"] >= 0).any()
        assert got.tobytes() == want.tobytes(), f"batch {seed}: kept top vs fresh scene"
        blocked = harness.occluded(kept, org, dirs, tfar, threads=2)
        assert np.array_equal(blocked, harness.occluded(dacrt.Scene(v, t), org, dirs, tfar, threads=2))
    # leaves of <= 256 triangles for few rays: ~500 tests a ray; of <= 32: ~75
    assert max(per_ray[1:]) < 150, f"triangle tests per ray of the later small batches: {per_ray}"
