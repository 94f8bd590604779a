"""The worker pool every native pass runs on (native/cpp/parallel.cpp): results identical to
one thread when a kept top splits small batches across threads, many calls in a row, calls
from several Python threads at once (the pool is busy: fresh threads), and a forked child,
which inherits the pool's memory but none of its threads."""

import multiprocessing
import threading

import dacrt
import numpy as np

from . import harness
from .cases import build_case

CASE = ("torus", 5, 6, "bounce", "finite", 20000, 5)


def _trace(scene, case, threads, seed=0):
    hits = harness.intersect(scene, case.org, case.dirs, case.tfar, threads=threads, shuffle_seed=seed)
    occ = harness.occluded(scene, case.org, case.dirs, case.tfar, threads=threads, shuffle_seed=seed + 1)
    return hits, occ


def _same(a, b):
    return (np.array_equal(a[0].view(np.uint32), b[0].view(np.uint32)) and np.array_equal(a[1], b[1]))


def _kept_scene(case):
    scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy(), keep_top=True)
    big = build_case("torus", 5, 6, "bounce", "finite", 70000, 9)   # >= 64K rays set the kept top
    harness.intersect(scene, big.org, big.dirs, big.tfar, threads=2)
    return scene


def test_kept_top_small_batches_split_across_threads_identically():
    case = build_case(*CASE)
    one = _trace(dacrt.Scene(case.vertices.copy(), case.triangles.copy()), case, 1)
    assert (one[0]["prim"] >= 0).any() and one[1].any() and not one[1].all()
    scene = _kept_scene(case)
    two = _trace(scene, case, 2)
    assert scene.last_stats["threads"] == 2, scene.last_stats
    assert _same(one, two)


def test_many_calls_in_a_row():
    case = build_case("cube", 3, 6, "axis", "mixed", 3000, 3)
    scene = _kept_scene(case)
    first = _trace(scene, case, 2)
    for i in range(200):
        assert _same(first, _trace(scene, case, 2, seed=i))


def test_concurrent_python_threads():
    case = build_case(*CASE)
    want = _trace(dacrt.Scene(case.vertices.copy(), case.triangles.copy()), case, 1)
    scene = _kept_scene(case)
    got, errors = [], []

    def work(i):
        try:
            for j in range(5):
                got.append(_trace(scene, case, 2, seed=10 * i + j))
        except Exception as e:   # reported below: a thread's exception would otherwise vanish
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a tracing thread hung"
    assert not errors, errors
    assert len(got) == 20 and all(_same(want, g) for g in got)


def _child(conn):
    case = build_case(*CASE)
    scene = _kept_scene(case)
    hits, occ = _trace(scene, case, 2)
    conn.send((hits["prim"].copy(), occ.copy(), scene.last_stats["threads"]))


def test_forked_child_traces_with_threads():
    case = build_case(*CASE)
    parent = _trace(_kept_scene(case), case, 2)     # the parent's pool exists before the fork
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_child, args=(send,))
    p.start()
    ready = recv.poll(120)
    answer = recv.recv() if ready else None     # before join: the child blocks on a full pipe
    p.join(timeout=30)
    if p.is_alive():
        p.kill()
    assert ready, "the forked child hung tracing with 2 threads"
    prim, occ, threads = answer
    assert threads == 2
    assert np.array_equal(prim, parent[0]["prim"]) and np.array_equal(occ, parent[1])


_MANY_THREADS = r"""
import os, sys, numpy as np, dacrt
def os_threads():
    return int(open("/proc/self/status").read().split("Threads:")[1].split()[0])
rng = np.random.default_rng(0)
v = rng.uniform(-1, 1, (300, 3)).astype(np.float32)
t = np.arange(300).reshape(100, 3)
o = rng.uniform(-2, 2, (20000, 3)).astype(np.float32)
d = rng.normal(size=(20000, 3)).astype(np.float32)
scene = dacrt.Scene(v, t, chunk_rays=16)  # 1,250 chunks: work for 1,000 threads
one = scene.intersect(dacrt.make_rays(o, d), threads=1)
before = os_threads()
many = scene.intersect(dacrt.make_rays(o, d), threads=1000)
print(before, os_threads(), scene.last_stats["threads"], int(many.tobytes() == one.tobytes()))
"""


def test_thread_counts_are_capped_at_the_hardware_threads():
    """threads=1000 used to start ~1,000 workers that stayed parked for the life of the process;
    a call now uses at most the machine's hardware threads (results never depend on the count).
    In a fresh process, so the count of OS threads is this call's alone."""
    import os
    import subprocess
    import sys
    out = subprocess.run([sys.executable, "-c", _MANY_THREADS], capture_output=True, text=True,
                         timeout=300, env=dict(os.environ))
    assert out.returncode == 0, out.stderr
    before, after, used, same = map(int, out.stdout.split())
    hw = max(os.cpu_count() or 1, dacrt._core.hardware_threads())
    assert same == 1, "threads=1000 changed the hits"
    assert 1 <= used <= hw, f"the call used {used} threads on a machine of {hw}"
    assert after - before <= hw - 1, f"{after - before} new OS threads for a call on {hw} hardware threads"


def _thread_cpu_seconds():
    """{thread id: CPU seconds} of this process's threads (Linux /proc), or None elsewhere."""
    import os
    try:
        tids = os.listdir("/proc/self/task")
    except OSError:
        return None
    out = {}
    for tid in tids:
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[tid] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    return out


def test_the_thread_limit_keeps_kernels_and_traces_on_that_many_threads():
    """dacrt.thread_limit(1) (Blender's Threads: Fixed 1, for a whole frame): shading kernels
    and traces given no thread count run on the calling thread alone, with the same results;
    only the tracer had honoured the setting, the kernels ran on every core."""
    import pytest
    if dacrt._core.hardware_threads() < 2 or _thread_cpu_seconds() is None:
        pytest.skip("needs two cores and Linux /proc to see which threads ran")
    keys = np.arange(4_000_000, dtype=np.uint32).reshape(2, -1)
    case = build_case(*CASE)
    scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy())
    free = (dacrt.shading.uniform2(keys, 1, 2), _trace(scene, case, threads=0))
    me = str(threading.get_native_id())
    with dacrt.thread_limit(1):
        assert dacrt._core.thread_limit() == 1
        before = _thread_cpu_seconds()
        for _ in range(10):
            limited = (dacrt.shading.uniform2(keys, 1, 2), _trace(scene, case, threads=0))
        after = _thread_cpu_seconds()
    assert dacrt._core.thread_limit() == 0
    others = sum(after[t] - before.get(t, 0.0) for t in after if t != me)
    mine = after[me] - before[me]
    # /proc counts CPU time in 10 ms ticks: work for tens of them even on a fast core
    assert mine > 0.1 and others < 0.1 * mine, (mine, others)
    assert all(np.array_equal(a, b) for a, b in zip(free[0], limited[0])) and _same(free[1], limited[1])


def test_the_thread_limit_belongs_to_the_thread_that_sets_it():
    """Two renders in one process (the viewport's worker and an F12 render) each hold their own
    limit: a process-wide one, entered by one and left by the other in between, had left the
    process capped at the first one's count after both were done."""
    entered, left = threading.Event(), threading.Event()
    seen = {}

    def viewport():
        with dacrt.thread_limit(1):
            entered.set()
            left.wait(30)
            seen['worker'] = dacrt._core.thread_limit()
        seen['worker after'] = dacrt._core.thread_limit()

    t = threading.Thread(target=viewport)
    with dacrt.thread_limit(2):
        t.start()
        assert entered.wait(30)
        seen['main'] = dacrt._core.thread_limit()
        left.set()
        t.join(30)
        seen['main after the worker left'] = dacrt._core.thread_limit()
    seen['main after'] = dacrt._core.thread_limit()
    assert seen == {'worker': 1, 'worker after': 0, 'main': 2, 'main after the worker left': 2, 'main after': 0}
