"""The set-up's fixed cost on every render (sceneprep.recentred): a scene whose origin already
keeps float32 precise is told so without sorting the sampled triangles for the weighted median
of their step / size (_imprecision's argsort, a fifth of the check on the 100K-triangle dragon);
the decision is the sort's, exactly (_median_above against _imprecision)."""

from dataclasses import replace

import numpy as np
import pytest

from addon import sceneprep
from addon.sceneprep import _imprecision, _median_above, recentred

from .scenes import ALL_VIS, cornell_box, geometry, icosphere, material
from ..stress.test_far_scenes import room


@pytest.fixture
def argsorts(monkeypatch):
    """The lengths of the arrays np.argsort sorts during the test."""
    sizes = []
    real = np.argsort

    def recording(a, *args, **kw):
        sizes.append(int(np.size(a)))
        return real(a, *args, **kw)
    monkeypatch.setattr(np, 'argsort', recording)
    return sizes


def _sphere_scene(offset):
    """A fine icosphere (5120 triangles) around offset, seen by the Cornell box's camera."""
    v, t = icosphere(1.0, subdiv=4, center=offset)
    return replace(cornell_box(), geometry=geometry([(v, t, 1, ALL_VIS)]))


@pytest.mark.parametrize('make', [cornell_box, room, lambda: _sphere_scene((0.0, 0.0, 0.0))],
                         ids=['cornell', 'room', 'sphere'])
def test_a_precise_scene_is_not_sorted(make, argsorts):
    scene = make()
    out, origin, warning = recentred(scene)
    assert out is scene and not origin.any() and warning is None
    assert argsorts == [], argsorts


def test_a_far_scene_still_weighs_its_origins(argsorts):
    """Where the origin is not good enough (the room 1e5 away with an outlier across the
    origin), the medians are sorted and the camera's surroundings chosen, as before."""
    out, origin, warning = recentred(room(1e5, outlier=True))
    assert argsorts and origin.any() and warning is None


def _boxes(rng, n, spread):
    lo = rng.normal(0.0, spread, (n, 3)) + rng.choice([0.0, 1e3, 1e5], n)[:, None]
    side = np.exp(rng.normal(-3.0, 2.0, n))
    hi = lo + side[:, None] * rng.uniform(0.2, 1.0, (n, 3))
    side = sceneprep._largest(hi - lo)
    weight = rng.uniform(0.0, 1.0, n) ** 4
    return lo, hi, side, weight


@pytest.mark.parametrize('seed', range(6))
def test_median_above_is_the_sorted_median_compared(seed):
    rng = np.random.default_rng(seed)
    n = [1, 2, 7, 300, 5000, 16384][seed]
    boxes = _boxes(rng, n, 10.0)
    origin = np.zeros(3) if seed % 2 else rng.normal(0.0, 1e3, 3)
    median = _imprecision(boxes, origin)[0]
    lo, hi, side, weight = boxes
    big = sceneprep._largest(np.maximum(np.abs(lo - origin), np.abs(hi - origin)))
    ratios = float(sceneprep.OFFSET_ULPS) * np.spacing(big.astype(np.float32)).astype(np.float64) / side
    # every ratio as the limit (ties at the median itself), its neighbours and far ones
    limits = np.concatenate([ratios, np.nextafter(ratios, 0), np.nextafter(ratios, np.inf), [0.0, 1e300]])
    for limit in limits[:3000]:
        assert _median_above(boxes, origin, limit) == (median > limit), (limit, median)


def test_median_above_at_an_exact_half_and_without_weight():
    """Two boxes of equal weight: the cumulative sum meets half at the first, the median is
    its ratio; all weights zero (underflowed): the smallest ratio, as the sort gives."""
    lo = np.array([[0.0, 0, 0], [0.0, 0, 0]])
    for weight in (np.array([1.0, 1.0]), np.array([0.0, 0.0]), np.array([1.0, 3.0]), np.array([3.0, 1.0])):
        hi = np.array([[1.0, 1, 1], [1e-3, 1e-3, 1e-3]])
        boxes = (lo, hi, sceneprep._largest(hi - lo), weight)
        median = _imprecision(boxes, np.zeros(3))[0]
        for limit in (0.0, median, np.nextafter(median, 0), np.nextafter(median, 1), 1.0):
            assert _median_above(boxes, np.zeros(3), limit) == (median > limit), (weight, limit)


def _huge_scenes():
    """Scenes the huge-surface check says something about and scenes it does not: planes of
    half-size 10 .. 1e6 under a box (at the origin, 1e5 away), a far mountain, a box seen from
    afar, the Cornell box, a fine sphere, and a vertex at infinity in a plane's corner."""
    from ..stress.test_huge_ground_plane_warning import scene
    out = [scene(h) for h in (10.0, 1e3, 1e4, 1e5, 1e6)]
    out += [scene(1e6, offset=1e5), scene(10.0, mountain_at=1e5), scene(1e6, eye=(0.0, -1e5, 2e4)),
            cornell_box(width=8, height=6, samples=1), _sphere_scene((0.0, 0.0, 0.0))]
    broken = scene(1e5)
    v = np.array(broken.geometry.vertices)
    v[0] = np.inf
    out.append(replace(broken, geometry=replace(broken.geometry, vertices=v)))
    return out


@pytest.mark.parametrize('k', range(11))
def test_huge_surfaces_says_the_same_from_recentred_sample(k):
    """huge_surfaces with what recentred found of its sample: the same warnings as on its own."""
    from addon.surfacetables import Triangles
    data = _huge_scenes()[k]
    found = {}
    moved, origin, _ = recentred(data, found)
    geo = Triangles(moved.geometry, []).geo
    alone = sceneprep.huge_surfaces(moved, origin, geo)
    assert sceneprep.huge_surfaces(moved, origin, geo, found) == alone
    if k == 3:
        assert len(alone) == 1     # (the 1e5 plane under the box is said)
    if origin.any():
        assert found == {}         # (moved vertices: nothing of the sample reused)


def _sized_in_huge_surfaces(monkeypatch):
    """The lengths of the samples sceneprep._largest sizes while huge_surfaces runs (filled as
    the Integrator is set up)."""
    from addon import integrator
    sized, inside = [], []
    real_largest, real_huge = sceneprep._largest, integrator.huge_surfaces

    def counting(a):
        if inside:
            sized.append(len(a))
        return real_largest(a)

    def huge(*args, **kw):
        inside.append(True)
        try:
            return real_huge(*args, **kw)
        finally:
            inside.pop()
    monkeypatch.setattr(sceneprep, '_largest', counting)
    monkeypatch.setattr(integrator, 'huge_surfaces', huge)
    return sized


def test_an_ordinary_render_samples_the_triangles_once(monkeypatch):
    """The Integrator's set-up of a scene around the origin: huge_surfaces takes recentred's
    smallest face instead of gathering and sizing the same sample again."""
    from addon import integrator
    sized = _sized_in_huge_surfaces(monkeypatch)
    integ = integrator.Integrator(_sphere_scene((0.0, 0.0, 0.0)))
    assert not [m for m in integ.messages if 'off the surface' in m[1]]
    assert sized == [], sized


def test_flags_no_material_has_are_not_gathered_per_triangle(monkeypatch):
    """The set-up's per-triangle flags (emissive, transparent, refracting, translucent) where
    no material has the flag: no gather over the triangles, the same all-False arrays."""
    from addon import integrator
    gathered = []
    real = integrator.Integrator._per_triangle

    def per_triangle(self, flags):
        out = real(self, flags)
        gathered.append(bool(np.asarray(flags).any()))
        return out
    monkeypatch.setattr(integrator.Integrator, '_per_triangle', per_triangle)
    plain = replace(_sphere_scene((0.0, 0.0, 0.0)), materials=[material('default'), material('grey', (0.5,) * 3)])
    integ = integrator.Integrator(plain)
    assert gathered and not any(gathered), gathered
    assert not integ._tri_emissive.any() and not integ._tri_transparent.any()
    assert integ._tri_emissive.dtype == bool and len(integ._tri_emissive) == len(integ.tri)
    # and where one has it, its triangles (the Cornell box's ceiling light)
    box = integrator.Integrator(cornell_box())
    want = box.mats.emissive[box.tri.material] & (box.tri.area > 0)
    assert want.any() and np.array_equal(box._tri_emissive, want)


def _pebble_on_a_field():
    """A fine pebble (an icosphere 2 cm across, 5120 faces ~1 mm) on a floor of half-size 10 at
    the origin, seen by the Cornell box's camera: the floor's step exceeds a hundredth of the
    pebble's faces (past huge_surfaces' smallest-face test, as the dragon on its floor), but not
    of the pebble."""
    v, t = icosphere(0.01, subdiv=4, center=(0.5, 0.5, 0.01))
    h = 10.0
    floor = (np.array([(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)]), np.array([(0, 1, 2), (0, 2, 3)]))
    return replace(cornell_box(), geometry=geometry([(v, t, 1, ALL_VIS), (*floor, 1, ALL_VIS)]))


def test_objects_on_a_far_reaching_face_are_sized_from_recentred_sample(monkeypatch):
    """Past the smallest-face test, huge_surfaces weighs the objects by the boxes of recentred's
    sampled faces, not a second gather and sizing of the same sample (~1 ms of the dragon's
    4-spp set-up), and says nothing here."""
    from addon import integrator
    sized = _sized_in_huge_surfaces(monkeypatch)
    integ = integrator.Integrator(_pebble_on_a_field())
    assert not [m for m in integ.messages if 'off the surface' in m[1]]
    assert sized == [2], sized      # (the two objects' boxes only: the test got past the faces)


@pytest.mark.parametrize('seed', range(5))
def test_group_boxes_are_the_boxes_of_each_groups_rows(seed):
    """_group_boxes against a loop over the groups, on runs (a placement's consecutive
    triangles), shuffled rows, one group, one row, and negative and huge ids."""
    rng = np.random.default_rng(seed)
    n = [1, 5, 300, 4000, 16384][seed]
    groups = np.repeat(rng.integers(-3, 2 ** 40, 1 + n // 50), 50)[:n]
    if seed % 2:
        groups = rng.permutation(groups)
    lo = rng.normal(0.0, 1e3, (n, 3))
    hi = lo + rng.uniform(0.0, 10.0, (n, 3))
    got_lo, got_hi = sceneprep._group_boxes(groups, lo, hi)
    kinds = np.unique(groups)
    want_lo = np.array([lo[groups == k].min(axis=0) for k in kinds])
    want_hi = np.array([hi[groups == k].max(axis=0) for k in kinds])
    np.testing.assert_array_equal(got_lo, want_lo)
    np.testing.assert_array_equal(got_hi, want_hi)


# --- recentred's camera cluster and sample, against the code they replaced (kept here as the
# reference): blockwise distances without a whole (k, 3) difference, reductions with where=
# instead of copies, the sampled rows by np.take, no copies of an all-kept sample

def _reference_cluster(v, eye):
    d = v - eye
    d = np.sqrt(np.einsum('ij,ij->i', d, d))
    d[~np.isfinite(d)] = np.inf
    if not np.isfinite(d).any():
        return None
    positive = d[d > 0]
    reach = float(positive.min()) if len(positive) else 0.0
    for _ in range(64):
        near = d <= sceneprep._GAP * reach
        grown = float(d[near].max())
        if grown <= reach:
            break
        reach = grown
    return near


def _reference_boxes(v, tri, near, eye, found=None):
    idx = np.arange(len(tri)) if near.all() else \
        np.flatnonzero(near[tri[:, 0]] | near[tri[:, 1]] | near[tri[:, 2]])
    idx = idx[::-(-len(idx) // sceneprep._SAMPLE)] if len(idx) > sceneprep._SAMPLE else idx
    t = tri[idx]
    c0, c1, c2 = (np.asarray(v[t[:, k]], np.float64) for k in range(3))
    lo, hi = np.minimum(np.minimum(c0, c1), c2), np.maximum(np.maximum(c0, c1), c2)
    side = sceneprep._largest(hi - lo)
    gap = np.maximum(np.maximum(lo - eye, 0.0), eye - hi)
    dist = np.sqrt(np.einsum('ij,ij->i', gap, gap))
    keep = np.isfinite(side) & np.isfinite(dist) & (side > 0)
    if found is not None and near.all():
        faces = side[np.isfinite(side) & (side > 0)]
        found['smallest_face'] = float(faces.min()) if len(faces) else None
        found['sample'] = (idx, lo, hi, side)
    if not keep.any():
        return None
    side, dist = side[keep], dist[keep]
    return lo[keep], hi[keep], side, (side / np.maximum(dist, side)) ** 2


def _clouds():
    """(vertices float64 (k, 3), eye): random clouds of up to ~3 distance blocks, clusters with
    gaps, magnitudes 1e-30 .. 1e30, NaN and infinite coordinates, a camera on a vertex, on the
    only finite one, and no finite vertex at all."""
    rng = np.random.default_rng(7)
    out = []
    for n, scale in ((1, 1.0), (5, 1e-30), (1000, 1.0), (70000, 1e3), (150000, 1e30), (200003, 1.0)):
        v = rng.normal(0.0, scale, (n, 3)) * np.exp(rng.normal(0.0, 3.0, (n, 1)))
        v[rng.random(n) < 0.05] += rng.normal(0.0, 1e5 * scale, 3)      # a far cluster
        out.append((v, rng.normal(0.0, scale, 3)))
    v = rng.normal(0.0, 1.0, (5000, 3))
    v[rng.integers(0, 5000, 50), rng.integers(0, 3, 50)] = np.nan
    v[rng.integers(0, 5000, 50), rng.integers(0, 3, 50)] = np.inf
    out.append((v, v[17].copy() if np.isfinite(v[17]).all() else np.zeros(3)))     # on a vertex
    out.append((np.array([[1.0, 2, 3], [np.inf, 0, 0], [0, np.nan, 0]]), np.array([1.0, 2, 3])))
    out.append((np.array([[np.inf, 0, 0], [0, np.nan, 0]]), np.zeros(3)))
    out.append((np.zeros((4, 3)), np.zeros(3)))
    return out


@pytest.mark.parametrize('case', range(10))
def test_camera_cluster_and_its_distances_are_the_reference_bits(case):
    v, eye = _clouds()[case]
    with np.errstate(all='ignore'):
        d = v - eye
        got_d = sceneprep._distances(v, eye)
        # its definition, bit for bit (the order of the sum numpy's einsum takes here) ...
        want = np.sqrt((d[:, 0] * d[:, 0] + d[:, 2] * d[:, 2]) + d[:, 1] * d[:, 1])
        assert np.array_equal(got_d.view(np.uint64), want.view(np.uint64))
        # ... and the einsum it replaced, to an ULP of the result (equal on the machine it was
        # written on; another order of the three products may round differently)
        einsum = np.sqrt(np.einsum('ij,ij->i', d, d))
        fin = np.isfinite(einsum)
        assert np.array_equal(np.isfinite(got_d), fin) and np.array_equal(np.isnan(got_d), np.isnan(einsum))
        assert (np.abs(got_d[fin] - einsum[fin]) <= np.spacing(einsum[fin])).all()
        got, ref = sceneprep._camera_cluster(v, eye), _reference_cluster(v, eye)
    assert (got is None) == (ref is None)
    if ref is not None:
        assert np.array_equal(got, ref)


@pytest.mark.parametrize('case', range(8))
def test_near_boxes_are_the_reference_boxes(case):
    """The sample's boxes, sizes, weights and what huge_surfaces reuses: every bit the
    reference's, for all-near and part-near clusters, float32 and float64 vertices, samples
    below and above _SAMPLE, degenerate and non-finite triangles."""
    rng = np.random.default_rng(case)
    n = [3, 100, 20000, 70001][case % 4]
    v = rng.normal(0.0, 10.0, (n, 3))
    if case % 2:
        v = v.astype(np.float32)
    v[:3] = v[0]                                    # a degenerate triangle's corners
    if case >= 4:
        v[rng.integers(0, n, 5)] = np.inf
    tri = rng.integers(0, n, (2 * n, 3)).astype(np.int32)
    eye = rng.normal(0.0, 5.0, 3)
    with np.errstate(all='ignore'):
        for near in (np.ones(n, bool), rng.random(n) < 0.3):
            f_got, f_ref = {}, {}
            got = sceneprep._near_boxes(v, tri, near, eye, f_got)
            ref = _reference_boxes(v, tri, near, eye, f_ref)
            assert (got is None) == (ref is None)
            for a, b in zip(got or (), ref or ()):
                a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
                assert a.dtype == b.dtype and np.array_equal(a.view(np.uint8), b.view(np.uint8))
            assert f_got.keys() == f_ref.keys()
            if f_ref:
                assert f_got['smallest_face'] == f_ref['smallest_face']
                for a, b in zip(f_got['sample'], f_ref['sample']):
                    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
                    assert a.dtype == b.dtype and np.array_equal(a.view(np.uint8), b.view(np.uint8))


class _Watched:
    """A triangle table that records being read (np.asarray calls __array__)."""

    def __init__(self, geo):
        self.geo, self.reads = geo, 0

    def __array__(self, dtype=None, copy=None):
        self.reads += 1
        return self.geo


def test_an_ordinary_scene_bounds_its_steps_from_recentred_box():
    """A scene around the origin whose vertices are all finite: huge_surfaces bounds its steps
    by recentred's box of the vertices instead of reducing the table's nine rows (0.3 ms of the
    dragon's set-up, ~4 ms at 1M triangles); the warnings are the same (above)."""
    from addon.surfacetables import Triangles
    for data in (cornell_box(), _sphere_scene((0.0, 0.0, 0.0)), _pebble_on_a_field()):
        found = {}
        moved, origin, _ = recentred(data, found)
        geo = _Watched(Triangles(moved.geometry, []).geo)
        assert sceneprep.huge_surfaces(moved, origin, geo, found) == []
        assert geo.reads == 0, geo.reads
