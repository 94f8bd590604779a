"""Bad input through the public API, exhaustively: NaN, +inf and -inf in every coordinate of a
vertex (first, middle, last; float32 and float64) and in every field component of a ray (first,
middle, last record), wrong dtypes, shapes and memory layouts, repeated and out-of-range ids,
bad skip arrays. Each must raise ValueError whose message names the problem (the field and the
index), leave the rays untouched, and leave the process healthy; random byte garbage as rays
either raises ValueError or gives the reference's answer for the rays it describes."""

import re
from pathlib import Path

import dacrt
import numpy as np
import pytest

from ..native import agreement, reference, scenes

V, T = scenes.icosphere(1)
BAD = {"nan": np.nan, "+inf": np.inf, "-inf": -np.inf}


def good_rays(n=40, seed=0):
    rng = np.random.default_rng(seed)
    return dacrt.make_rays(rng.uniform(-0.3, 0.3, (n, 3)), rng.normal(size=(n, 3)))


def expect_error(pattern, fn, *args, **kw):
    with pytest.raises(ValueError) as info:
        fn(*args, **kw)
    msg = str(info.value)
    assert re.search(pattern, msg, re.I), f"message {msg!r} does not match /{pattern}/"
    return msg


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("value", list(BAD))
def test_non_finite_vertex_coordinates(dtype, value):
    for row in (0, len(V) // 2, len(V) - 1):
        for axis in range(3):
            v = V.astype(dtype)
            v[row, axis] = BAD[value]
            expect_error(rf"vertices\[{row}\].*(finite|nan|inf)", dacrt.Scene, v, T)
    big = V.astype(np.float64)
    big[3, 1] = 1e39  # finite in float64, not in float32
    expect_error(r"vertices\[3\].*(float32|large|finite)", dacrt.Scene, big, T)


@pytest.mark.parametrize("query", ["intersect", "occluded"])
@pytest.mark.parametrize("value", list(BAD))
def test_non_finite_ray_fields(query, value):
    scene = dacrt.Scene(V, T)
    for k in (0, 17, 39):
        for field, comp in [("org", 0), ("org", 1), ("org", 2), ("dir", 0), ("dir", 1),
                            ("dir", 2), ("tfar", None)]:
            if field == "tfar" and value == "+inf":
                continue  # tfar = +inf is the unbounded ray, valid
            rays = good_rays()
            if comp is None:
                rays[field][k] = BAD[value]
            else:
                rays[field][k, comp] = BAD[value]
            before = rays.tobytes()
            expect_error(rf"rays\[{k}\]\.{field}", getattr(scene, query), rays)
            assert rays.tobytes() == before, f"{field}[{k}] = {value}: rays modified"


@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_ids_and_directions(query):
    scene = dacrt.Scene(V, T)
    cases = [
        (lambda r: r["id"].__setitem__(5, r["id"][9]), r"rays\[(5|9)\]\.id.*repeat"),
        (lambda r: r["id"].__setitem__(39, 40), r"rays\[39\]\.id.*range"),
        (lambda r: r["id"].__setitem__(0, 2**32 - 1), r"rays\[0\]\.id.*range"),
        (lambda r: r["id"].__setitem__(slice(None), 0), r"\.id.*repeat"),
        (lambda r: r["dir"].__setitem__(12, 0.0), r"rays\[12\]\.dir.*zero"),
        (lambda r: r["dir"].__setitem__(12, -0.0), r"rays\[12\]\.dir.*zero"),
        (lambda r: r["tfar"].__setitem__(3, -1e-45), r"rays\[3\]\.tfar.*negative"),
        (lambda r: r["tfar"].__setitem__(3, -0.5), r"rays\[3\]\.tfar.*negative"),
    ]
    for edit, pattern in cases:
        rays = good_rays()
        edit(rays)
        before = rays.tobytes()
        expect_error(pattern, getattr(scene, query), rays)
        assert rays.tobytes() == before


def test_wrong_dtypes_shapes_and_layouts():
    scene = dacrt.Scene(V, T)
    r = good_rays(32)
    for bad, pattern in [
            (r.view(np.float32).reshape(32, 8), "dtype|ray"),
            (r.view(np.uint8), "dtype|ray"),
            (r.reshape(4, 8), "1-d|shape"),
            (r[::2], "contiguous"),
            (np.asfortranarray(r.reshape(4, 8)), "1-d|shape|contiguous"),
            (r.astype(RAY_BE := dacrt.RAY_DTYPE.newbyteorder(">")), "dtype"),
            (np.zeros(32, [("org", "<f8", (3,)), ("dir", "<f8", (3,)), ("tfar", "<f8"),
                           ("id", "<u8")]), "dtype")]:
        for query in (scene.intersect, scene.occluded):
            expect_error(pattern, query, bad)
    ro = good_rays(8)
    ro.setflags(write=False)
    expect_error("writeable", scene.intersect, ro)
    for v, t, pattern in [
            (V[:, :2], T, r"vertices.*shape"), (V.ravel(), T, r"vertices.*shape"),
            (V[None], T, r"vertices.*shape"), (V.astype(np.int32), T, r"vertices.*float"),
            (V.astype(np.complex64), T, r"vertices.*float"),
            (V.astype(object), T, r"vertices.*float"),
            (V, T[:, :2], r"triangles.*shape"), (V, T.astype(np.float32), r"triangles.*integer"),
            (V, T.astype(bool), r"triangles.*integer"), (V, T - 1, r"triangles\[\d+\].*negative"),
            (V, T + len(V) - T.min(), r"triangles\[0\].*vert")]:
        expect_error(pattern, dacrt.Scene, v, t)
    for bad_skip, pattern in [(np.zeros(31, np.int32), "skip"), (np.zeros(32), "skip"),
                              (np.zeros((32, 1), np.int32), "skip")]:
        expect_error(pattern, scene.intersect, good_rays(32), skip=bad_skip)
    for threads, pattern in [(-1, "thread"), (1.5, "thread"), ("2", "thread"), (True, "thread")]:
        expect_error(pattern, scene.intersect, good_rays(8), threads=threads)


def test_non_contiguous_inputs_are_copied_not_rejected():
    """Vertices and triangles are copied by the Scene, so any layout is fine."""
    vs = np.repeat(V, 2, axis=1)[:, ::2]  # strided views of the same values
    ts = np.repeat(T, 2, axis=1)[:, ::2]
    assert not vs.flags.c_contiguous and not ts.flags.c_contiguous
    a = dacrt.Scene(vs, ts).intersect(good_rays())
    b = dacrt.Scene(V, T).intersect(good_rays())
    assert np.array_equal(a, b)


def test_random_garbage_rays_never_crash():
    """Random bytes as ray records: a ValueError naming a field, or (when the bytes happen to
    form valid rays) answers that agree with the reference."""
    rng = np.random.default_rng(7)
    scene = dacrt.Scene(V, T)
    accepted = 0
    for trial in range(300):
        n = int(rng.integers(1, 50))
        raw = rng.integers(0, 256, n * 32, dtype=np.uint8)
        rays = raw.view(dacrt.RAY_DTYPE).copy()
        if trial % 3:  # make most fields plausible so validation goes deeper
            rays["id"] = rng.permutation(n)
            f = rays["org"].view(np.uint32)
            f &= np.uint32(0x3FFFFFFF)  # exponents below 1: finite
            if trial % 3 == 2:
                rays["dir"].view(np.uint32)[...] &= np.uint32(0xBFFFFFFF)
                rays["tfar"] = np.abs(rays["tfar"])
        before = rays.copy()
        try:
            hits = scene.intersect(rays)
        except ValueError as e:
            assert re.search(r"rays\[\d+\]\.(org|dir|tfar|id)", str(e)), str(e)
            assert rays.tobytes() == before.tobytes()
            continue
        accepted += 1
        b = before[np.argsort(before["id"])]
        ref = reference.trace(V, T, b["org"], b["dir"], b["tfar"])
        agreement.check_hits(V, T, b["org"], b["dir"], b["tfar"], hits, ref,
                             context=f"garbage trial {trial}")
    assert accepted > 20


# every mutation script ends by stopping its writer thread and saying it survived
_STOP_WRITER = """finally:
    stop = True
    th.join()
print("done")
"""

_REWRITE_TRIANGLES = r"""
import threading, numpy as np, dacrt
M = 500_000
V = np.random.default_rng(0).uniform(-1, 1, (3 * M, 3)).astype(np.float32)
T = np.arange(3 * M, dtype=np.uint32).reshape(M, 3)  # passed to the native layer uncopied
stop = False
def writer():
    k = 0
    while not stop:
        r = M - 1 - k % 1000
        T[r, 0] = 0xF0000000  # far outside the vertex array
        T[r, 0] = 3 * r
        k += 1
th = threading.Thread(target=writer)
th.start()
try:
    for i in range(8):
        try:
            dacrt.Scene(V, T, spatial_order=bool(i % 2))
        except ValueError:
            pass
""" + _STOP_WRITER

_REWRITE_RAY_IDS = r"""
import threading, numpy as np, dacrt
rng = np.random.default_rng(0)
M = 20_000
c = rng.uniform(-1, 1, (M, 1, 3))
s = dacrt.Scene((c + rng.normal(scale=0.02, size=(M, 3, 3))).reshape(-1, 3).astype(np.float32),
                np.arange(3 * M).reshape(M, 3))
n = 300_000
o = rng.uniform(-0.2, 0.2, (n, 3)).astype(np.float32)
d = rng.normal(size=(n, 3)).astype(np.float32)
rays = dacrt.make_rays(o, d)
ids = rays["id"]  # a view into the records the tracer reads
stop = False
def writer():
    while not stop:
        ids[::997] = 0x7FFFFFF0
        ids[::997] = np.arange(0, n, 997)
th = threading.Thread(target=writer)
th.start()
try:
    for i in range(8):
        rays[:] = dacrt.make_rays(o, d)
        try:
            (s.intersect if i % 2 == 0 else s.occluded)(rays, threads=2, skip=np.full(n, -1))
        except ValueError:
            pass
""" + _STOP_WRITER


# The shading kernels' index arrays (path columns, film columns, the triangles of hits), each
# rewritten while kernels read it: the values written name no column, film column or triangle.
_REWRITE_SHADING_INDICES = r"""
import threading, numpy as np, dacrt
from addon.lights import lamp_records, make_lamp
from tests.integrator.scenes import light, translation
rng = np.random.default_rng(0)
M, n = 2_000, 400_000
V = rng.uniform(-1, 1, (3 * M, 3)).astype(np.float32)
T = np.arange(3 * M, dtype=np.int32).reshape(M, 3)
geo, area = dacrt.shading.triangle_table(V, T, 8.0)
hits = np.zeros(n, dacrt.HIT_DTYPE)
hits["t"], hits["prim"], hits["u"], hits["v"] = 1.0, rng.integers(0, M, n), 0.25, 0.25
hit = np.ones(n, bool)
O = rng.uniform(-1, 1, (3, n)).astype(np.float32)
D = rng.normal(size=(3, n)).astype(np.float32)
D /= np.linalg.norm(D, axis=0)
dist = np.ones(n, np.float32)
thr = np.ones((3, n), np.float32)
pdf = np.ones(n, np.float32)
idx = np.arange(n, dtype=np.int64)
pid = np.arange(n, dtype=np.int64)
L = np.zeros((3, n), np.float32)
emission = np.ones((3, M), np.float32)
albedo = np.full((3, M), 0.5, np.float32)
every = np.ones(M, bool)
prob = np.full(M, 1.0 / M, np.float32)
records = lamp_records([make_lamp(light("POINT", 10.0, translation(0, 0, 2), radius=0.1))])
env = dacrt.lamps.environment_map(np.ones((8, 16, 3), np.float32))
prims = hits["prim"]  # a view into the records the kernels read
stop = False
def writer():
    while not stop:
        for a in (idx, pid):
            a[::997] = -(1 << 40)
            a[1::997] = 1 << 40
            a[::997] = np.arange(0, n, 997)
            a[1::997] = np.arange(1, n, 997)
        prims[::997] = 0x7FFFFFF0
        prims[1::997] = -7
        prims[::997] = 3
        prims[1::997] = 4
th = threading.Thread(target=writer)
th.start()
calls = [
    lambda: dacrt.shading.surface(geo, None, hits, idx, D),
    lambda: dacrt.shading.take_columns(idx, O, thr, pid, pdf),
    lambda: dacrt.shading.shadow_rays(O, D, dist, None, idx),
    lambda: dacrt.shading.gather_emission(hits, hit, emission, every, prob, area, geo, O, D, thr, pdf, pid, L),
    lambda: dacrt.shading.accumulate_masked(L, pid, thr, hit),
    lambda: dacrt.shading.continue_paths(hits, hit, every, albedo, thr, None, surface=(geo, None, D),
                                         take=(pid, pdf)),
    lambda: dacrt.lamps.lamp_gather(records, [0], O, D, dist, hit, pid, L, thr=thr, pdf_bsdf=pdf,
                                    lamp_prob=np.ones(1, np.float32)),
    lambda: env.gather(0.5, D, hit, thr, pdf, pid, L),
]
try:
    for i in range(48):
        try:
            calls[i % len(calls)]()
        except ValueError:
            pass
""" + _STOP_WRITER


@pytest.mark.parametrize("script", ["triangles", "ray ids", "shading indices"])
def test_inputs_rewritten_by_another_thread_during_a_call_never_crash(script):
    """The GIL is released while a Scene is built and while rays are traced, and the inputs are
    the caller's arrays: another Python thread may rewrite them after they were checked. That
    gives wrong answers, never memory errors (an index read again after the check used to
    read or write far outside the arrays: a segfault). In a child process, so a crash fails
    the test instead of ending the run."""
    import subprocess
    import sys
    code = {"triangles": _REWRITE_TRIANGLES, "ray ids": _REWRITE_RAY_IDS,
            "shading indices": _REWRITE_SHADING_INDICES}[script]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600,
                         cwd=Path(__file__).resolve().parents[2])
    assert out.returncode == 0 and out.stdout.strip() == "done", \
        f"the child ended with {out.returncode}: {out.stderr[-2000:]}"
