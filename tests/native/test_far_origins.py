"""Rays with far origins in a batch of near ones. The filter pads node boxes by the rounding a
ray of the batch's largest |origin| needs; a few far rays must not pad the boxes of every other
ray (the tracer traces them as groups of their own), and grouping must change no hit."""

import dacrt
import numpy as np
import pytest

from . import agreement, harness, reference, scenes

ISAS = dacrt.supported_isas()


def _small_triangles():
    # 20K triangles of ~0.01 in the unit cube: far origins pad their boxes many times over
    return scenes.random_soup(np.random.default_rng(11), 20000, spread=1.0, size=0.005)


def _rays(rng, n, distance):
    """n rays aimed through the unit cube, their origins `distance` away (0: inside it)."""
    target = rng.uniform(-1, 1, (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    org = target if distance == 0 else target - d * distance
    return (org.astype(np.float32), d.astype(np.float32),
            np.full(n, np.inf, np.float32))


def _batch():
    """4000 near rays, then 20 far rays at each of six distances (groups of their own)."""
    rng = np.random.default_rng(3)
    parts = [_rays(rng, 4000, 0)] + [_rays(rng, 20, x) for x in (3e3, 5e4, 1e6, 3e7, 1e12, 1e30)]
    return tuple(np.concatenate([p[k] for p in parts]) for k in range(3))


@pytest.mark.parametrize("isa", ISAS)
def test_far_origins_change_no_hit(monkeypatch, isa):
    monkeypatch.setenv("DACRT_ISA", isa)
    v, t = _small_triangles()
    org, dirs, tfar = _batch()
    near = slice(0, 4000)
    alone_scene = dacrt.Scene(v, t)
    near_hits = harness.intersect(alone_scene, org[near], dirs[near], tfar[near], threads=1)
    near_occ = harness.occluded(alone_scene, org[near], dirs[near], tfar[near], threads=1)
    far = slice(4000, None)
    ref = reference.trace(v, t, org[far], dirs[far], tfar[far])  # float64 brute force
    for threads, chunk_rays in ((1, 0), (2, 0), (2, 7)):
        scene = dacrt.Scene(v, t, chunk_rays=chunk_rays)
        hits = harness.intersect(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads)
        occ = harness.occluded(scene, org, dirs, tfar, threads=threads, shuffle_seed=threads)
        assert np.array_equal(hits[near].view(np.uint32), near_hits.view(np.uint32)), \
            f"{isa}, {threads} threads, chunks of {chunk_rays}: near rays' hits changed"
        assert np.array_equal(occ[near], near_occ)
        # every far ray against the reference
        agreement.check_hits(v, t, org[far], dirs[far], tfar[far], hits[far], ref,
                             context=f"{isa}, {threads} threads: far rays")
        agreement.check_occluded(org[far], dirs[far], tfar[far], occ[far], ref,
                                 context=f"{isa}, {threads} threads: far rays")
        assert (hits["prim"][far] >= 0).sum() >= 10  # aimed through the cube: some hit


def test_a_far_origin_does_not_pad_the_boxes_of_near_rays():
    """Work, not time: triangle tests of the mixed batch stay those of its near rays traced
    alone plus its far rays traced alone (one far origin at 1e6 had made every near ray test
    ~30x as many triangles)."""
    v, t = _small_triangles()
    org, dirs, tfar = _batch()
    scene = dacrt.Scene(v, t)

    def tri_tests(sel):
        harness.intersect(scene, org[sel], dirs[sel], tfar[sel], threads=1)
        return scene.last_stats["tri_tests"]

    near_alone = tri_tests(slice(0, 4000))
    far_alone = sum(tri_tests(slice(4000 + 20 * k, 4020 + 20 * k)) for k in range(6))
    mixed = tri_tests(slice(None))
    assert mixed <= 1.05 * (near_alone + far_alone), (mixed, near_alone, far_alone)
    # and the near rays' own count did not grow with their box padding
    one_far = np.r_[0:4000, 4040]  # the near rays and one ray from 1e6
    assert tri_tests(one_far) <= 1.05 * near_alone + tri_tests(slice(4040, 4041)), near_alone


def test_rays_from_far_away_test_the_triangles_near_their_path():
    """Rays from 10^4 away test a few times the triangles the same segments started next to
    the scene test (their boxes padded by ~0.02, the rounding of such origins, against
    triangles of ~0.01): the fast box test's slack grows with the distance along the ray
    (2^-10 of it, ~10 here), so such rays had reached every triangle near their path."""
    v, t = _small_triangles()
    rng = np.random.default_rng(8)
    org, dirs, tfar = _rays(rng, 3000, 1e4)
    near_org = (org.astype(np.float64) + dirs * (1e4 - 3.0)).astype(np.float32)  # same lines
    scene = dacrt.Scene(v, t)
    harness.intersect(scene, near_org, dirs, tfar, threads=1)
    near = scene.last_stats["tri_tests"]
    harness.intersect(scene, org, dirs, tfar, threads=1)
    far = scene.last_stats["tri_tests"]
    assert far <= 3 * near, (far, near)  # 2.1x; the fast test had made it 114x
