"""lights.sphereinside.triangles_within (which triangles a sphere light's radius reaches, for
the inside-a-sphere-spot message) against a float64 brute force: the nearest of a dense grid of
points on each random triangle. Radii 3% under and over that distance must give False and True
(the grid's own error is ~0.5%); so does every Voronoi region (vertex, edge, face) of the
triangle, which random centres all around it reach."""
import numpy as np

from addon.lights.sphereinside import triangles_within


def _brute(c, tri, n=200):
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    m = u + v <= 1
    pts = tri[0] + u[m, None] * (tri[1] - tri[0]) + v[m, None] * (tri[2] - tri[0])
    return np.sqrt(((pts - c) ** 2).sum(1)).min()


def _geo(tris):
    return np.stack([np.concatenate([t[0], t[1] - t[0], t[2] - t[0]]) for t in tris], axis=1).astype(np.float32)


def test_matches_brute_force_distance():
    rng = np.random.default_rng(7)
    for _ in range(150):
        tri = rng.normal(size=(3, 3))
        c = rng.normal(size=3) * 1.5
        d = _brute(c, tri)
        assert not triangles_within(c, 0.97 * d, _geo([tri]))
        assert triangles_within(c, 1.03 * d, _geo([tri]))


def test_any_of_many_and_degenerate_input():
    rng = np.random.default_rng(3)
    far = [rng.normal(size=(3, 3)) + 10.0 for _ in range(50)]
    near = np.array([[0.0, 0.0, 0.05], [1.0, 0.0, 0.05], [0.0, 1.0, 0.05]])
    flat = np.array([[0.0, 0.0, 0.0]] * 3)             # a zero-area triangle at the centre
    assert not triangles_within((0.2, 0.2, 0.0), 0.04, _geo(far + [near]))
    assert triangles_within((0.2, 0.2, 0.0), 0.06, _geo(far + [near]))
    assert triangles_within((0.0, 0.0, 0.01), 0.02, _geo([flat]))
    assert not triangles_within((0.0, 0.0, 0.0), 0.0, _geo([near]))
    assert not triangles_within((0.0, 0.0, 0.0), 1.0, np.zeros((12, 0), np.float32))


def test_many_queries_on_shared_triangles_match_one_by_one():
    """TriangleReach (sorted by x, wide triangles apart) answers as the brute check of each
    triangle alone, for lights all over a field of small triangles and one wide floor."""
    from addon.lights.sphereinside import TriangleReach
    rng = np.random.default_rng(11)
    small = [p + rng.normal(size=(3, 3)) * 0.1 for p in rng.uniform(-5, 5, size=(400, 3))]
    floor = np.array([[-50.0, -50.0, -3.0], [50.0, -50.0, -3.0], [0.0, 60.0, -3.0]])
    tris = small + [floor]
    reach = TriangleReach(_geo(tris))
    # triangles_within(c, r, _geo([t])) is TriangleReach(_geo([t])).within(c, r): each alone,
    # built once rather than per query (80,000 builds had cost 13 s CPU, now 0.8 s)
    alone = [TriangleReach(_geo([t])) for t in tris]
    for _ in range(200):
        c, r = rng.uniform(-6, 6, size=3), rng.uniform(0.01, 1.0)
        assert reach.within(c, r) == any(t.within(c, r) for t in alone)
