"""Awkward rays against the float64 reference, in every configuration: direction components
that are zero, -0.0, denormal or above 2^126 (and directions that are entirely denormal),
origins exactly on
box planes, on triangles, on edges and vertices, grazing rays in and near a face's plane, and
rays starting inside closed meshes."""

import numpy as np

from ..native import reference, scenes
from .checks import against_reference

FLT_MAX = float(np.finfo(np.float32).max)
ODD = np.array([0.0, -0.0, 1e-45, -1e-45, 1e-40, -3e-39, 1.1754944e-38, -1.1754944e-38])


def _scene():
    """A cube with faces on axis planes plus a sphere inside it: flat boxes and curved ones."""
    cv, ct = scenes.subdivided_cube(6, 1.0)
    sv, st = scenes.icosphere(2, 0.6)
    return np.concatenate([cv, sv]), np.concatenate([ct, st + len(cv)])


def test_zero_negative_zero_and_denormal_components(monkeypatch):
    rng = np.random.default_rng(1)
    v, t = _scene()
    n = 6000
    o = rng.uniform(-1.6, 1.6, (n, 3))
    d = rng.normal(size=(n, 3))
    odd = rng.uniform(size=(n, 3)) < 0.45
    d = np.where(odd, rng.choice(ODD, (n, 3)), d)
    tiny = np.all(np.abs(d) < 1e-30, axis=1)
    d[tiny, rng.integers(0, 3, tiny.sum())] = rng.choice([1.0, -1.0], tiny.sum())
    assert (np.signbit(d) & (d == 0)).any() and ((np.abs(d) > 0) & (np.abs(d) < 1.2e-38)).any()
    hits, ref = against_reference(monkeypatch, v, t, o, d, label="odd direction components")
    assert (hits["prim"] >= 0).sum() > n // 3


def test_entirely_denormal_directions(monkeypatch):
    """|dir| ~ 1e-40: t = distance / |dir| fits a float only for targets closer than ~1e-2
    (2^128 * 1e-40); farther hits cannot be represented and are misses, never t = inf."""
    rng = np.random.default_rng(2)
    v, t = scenes.icosphere(3, 1.0)
    n = 4000
    d = rng.normal(size=(n, 3)) * 1e-40
    o = rng.uniform(-0.5, 0.5, (n, 3))
    # half of them start just inside the sphere, 1e-3 .. 1e-2 from it
    near = rng.uniform(size=n) < 0.5
    u = d[near] / np.linalg.norm(d[near], axis=1, keepdims=True)
    o[near] = u * (1 - rng.uniform(1e-3, 1e-2, (near.sum(), 1)))
    o32, d32 = o.astype(np.float32), d.astype(np.float32)
    ref = reference.trace(v, t, o32, d32, np.inf)
    fits = ref.t < FLT_MAX
    assert fits.sum() > n // 4 and (~fits).sum() > n // 4
    hits, _ = against_reference(monkeypatch, v, t, o32[fits], d32[fits], label="denormal dirs")
    assert (hits["prim"] >= 0).all()
    far, _ = against_reference(monkeypatch, v, t, o32[~fits], d32[~fits],
                               label="denormal dirs, t beyond float", ref=_strict_miss(ref, ~fits))
    assert (far["prim"] == -1).all() and np.isposinf(far["t"]).all()


def _walls(xs, scale=1.0):
    """Square walls x = const (two triangles each) covering y, z in [-1, 1] * scale."""
    v = [[x, y * scale, z * scale] for x in xs for y, z in ((-1, -1), (1, -1), (-1, 1), (1, 1))]
    t = [[4 * k, 4 * k + 1, 4 * k + 2] for k in range(len(xs))] + \
        [[4 * k + 1, 4 * k + 3, 4 * k + 2] for k in range(len(xs))]
    return np.array(v, np.float32), np.array(t, np.int32)


def test_far_hits_of_denormal_direction_components(monkeypatch):
    """Rays whose only nonzero direction component is denormal reach walls at t ~ 1e35: the box
    test's reciprocal of such a component is +-inf (AVX2 reads a denormal as 0; 1/d overflows
    below ~2.9e-39), which put the wall's box at infinity and culled them (a farther wall or a
    miss instead). With a finite tfar, and with tfar = inf in a batch whose other rays make the
    far wall's node come first."""
    rng = np.random.default_rng(7)
    v, t = _walls([1e-3, 1e-2])
    n = 400
    o = np.c_[np.zeros(n), rng.uniform(-0.9, 0.9, (n, 2))]
    d = np.zeros((n, 3))
    d[:, 0] = rng.choice([5e-39, 2e-39, 1e-39, 1.1e-38, 3e-40], n)  # t = 1e-3 / d <= 3.4e36
    tfar = np.where(rng.uniform(size=n) < 0.5, 1e37, np.inf)
    others = 2 * n  # travelling -x from beyond the far wall
    o = np.r_[o, np.c_[np.ones(others), rng.uniform(-0.5, 0.5, (others, 2))]]
    d = np.r_[d, np.c_[-np.ones(others), rng.uniform(-0.05, 0.05, (others, 2))]]
    tfar = np.r_[tfar, np.full(others, np.inf)]
    hits, _ = against_reference(monkeypatch, v, t, o, d, tfar, label="denormal direction components")
    assert np.isin(hits["prim"][:n], [0, 2]).all(), "a denormal-direction ray missed the near wall"


def test_hits_of_huge_direction_components(monkeypatch):
    """Direction components above 2^126: AVX2's approximate reciprocal flushes its tiny result
    to 0, which made the slab [0, 0] and culled every ray entering the box later (here through
    its y slab at t = 2.5)."""
    rng = np.random.default_rng(8)
    # the wall y = 1e38, x in [1e38, 2.2e38], z in [-1e38, 1e38]
    v = np.array([[1e38, 1e38, -1e38], [2.2e38, 1e38, -1e38], [1e38, 1e38, 1e38], [2.2e38, 1e38, 1e38]],
                 np.float32)
    t = np.array([[0, 1, 2], [1, 3, 2]], np.int32)
    n = 500
    o = np.tile([-5e37, 0.0, 0.0], (n, 1))
    d = np.c_[rng.uniform(8.6e37, 1e38, n), np.full(n, 4e37), rng.uniform(-2e37, 2e37, n)]
    hits, _ = against_reference(monkeypatch, v, t, o, d, label="huge direction components")
    assert (hits["prim"] >= 0).all()


def _strict_miss(ref, sel):
    """The reference restricted to sel, with hits beyond the float range turned into misses."""
    out = {k: getattr(ref, k)[sel].copy() for k in ref.__dataclass_fields__}
    out["t"][:] = np.inf
    out["prim"][:] = -1
    out["robust_t"][:] = np.inf
    for k in ("occluded", "occluded_robust", "occluded_possible"):
        out[k][:] = False
    return type(ref)(**out)


def test_origins_on_box_planes(monkeypatch):
    """Origins whose coordinates equal vertex coordinates (every node box is bounded by such
    planes), with zero direction components along those axes: rays running inside a slab
    plane of many node boxes."""
    rng = np.random.default_rng(3)
    v, t = _scene()
    n = 6000
    o = rng.uniform(-1.5, 1.5, (n, 3))
    snap = rng.uniform(size=(n, 3)) < 0.5
    src = v[rng.integers(0, len(v), (n, 3)), np.arange(3)[None, :].repeat(n, 0)]
    o = np.where(snap, src, o)
    d = rng.normal(size=(n, 3))
    flat = snap & (rng.uniform(size=(n, 3)) < 0.6)
    d = np.where(flat, rng.choice([0.0, -0.0], (n, 3)), d)
    dead = np.all(d == 0, axis=1)
    d[dead] = rng.normal(size=(dead.sum(), 3))
    against_reference(monkeypatch, v, t, o, d, label="origins on box planes")


def test_origins_on_triangles_edges_and_vertices(monkeypatch):
    """Origins exactly on the cube's faces (coordinate +-1 is exact), on its grid edges and
    vertices, and as close as float32 gets to points of the sphere's triangles."""
    rng = np.random.default_rng(4)
    v, t = _scene()
    n = 6000
    g = np.linspace(-1, 1, 7)
    o = rng.uniform(-1, 1, (n, 3))
    axis = rng.integers(0, 3, n)
    o[np.arange(n), axis] = rng.choice([-1.0, 1.0], n)  # on a face
    on_edge = rng.uniform(size=n) < 0.3
    ax2 = (axis + 1) % 3
    o[on_edge, ax2[on_edge]] = rng.choice(g, on_edge.sum())  # on a grid line of that face
    on_vertex = rng.uniform(size=n) < 0.15
    ax3 = (axis + 2) % 3
    o[on_vertex, ax2[on_vertex]] = rng.choice(g, on_vertex.sum())
    o[on_vertex, ax3[on_vertex]] = rng.choice(g, on_vertex.sum())
    sphere = rng.uniform(size=n) < 0.25
    k = rng.integers(len(scenes.subdivided_cube(6)[1]), len(t), sphere.sum())
    a, b = rng.uniform(size=(2, sphere.sum(), 1))
    f = a + b > 1
    a, b = np.where(f, 1 - a, a), np.where(f, 1 - b, b)
    vv = v.astype(np.float64)
    o[sphere] = vv[t[k, 0]] + a * (vv[t[k, 1]] - vv[t[k, 0]]) + b * (vv[t[k, 2]] - vv[t[k, 0]])
    d = rng.normal(size=(n, 3))
    against_reference(monkeypatch, v, t, o, d, label="origins on surfaces")


def test_grazing_rays(monkeypatch):
    """Rays inside a face's plane (exactly: zero component, origin on the plane) and nearly
    so (1e-7 .. 1e-3 rad), including along the grid lines where two faces' triangles meet."""
    rng = np.random.default_rng(5)
    v, t = _scene()
    n = 6000
    o = rng.uniform(-1.5, 1.5, (n, 3))
    axis = rng.integers(0, 3, n)
    o[np.arange(n), axis] = rng.choice([-1.0, 1.0, -0.5, 0.0], n)
    d = rng.normal(size=(n, 3))
    tilt = rng.choice([0.0, 0.0, 1e-7, -1e-5, 1e-3], n)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[np.arange(n), axis] = tilt
    line = rng.uniform(size=n) < 0.3  # also on a grid line of the face, moving along it
    ax2 = (axis + 1) % 3
    o[line, ax2[line]] = rng.choice(np.linspace(-1, 1, 7), line.sum())
    d[line, ax2[line]] = 0.0
    dead = np.all(d == 0, axis=1)
    d[dead, (axis[dead] + 2) % 3] = 1.0
    against_reference(monkeypatch, v, t, o, d, label="grazing")


def test_rays_from_inside_closed_meshes(monkeypatch):
    rng = np.random.default_rng(6)
    for name, (v, t), inside in [
            ("icosphere", scenes.icosphere(3, 1.0), lambda m: rng.uniform(-0.55, 0.55, (m, 3))),
            ("torus", scenes.torus(1.0, 0.35, 48, 24), lambda m: _in_torus(rng, m)),
            ("cube", scenes.subdivided_cube(8, 1.0), lambda m: rng.uniform(-0.999, 0.999, (m, 3)))]:
        o = inside(4000)
        d = rng.normal(size=o.shape) * 10 ** rng.uniform(-3, 3, (len(o), 1))
        hits, _ = against_reference(monkeypatch, v, t, o, d, label=f"inside {name}")
        assert (hits["prim"] >= 0).all(), f"{name}: a ray from inside escaped"


def _in_torus(rng, m):
    a = rng.uniform(0, 2 * np.pi, m)
    r = 1.0 + rng.uniform(-0.25, 0.25, m)
    return np.stack([r * np.cos(a), r * np.sin(a), rng.uniform(-0.25, 0.25, m)], 1)
