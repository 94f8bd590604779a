"""The optional per-ray skip triangle: a ray ignores exactly the triangle named for its id, in
both queries, and nothing else changes. Checked against the float64 reference run on the mesh
with that triangle removed (made degenerate), for every ISA."""

import dacrt
import numpy as np
import pytest

from . import agreement, reference, scenes

ISAS = dacrt.supported_isas()


def _rays_from_inside(rng, n):
    # Inside a closed sphere every ray hits; skipping the first hit must reveal the next one
    # (the far side), never a miss and never the skipped triangle.
    org = rng.uniform(-0.3, 0.3, (n, 3))
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)   # t is then a distance
    return org.astype(np.float32), dirs.astype(np.float32)


@pytest.mark.parametrize("isa", ISAS)
def test_skip_matches_reference_without_that_triangle(isa, monkeypatch):
    monkeypatch.setenv("DACRT_ISA", isa)
    rng = np.random.default_rng(5)
    # Two nested spheres: the first hit from inside the inner one is on the inner sphere.
    v1, t1 = scenes.icosphere(2, 1.0)
    v2, t2 = scenes.icosphere(2, 2.0)
    vertices = np.concatenate([v1, v2]).astype(np.float32)
    triangles = np.concatenate([t1, t2 + len(v1)])
    scene = dacrt.Scene(vertices, triangles)
    org, dirs = _rays_from_inside(rng, 120)
    tfar = np.full(len(org), np.inf, np.float32)

    plain = scene.intersect(dacrt.make_rays(org, dirs), threads=1)
    assert (plain["prim"] >= 0).all()
    skip = plain["prim"].astype(np.int32)
    skip[::4] = -1                      # some rays skip nothing
    skip[1::4] = len(triangles) - 1 - skip[1::4]   # some skip an unrelated triangle

    hits = scene.intersect(dacrt.make_rays(org, dirs), threads=2, skip=skip)
    occ = scene.occluded(dacrt.make_rays(org, dirs, tfar=3.0), threads=2, skip=skip)
    assert not np.any(hits["prim"][skip >= 0] == skip[skip >= 0]), "a ray hit its skipped triangle"

    for k in np.unique(skip):
        sel = np.flatnonzero(skip == k)
        tri = triangles.copy()
        if k >= 0:
            tri[k] = tri[k][0]           # the reference mesh without triangle k
        ref = reference.trace(vertices, tri, org[sel], dirs[sel], tfar[sel])
        agreement.check_hits(vertices, tri, org[sel], dirs[sel], tfar[sel], hits[sel], ref,
                             context=f"skip={k}")
        # every ray is inside the outer sphere (radius 2), so something within t < 3 blocks it
        assert occ[sel].all(), f"skip={k}: occluded() lost rays {sel[~occ[sel]]}"
    # Rays whose skip was their first hit now hit something farther away.
    own = np.flatnonzero(skip == plain["prim"])
    assert len(own) and (hits["t"][own] > plain["t"][own]).all()


def test_skip_is_validated():
    scene = dacrt.Scene(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]]))
    rays = dacrt.make_rays(np.zeros((2, 3)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="skip"):
        scene.intersect(rays, skip=np.zeros(3, np.int32))
    with pytest.raises(ValueError, match="skip"):
        scene.occluded(rays, skip=np.zeros(2, np.float32))


@pytest.mark.parametrize("isa", ISAS)
def test_skip_checked_traces_as_the_checked_call(isa, monkeypatch):
    """skip_checked (the renderer's batches: skips from the tracer's own hits) passes an int32
    skip without the range pass: the same answers, bit for bit, as the checked call; an entry
    outside the triangle indices then skips nothing (the tracer only compares against it),
    while calls without the flag, and other dtypes with it, are still refused."""
    monkeypatch.setenv("DACRT_ISA", isa)
    rng = np.random.default_rng(11)
    v1, t1 = scenes.icosphere(2, 1.0)
    v2, t2 = scenes.icosphere(2, 2.0)
    vertices = np.concatenate([v1, v2]).astype(np.float32)
    triangles = np.concatenate([t1, t2 + len(v1)])
    m = len(triangles)
    scene = dacrt.Scene(vertices, triangles)
    org, dirs = _rays_from_inside(rng, 200)
    plain = scene.intersect(dacrt.make_rays(org, dirs), threads=1)
    skip = plain["prim"].astype(np.int32)
    skip[::5] = -1
    skip[2::5] = m - 1 - skip[2::5]
    for query, tfar in (("intersect", None), ("occluded", 1.5)):
        def run(s, **kw):
            rays = dacrt.make_rays(org, dirs) if tfar is None else dacrt.make_rays(org, dirs, tfar=tfar)
            out = getattr(scene, query)(rays, threads=2, skip=s, **kw)
            return out, rays
        want, want_rays = run(skip)
        got, got_rays = run(skip, skip_checked=True)
        assert got.tobytes() == want.tobytes() and got_rays.tobytes() == want_rays.tobytes(), query
        # out of range with the flag: as -1 (what the check would have refused)
        bad = skip.copy()
        bad[1::5] = np.array([m, -2, 2**31 - 1, -2**31], np.int32)[np.arange(len(bad[1::5])) % 4]
        none = skip.copy()
        none[1::5] = -1
        got, _ = run(bad, skip_checked=True)
        assert got.tobytes() == run(none)[0].tobytes(), query
        with pytest.raises(ValueError, match=r"skip\[1\] = .* is not a triangle index"):
            run(bad)
        wide = bad.astype(np.int64)
        wide[1] = 2**32                  # int64 is still checked: its int32 cast would wrap to 0
        with pytest.raises(ValueError, match=r"skip\[1\] = 4294967296 is not a triangle index"):
            run(wide, skip_checked=True)
