"""Per-triangle visibility masks: a call with `visible` must return exactly what a scene made of
only the triangles it sees returns (hit triangle, t, u, v bit for bit; occlusion), on every ISA
and thread count, also when one keep_top scene serves several ray kinds in turn."""
import numpy as np
import pytest

import dacrt

from . import harness
from .rays import make_rays

ISAS = dacrt.supported_isas()


def _clustered(m, seed):
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(m, 1, 3)) * 3
    v = (centres + rng.normal(size=(m, 3, 3)) * 0.25).reshape(-1, 3).astype(np.float32)
    t = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    masks = rng.integers(0, 8, size=m).astype(np.uint8)      # 3 ray kinds; some seen by none
    masks[rng.random(m) < 0.7] = 7                           # most triangles seen by all kinds
    return v, t, masks


def _expected(v, t, masks, bit, org, dirs, tfar, threads):
    """Hits and occlusion from a scene of only the triangles with `bit`, in global indices."""
    sub = np.flatnonzero(masks & bit)
    fresh = dacrt.Scene(v, t[sub])
    hits = harness.intersect(fresh, org, dirs, tfar, threads=threads)
    hits["prim"] = np.where(hits["prim"] >= 0, sub[np.maximum(hits["prim"], 0)], -1)
    return hits, harness.occluded(fresh, org, dirs, tfar, threads=threads)


@pytest.mark.parametrize("isa", ISAS)
def test_visible_traces_exactly_the_triangles_it_sees(isa, monkeypatch):
    monkeypatch.setenv("DACRT_ISA", isa)
    v, t, masks = _clustered(6000, 3)
    kept = dacrt.Scene(v, t, masks=masks, keep_top=True)
    for i, (bit, kind, threads) in enumerate(((1, "camera", 2), (2, "bounce", 1), (4, "bounce", 2),
                                              (3, "random", 2), (1, "bounce", 2))):
        org, dirs, tfar = make_rays(kind, "inf", v, t, 40000, 30 + i)
        want_hits, want_occ = _expected(v, t, masks, bit, org, dirs, tfar, threads)
        for scene in (kept, dacrt.Scene(v, t, masks=masks),
                      dacrt.Scene(v, t, masks=masks, keep_top=True, spatial_order=True)):
            hits = harness.intersect(scene, org, dirs, tfar, threads=threads, visible=bit)
            assert (hits["prim"] >= 0).any()
            np.testing.assert_array_equal(hits["prim"], want_hits["prim"], f"bit {bit}: hit triangles")
            hit = hits["prim"] >= 0
            for f in ("t", "u", "v"):
                np.testing.assert_array_equal(hits[f][hit].view(np.uint32),
                                              want_hits[f][hit].view(np.uint32), f"bit {bit}: {f}")
            occ = harness.occluded(scene, org, dirs, tfar, threads=threads, visible=bit)
            np.testing.assert_array_equal(occ, want_occ, f"bit {bit}: occlusion")
        seen = masks[hits["prim"][hit]]
        assert np.all(seen & bit), "a triangle without the call's bit was hit"


def test_without_visible_every_triangle_counts_and_bad_masks_are_refused():
    v, t, masks = _clustered(2000, 4)
    org, dirs, tfar = make_rays("random", "inf", v, t, 5000, 1)
    plain = harness.intersect(dacrt.Scene(v, t), org, dirs, tfar)
    masked = harness.intersect(dacrt.Scene(v, t, masks=masks), org, dirs, tfar)
    np.testing.assert_array_equal(plain["prim"], masked["prim"])
    with pytest.raises(ValueError, match="masks must be a uint8 array"):
        dacrt.Scene(v, t, masks=masks.astype(np.int32))
    with pytest.raises(ValueError, match="masks must be a uint8 array"):
        dacrt.Scene(v, t, masks=masks[:-1])
    scene = dacrt.Scene(v, t, masks=masks)
    rays = harness.packed(org, dirs, tfar)
    for bad in (0, 256, -1, True, 1.0):
        with pytest.raises(ValueError, match="visible must be an integer in 1..255"):
            scene.intersect(rays, visible=bad)
    with pytest.raises(ValueError, match="made without masks"):
        dacrt.Scene(v, t).occluded(rays, visible=1)
