"""The oracle itself: the float64 reference tracer, the scene generators and the OBJ loader are
checked against closed-form cases and an independent linear-solve implementation, so that a
disagreement with dacrt means a tracer bug. (No dacrt needed here.)"""

import dataclasses

import numpy as np
import pytest

from . import reference, scenes
from .rays import make_rays

TRI = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]]))


def trace1(verts, tris, o, d, tfar=np.inf):
    return reference.trace(verts, tris, np.array([o], np.float32), np.array([d], np.float32),
                           np.array([tfar], np.float32))


def test_single_triangle_closed_form():
    r = trace1(*TRI, (0.25, 0.125, 1.0), (0, 0, -1))
    assert (r.prim[0], r.t[0], r.u[0], r.v[0]) == (0, 1.0, 0.25, 0.125)
    # t is measured in units of the direction's length
    assert trace1(*TRI, (0.25, 0.125, 1.0), (0, 0, -2)).t[0] == 0.5
    # from behind: triangles are double-sided
    assert trace1(*TRI, (0.25, 0.125, -3.0), (0, 0, 1)).t[0] == 3.0
    # edges of (0.2, 0.3): x=0 at 0.2, y=0 at 0.3, the hypotenuse at 0.5/sqrt(2)
    assert trace1(*TRI, (0.2, 0.3, 1), (0, 0, -1)).margin[0] == pytest.approx(0.2)
    # measured perpendicular to the ray: a 45-degree ray sees the x=0 edge at 0.2*cos(45)
    assert trace1(*TRI, (0.2 - 1, 0.3, 1), (1, 0, -1)).margin[0] == pytest.approx(0.2 / 2 ** 0.5)
    assert trace1(*TRI, (0.45, 0.45, 1), (0, 0, -1)).margin[0] == pytest.approx(0.1 / 2 ** 0.5)
    assert trace1(*TRI, (0.45, 0.45, 1), (0, 0, -1)).bary_min[0] == pytest.approx(0.1)


def test_interval_semantics():
    hit = trace1(*TRI, (0.2, 0.2, 1), (0, 0, -1), tfar=1.0)
    assert hit.prim[0] == 0 and not hit.occluded[0]  # intersect: (0, tfar]; occluded: (0, tfar)
    assert trace1(*TRI, (0.2, 0.2, 1), (0, 0, -1), tfar=np.float32(1.0001)).occluded[0]
    assert trace1(*TRI, (0.2, 0.2, 1), (0, 0, -1), tfar=0.999).prim[0] == -1
    assert trace1(*TRI, (0.2, 0.2, 1), (0, 0, 1)).prim[0] == -1  # pointing away
    assert trace1(*TRI, (0.2, 0.2, 0), (0, 0, 1)).prim[0] == -1  # t = 0 is excluded
    assert trace1(*TRI, (0.2, 0.2, 1), (0, 0, -1), tfar=0.0).prim[0] == -1
    assert trace1(*TRI, (2.0, 2.0, 1), (0, 0, -1)).prim[0] == -1


def test_ties_second_best_and_degenerates():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1], [1, 0, -1], [0, 1, -1],
                  [0, 0, 0], [1, 1, 0], [2, 2, 0]], np.float32)
    t = np.array([[6, 7, 8], [3, 4, 5], [0, 1, 2], [0, 1, 2]])  # degenerate, back, front, dup
    r = trace1(v, t, (0.2, 0.2, 1), (0, 0, -1))
    assert (r.prim[0], r.t[0], r.t2[0]) == (2, 1.0, 1.0)  # exact tie: lowest index wins
    r = trace1(v, t[:3], (0.2, 0.2, 1), (0, 0, -1))
    assert (r.prim[0], r.t2[0]) == (2, 2.0)
    # the degenerate triangle lies on the ray's path and is never hit
    r = trace1(v, t[:1], (1.0, 1.0, 1), (0, 0, -1))
    assert r.prim[0] == -1 and not r.occluded[0]


def _solve_reference(verts, tris, o, d, tfar):
    """Slow, independent closest hit: solve o + t d = v0 + u e1 + v e2 per pair."""
    best = (np.inf, -1, 0.0, 0.0)
    for k, (a, b, c) in enumerate(verts[tris].astype(np.float64)):
        if np.linalg.norm(np.cross(b - a, c - a)) == 0:
            continue
        m = np.column_stack([-d, b - a, c - a])
        if abs(np.linalg.det(m)) < 1e-300:
            continue
        tt, u, v = np.linalg.solve(m, o - a)
        if u >= 0 and v >= 0 and u + v <= 1 and 0 < tt <= tfar and tt < best[0]:
            best = (tt, k, u, v)
    return best


@pytest.mark.parametrize("kind", ["soup", "sphere", "cube_rotated", "torus", "nested"])
def test_vectorised_reference_matches_linear_solve(kind):
    v, t = scenes.make_scene(kind, seed=3, size=1)
    o, d, tf = make_rays("random", "mixed", v, t, 60, seed=5)
    r = reference.trace(v, t, o, d, tf)
    for i in range(len(o)):
        tt, k, uu, vv = _solve_reference(v, t, o[i].astype(float), d[i].astype(float), tf[i])
        if k != r.prim[i]:  # only at genuine ties / edges, which the margins must flag
            assert abs(tt - r.t[i]) <= 1e-9 * max(1, tt) or min(r.margin[i], 1) < 1e-9, i
            continue
        if k >= 0:
            assert r.t[i] == pytest.approx(tt, rel=1e-10)
            assert (r.u[i], r.v[i]) == pytest.approx((uu, vv), abs=1e-9)


def test_chunking_does_not_change_the_answer(monkeypatch):
    v, t = scenes.make_scene("nested", seed=1, size=2)
    o, d, tf = make_rays("bounce", "mixed", v, t, 300, seed=2)
    whole = reference.trace(v, t, o, d, tf)
    monkeypatch.setattr(reference, "PAIRS_PER_CHUNK", 7 * len(t))
    parts = reference.trace(v, t, o, d, tf)
    for f in ("t", "prim", "u", "v", "t2", "robust_t", "occluded", "occluded_robust"):
        np.testing.assert_array_equal(getattr(whole, f), getattr(parts, f), err_msg=f)


def test_skipping_far_runs_of_triangles_does_not_change_the_answer(monkeypatch):
    """Large meshes skip runs of triangles far from each ray (reference._Blocks); forced onto a
    14,400-triangle torus (rays from inside its tube, half aimed at vertices, some with a finite
    tfar, and as many from outside at its vertices) and a mesh with non-finite vertices, every
    field must equal the dense cull's."""
    rng = np.random.default_rng(3)
    v, t = scenes.torus(1.0, 0.35, 120, 60)
    n = 400
    a = rng.uniform(0, 2 * np.pi, n)
    o = (np.stack([np.cos(a), np.sin(a), np.zeros(n)], 1) + rng.uniform(-0.2, 0.2, (n, 3))).astype(np.float32)
    d = np.where(rng.uniform(size=(n, 1)) < 0.5, v[rng.integers(0, len(v), n)] - o,
                 rng.normal(size=(n, 3))).astype(np.float32)
    outside = rng.uniform(-2, 2, (n, 3)).astype(np.float32)
    o, d = np.concatenate([o, outside]), np.concatenate([d, v[rng.integers(0, len(v), n)] - outside])
    n *= 2
    tf = np.where(rng.uniform(size=n) < 0.7, np.inf, rng.uniform(0, 1, n)).astype(np.float32)
    broken = v.astype(np.float32).copy()
    broken[5], broken[9, 1] = np.inf, np.nan
    for verts in (v, broken):
        dense = reference.trace(verts, t, o, d, tf)
        monkeypatch.setattr(reference, "BLOCKED_TRIANGLES", 1)
        blocked = reference.trace(verts, t, o, d, tf)
        monkeypatch.undo()
        for f in dataclasses.fields(dense):
            np.testing.assert_array_equal(getattr(dense, f.name), getattr(blocked, f.name), err_msg=f.name)
    # and the runs do skip triangles here, or the comparison would prove nothing
    mesh = reference.Mesh.from_arrays(v, t)
    centre = mesh.v0 + (mesh.e1 + mesh.e2) / 3.0
    radius = np.max(np.linalg.norm(np.stack([mesh.v0, mesh.v0 + mesh.e1, mesh.v0 + mesh.e2], 1)
                                   - centre[:, None], axis=2), axis=1)
    dhat = (d / np.linalg.norm(d, axis=1)[:, None]).astype(np.float64)
    near = reference._Blocks(centre, radius).near(o[:1].astype(np.float64), dhat[:1], np.array([1e-4]))
    assert 0 < len(near) < len(t) / 2


def _edge_use(tris):
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return counts


@pytest.mark.parametrize("build", [lambda: scenes.icosphere(3), lambda: scenes.subdivided_cube(5),
                                   lambda: scenes.torus(1, 0.3, 20, 10),
                                   scenes.generated_100k],
                         ids=["icosphere", "cube", "torus", "generated_100k"])
def test_closed_meshes_are_closed(build):
    v, t = build()
    assert np.all(_edge_use(t) == 2), "every edge must be shared by exactly two triangles"
    assert len(np.unique(t)) == len(v)


def test_generated_100k_size_and_scene_kinds_are_deterministic():
    assert len(scenes.generated_100k()[1]) == 100_000
    for kind in scenes.SCENE_KINDS:
        a, b = scenes.make_scene(kind, 11, 3), scenes.make_scene(kind, 11, 3)
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]), kind
        assert a[0].dtype == np.float32 and a[1].dtype == np.int32 and len(a[1]) > 0, kind
        assert a[1].min() >= 0 and a[1].max() < len(a[0]), kind


def test_obj_loader(tmp_path):
    p = tmp_path / "quad.obj"
    p.write_text("# comment\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
                 "f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4 -2 -1\n")
    v, t = scenes.load_obj(p)
    assert v.shape == (4, 3) and v.dtype == np.float32
    np.testing.assert_array_equal(t, [[0, 1, 2], [0, 2, 3], [0, 2, 3]])


def test_dragon_obj_from_shared():
    if not scenes.DRAGON_OBJ.exists():
        pytest.skip(f"{scenes.DRAGON_OBJ} is absent (../shared beside the repository)")
    v, t = scenes.load_obj(scenes.DRAGON_OBJ)
    assert t.shape == (100_000, 3) and v.shape == (50_000, 3)
    assert t.min() == 0 and t.max() == len(v) - 1
