"""Bad input gets a ValueError naming the problem, raised before any ray is touched: every
validation rule of the native API, for Scene construction, Scene properties, intersect() and
occluded()."""

import re

import dacrt
import numpy as np
import pytest

from .rays import RAY_DTYPE, to_rays

V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
T = np.array([[0, 1, 2], [0, 1, 3]], np.int32)


def raises(pattern, fn, *args, **kw):
    with pytest.raises(ValueError) as info:
        fn(*args, **kw)
    msg = str(info.value)
    assert re.search(pattern, msg, re.I), f"message {msg!r} does not mention /{pattern}/"


SCENE_ERRORS = {
    "vertices (V,2)": (np.zeros((4, 2), np.float32), T, "vert"),
    "vertices 1-D": (np.zeros(12, np.float32), T, "vert"),
    "vertices (V,3,1)": (np.zeros((4, 3, 1), np.float32), T, "vert"),
    "vertices integer": (V.astype(np.int32), T, "vert"),
    "vertices NaN": (np.where(np.arange(12).reshape(4, 3) == 5, np.nan, V).astype(np.float32),
                     T, "finite|nan"),
    "vertices inf": (np.where(np.arange(12).reshape(4, 3) == 0, np.inf, V).astype(np.float32),
                     T, "finite|inf"),
    "vertices -inf float64": (np.where(np.arange(12).reshape(4, 3) == 11, -np.inf, V), T,
                              "finite|inf"),
    "triangles (M,2)": (V, T[:, :2], "triang"),
    "triangles (M,4)": (V, np.zeros((2, 4), np.int32), "triang"),
    "triangles 1-D": (V, T.ravel(), "triang"),
    "triangles float": (V, T.astype(np.float32), "triang|integer"),
    "triangle index -1": (V, np.array([[0, 1, 2], [0, -1, 3]], np.int32), "triang.*vert|index|range|bound"),
    "triangle index == V": (V, np.array([[0, 1, 4]], np.int64), "triang.*vert|index|range|bound"),
    "triangle index huge uint32": (V, np.array([[0, 1, 2**32 - 1]], np.uint32),
                                   "triang.*vert|index|range|bound"),
}


@pytest.mark.parametrize("name", list(SCENE_ERRORS))
def test_scene_rejects(name):
    v, t, pattern = SCENE_ERRORS[name]
    raises(pattern, dacrt.Scene, v, t)


def test_scene_rejects_bad_settings():
    raises("partition", dacrt.Scene, V, T, partition="octree")
    raises("leaf", dacrt.Scene, V, T, leaf_size=0)
    raises("leaf", dacrt.Scene, V, T, leaf_size=-3)
    raises("leaf_rays", dacrt.Scene, V, T, leaf_rays=0)
    raises("leaf_rays", dacrt.Scene, V, T, leaf_rays=2.5)
    scene = dacrt.Scene(V, T)
    with pytest.raises(ValueError, match="(?i)partition"):
        scene.partition = "bvh"
    with pytest.raises(ValueError, match="(?i)leaf"):
        scene.leaf_size = 0
    with pytest.raises(ValueError, match="leaf_rays"):
        scene.leaf_rays = -1
    assert (scene.partition, scene.leaf_size, scene.leaf_rays) == ("adaptive", None, 32)  # unchanged


def good_rays(n=16):
    rng = np.random.default_rng(1)
    return to_rays(rng.normal(size=(n, 3)) + [0.2, 0.2, 3], rng.normal(size=(n, 3)) * 0.1
                   + [0, 0, -1], np.inf)


def _set(field, index, value):
    def edit(r):
        r[field][index] = value
        return r
    return edit


RAY_ERRORS = {
    "NaN in org": (_set("org", (3, 1), np.nan), "finite|nan|org"),
    "inf in org": (_set("org", (0, 0), np.inf), "finite|inf|org"),
    "-inf in org": (_set("org", (15, 2), -np.inf), "finite|inf|org"),
    "NaN in dir": (_set("dir", (7, 2), np.nan), "finite|nan|dir"),
    "inf in dir": (_set("dir", (2, 0), np.inf), "finite|inf|dir"),
    "all-zero dir": (_set("dir", 5, 0.0), "zero|dir"),
    "all -0.0 dir": (_set("dir", 5, -0.0), "zero|dir"),
    "NaN tfar": (_set("tfar", 4, np.nan), "tfar"),
    "negative tfar": (_set("tfar", 9, -1.0), "tfar"),
    "-inf tfar": (_set("tfar", 9, -np.inf), "tfar"),
    "id == N": (_set("id", 3, 16), r"\bid"),
    "id huge": (_set("id", 0, 2**32 - 1), r"\bid"),
    "repeated id": (_set("id", 3, 4), r"\bid|duplicate|repeat"),
}


@pytest.mark.parametrize("query", ["intersect", "occluded"])
@pytest.mark.parametrize("name", list(RAY_ERRORS))
def test_rays_rejected_and_untouched(query, name):
    edit, pattern = RAY_ERRORS[name]
    scene = dacrt.Scene(V, T)
    rays = edit(good_rays())
    before = rays.copy()
    raises(pattern, getattr(scene, query), rays)
    assert rays.tobytes() == before.tobytes(), "the rays were modified by a failed call"


def _wrong_arrays():
    r = good_rays(16)
    swapped = np.dtype([("dir", "<f4", (3,)), ("org", "<f4", (3,)), ("tfar", "<f4"),
                        ("id", "<u4")])
    big_endian = RAY_DTYPE.newbyteorder(">")
    padded = np.dtype({"names": ["org", "dir", "tfar", "id"],
                       "formats": [("<f4", (3,)), ("<f4", (3,)), "<f4", "<u4"],
                       "offsets": [0, 12, 24, 28], "itemsize": 36})
    return {
        "float32 (N,8) array": (np.zeros((16, 8), np.float32), "dtype|ray"),
        "fields in another order": (np.zeros(16, swapped), "dtype|ray"),
        "big-endian fields": (r.astype(big_endian), "dtype|ray"),
        "36-byte records": (np.zeros(16, padded), "dtype|ray"),
        "2-D ray array": (r.reshape(4, 4), "1-d|dimension|shape|ndim"),
        "non-contiguous": (r[::2], "contiguous"),
        "a list": (list(r), "dtype|ray|array"),
    }


@pytest.mark.parametrize("query", ["intersect", "occluded"])
@pytest.mark.parametrize("name", list(_wrong_arrays()))
def test_wrong_ray_arrays_rejected(query, name):
    arr, pattern = _wrong_arrays()[name]
    before = arr.tobytes() if isinstance(arr, np.ndarray) else None  # raw bytes, padding too
    with pytest.raises((ValueError, TypeError)) as info:
        getattr(dacrt.Scene(V, T), query)(arr)
    if isinstance(arr, np.ndarray):  # a list cannot be reordered in place: TypeError is fine
        assert info.type is ValueError, f"{name}: expected ValueError, got {info.value!r}"
        assert re.search(pattern, str(info.value), re.I), \
            f"message {str(info.value)!r} does not mention /{pattern}/"
        assert arr.tobytes() == before, "the array was modified by a failed call"


@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_negative_threads_rejected(query):
    rays = good_rays()
    before = rays.copy()
    raises("thread", getattr(dacrt.Scene(V, T), query), rays, threads=-1)
    assert rays.tobytes() == before.tobytes()


def test_valid_edge_values_accepted():
    """Not errors: tfar = +inf and 0, directions with -0.0 components, huge finite values."""
    r = good_rays(8)
    r["tfar"][:4] = [np.inf, 0.0, 1e30, np.finfo(np.float32).max]
    r["dir"][5] = [-0.0, 0.0, -1.0]
    r["org"][6] = [-0.0, 1e30, -1e30]
    scene = dacrt.Scene(V, T)
    hits = scene.intersect(r.copy())
    assert hits.shape == (8,) and hits["prim"][1] == -1  # tfar = 0 never hits
    assert scene.occluded(r.copy()).shape == (8,)


BIG = 200_000   # validated on several threads (the serial path is for batches under 64K rays)
BIG_ERRORS = {
    "NaN in org (two bad rays)": ([("org", (170_000, 0), np.nan), ("org", (120_000, 1), np.nan)],
                                  r"rays\[120000\]\.org"),
    "id == N late": ([("id", 190_000, BIG)], r"rays\[190000\]\.id"),
    "repeated id far apart": ([("id", 150_000, 10)], r"rays\[150000\]\.id = 10 is repeated"),
    "repeated id, first ray": ([("id", 0, BIG - 1)], r"rays\[199999\]\.id = 199999 is repeated"),
}


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("query", ["intersect", "occluded"])
@pytest.mark.parametrize("name", list(BIG_ERRORS))
def test_big_batch_names_first_bad_ray(query, name, threads):
    """A big batch is checked on several threads; the message still names the first bad ray
    (as the serial scan would) and the rays are untouched."""
    edits, pattern = BIG_ERRORS[name]
    rays = good_rays(BIG)
    for field, index, value in edits:
        rays[field][index] = value
    before = rays.copy()
    raises(pattern, getattr(dacrt.Scene(V, T), query), rays, threads=threads)
    assert rays.tobytes() == before.tobytes(), "the rays were modified by a failed call"


@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_big_batch_outputs_do_not_depend_on_threads(query):
    """The outputs the parallel check initialises (misses, unoccluded) are the serial ones."""
    rays = good_rays(BIG)
    scene = dacrt.Scene(V, T)
    out = [getattr(scene, query)(rays.copy(), threads=t) for t in (1, 2)]
    assert out[0].tobytes() == out[1].tobytes()
    if query == "intersect":
        assert 0 < np.count_nonzero(out[0]["prim"] >= 0) < BIG   # some rays hit, some miss
        assert np.all(np.isinf(out[0]["t"][out[0]["prim"] < 0]))


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_big_batch_ids_out_of_order_accepted(query, threads):
    """Ids in order (ray k has id k) are validated in one pass; any other permutation takes
    the marking check. Both must give every ray its own answer: ids swapped at the end, in
    the middle of a thread's range and across the ranges, and fully shuffled."""
    rays = good_rays(BIG)
    scene = dacrt.Scene(V, T)
    want = getattr(scene, query)(rays.copy(), threads=threads)
    for swaps in ([(BIG - 2, BIG - 1)], [(1000, 60_000)], [(5, BIG - 5), (99_999, 100_000)], None):
        order = np.arange(BIG)
        if swaps is None:
            order = np.random.default_rng(4).permutation(BIG)
        else:
            for a, b in swaps:
                order[[a, b]] = order[[b, a]]
        got = getattr(scene, query)(rays[order], threads=threads)   # ray k keeps its id order[k]
        assert got.tobytes() == want.tobytes(), f"swaps {swaps}: answers not the in-order ones by id"


@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_skip_outside_the_triangle_indices_rejected(query):
    """skip must be -1 or a triangle index 0..M-1, checked before the int32 conversion (which
    turned int64 2**32 into 0 and uint64 2**64-1 into -1)."""
    scene = dacrt.Scene(V, T)  # 2 triangles
    for value, dtype in [(2, np.int32), (7, np.int64), (-2, np.int32), (-7, np.int64),
                         (2**32, np.int64), (2**33 + 1, np.int64), (2**64 - 1, np.uint64),
                         (2**31, np.uint32)]:
        skip = np.array([-1 if np.issubdtype(dtype, np.signedinteger) else 0] * 15 + [value], dtype)
        rays = good_rays()
        before = rays.copy()
        raises(rf"skip\[15\] = {value} .*triangle", getattr(scene, query), rays, skip=skip)
        assert rays.tobytes() == before.tobytes()
    want = getattr(scene, query)(good_rays(), skip=np.array([1] * 16, np.int32))
    for dtype in (np.int64, np.uint64, np.int8, np.uint16):  # in range: any integer type works
        got = getattr(scene, query)(good_rays(), skip=np.array([1] * 16, dtype))
        assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("name", ["triangle_table", "face_normals"])
def test_shading_tables_reject_indices_that_would_wrap(name):
    from dacrt import shading
    args = {"triangle_table": lambda t: (V, t, 4.0), "face_normals": lambda t: (V.astype(np.float64), t)}[name]
    for t in [np.array([[0, 2**32 + 1, 2]], np.int64), np.array([[0, 1, 2**64 - 1]], np.uint64),
              np.array([[0, 1, -1]], np.int64), np.array([[0, 1, 4]], np.int32)]:
        raises(r"triangles\[0\] refers to vertex", getattr(shading, name), *args(t))
    ok = getattr(shading, name)(*args(np.array([[0, 1, 3]], np.uint64)))
    assert np.array_equal(ok[0], getattr(shading, name)(*args(np.array([[0, 1, 3]], np.int32)))[0])


SETTING_LIMITS = {  # setting: (too large, the largest accepted)
    "leaf_size": (2**31, 2**31 - 1),
    "leaf_rays": (2**31, 2**31 - 1),
    "chunk_rays": (2**64, 2**64 - 1),
    "sah_ratio": (1e39, 3.4e38),
}


@pytest.mark.parametrize("name", list(SETTING_LIMITS))
def test_settings_beyond_the_native_range_rejected_when_set(name):
    """Values the native layer cannot hold fail where they are set, naming the setting and the
    value (they used to pass and fail at trace time with pybind11's dump of every argument)."""
    big, largest = SETTING_LIMITS[name]
    raises(rf"{name}.*{re.escape(repr(big))}", dacrt.Scene, V, T, **{name: big})
    scene = dacrt.Scene(V, T)
    with pytest.raises(ValueError, match=name):
        setattr(scene, name, big)
    want = scene.intersect(good_rays())
    setattr(scene, name, largest)  # accepted, and traces the same hits
    assert scene.intersect(good_rays()).tobytes() == want.tobytes()


@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_thread_counts_beyond_int32_rejected(query):
    scene = dacrt.Scene(V, T)
    for threads in (2**31, 2**63, 2**64):
        raises(rf"threads.*{threads}", getattr(scene, query), good_rays(), threads=threads)
    want = getattr(scene, query)(good_rays(), threads=1)
    assert getattr(scene, query)(good_rays(), threads=2**31 - 1).tobytes() == want.tobytes()


def test_make_rays_names_a_bad_tfar_or_an_overflowing_coordinate():
    o, d = np.zeros((4, 3)), np.ones((4, 3))
    raises(r"tfar.*\(4,\)", dacrt.make_rays, o, d, np.ones(3))
    raises(r"tfar.*\(4,\)", dacrt.make_rays, o, d, np.ones((4, 1)))
    big = o.copy()
    big[2, 1] = 1e300  # finite in float64, inf in float32
    raises(r"org\[2\].*float32", dacrt.make_rays, big, d)
    raises(r"dir\[2\].*float32", dacrt.make_rays, o, big + 1)
    r = dacrt.make_rays(o, d, np.full(4, 1e300))  # a tfar beyond float32 is the unbounded ray
    assert np.isposinf(r["tfar"]).all()
    assert dacrt.make_rays(o.astype(np.float32), d, [1, 2, 3, 4])["tfar"].tolist() == [1, 2, 3, 4]


def test_make_rays_refuses_complex_input():
    """numpy would keep the real part with only a ComplexWarning; the next error then blamed a
    'zero vector' direction for what was (0 + 1j, ...)."""
    o, d = np.zeros((2, 3)), np.ones((2, 3))
    raises(r"org.*real", dacrt.make_rays, o + 0j, d)
    raises(r"dir.*real", dacrt.make_rays, o, d * 1j)
    raises(r"tfar.*real", dacrt.make_rays, o, d, np.ones(2) + 1j)


@pytest.mark.parametrize("tfar", [-1e-7, -1e-30, -1e-45])
def test_a_small_negative_tfar_is_named_with_its_digits(tfar):
    """std::to_string's fixed six decimals had shown each of these as 'negative (-0.000000)'."""
    rays = dacrt.make_rays(np.zeros((1, 3)), [[0, 0, 1]])
    rays["tfar"] = tfar
    scene = dacrt.Scene(V, T)
    raises(r"tfar is negative \(-[1-9]", scene.intersect, rays)
