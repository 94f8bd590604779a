"""A worker thread that a loaded machine has not scheduled yet holds no call back
(native/cpp/parallel.cpp, dispatch.cpp): its share is run by whichever thread is free first,
so a 2-thread trace returns in about one thread's time however late the second thread is, with
hits bit-identical to one thread's; and the late worker, when it does run, joins no call that
has ended (later calls stay exact).

The late worker is made deterministic with DACRT_TEST_WORKER_DELAY_US, which makes each pool
worker sleep that long after being woken, before it takes any work: a woken thread the
scheduler has not run yet. The tracer's calls run in a subprocess (the variable is read once
per process). Before the fix the caller waited for that worker: every 2-thread call took the
whole delay."""

import json
import os
import subprocess
import sys
import textwrap

DELAY_S = 3.0

SCRIPT = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    import dacrt
    from tests.native import scenes

    rng = np.random.default_rng(5)
    v, t = scenes.random_soup(rng, 20000, spread=1.0, size=0.05)
    def rays(n, seed):
        r = np.random.default_rng(seed)
        org = r.uniform(-1.2, 1.2, (n, 3)).astype(np.float32)
        d = r.normal(size=(n, 3)).astype(np.float32)
        return dacrt.make_rays(org, d)
    # 20K rays on a kept top are 2 chunks (from 1K rays); 70K rays without one are 2 chunks
    # of 35K, and their field check is a 2-thread parallel_for (from 64K rays)
    cases = [("kept", 20000, True), ("own", 70000, False)]
    ref = {}
    for name, n, keep in cases:
        s = dacrt.Scene(v, t, keep_top=keep)
        ref[name] = (s.intersect(rays(n, 1), threads=1), s.occluded(rays(n, 2), threads=1))
    scene = {name: dacrt.Scene(v, t, keep_top=keep) for name, n, keep in cases}
    out = {"times": [], "threads": [], "same": []}
    def round_():
        for name, n, keep in cases:
            r1, r2 = rays(n, 1), rays(n, 2)
            t0 = time.perf_counter()
            h = scene[name].intersect(r1, threads=2)
            out["threads"].append(scene[name].last_stats["threads"])
            o = scene[name].occluded(r2, threads=2)
            out["times"].append(time.perf_counter() - t0)
            out["same"].append(bool(np.array_equal(h.view(np.uint32), ref[name][0].view(np.uint32))
                                    and np.array_equal(o, ref[name][1])))
    round_()
    round_()
    time.sleep(DELAY + 0.5)  # the worker wakes from each call's delay to find it over
    round_()
    print(json.dumps(out))
""")


def test_late_worker_holds_no_call_back_and_hits_stay_exact():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, DACRT_TEST_WORKER_DELAY_US=str(int(DELAY_S * 1e6)))
    env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in sys.path if p])
    proc = subprocess.run([sys.executable, "-c", f"DELAY = {DELAY_S}\n" + SCRIPT], env=env, cwd=root,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert all(out["same"]), f"2-thread hits differ from 1 thread's: {out['same']}"
    assert all(t == 2 for t in out["threads"]), f"calls did not ask for 2 threads: {out['threads']}"
    # each call (an intersect and an occluded) in well under one worker's delay: none waited
    slow = [round(t, 2) for t in out["times"] if t > DELAY_S / 2]
    assert not slow, f"2-thread calls waited for the late worker: {slow} s of {out['times']} (its delay {DELAY_S} s)"


STRESS = textwrap.dedent("""
    import json
    import numpy as np
    import dacrt
    from tests.native import scenes

    rng = np.random.default_rng(6)
    v, t = scenes.random_soup(rng, 5000, spread=1.0, size=0.08)
    def rays(n, seed):
        r = np.random.default_rng(seed)
        org = r.uniform(-1.2, 1.2, (n, 3)).astype(np.float32)
        return dacrt.make_rays(org, r.normal(size=(n, 3)).astype(np.float32))
    sizes = [1100, 2500, 9000]
    src = {n: rays(n, n) for n in sizes}
    ref = {n: dacrt.Scene(v, t).intersect(src[n].copy(), threads=1) for n in sizes}
    s = dacrt.Scene(v, t, keep_top=True)
    bad = []
    for i in range(150):  # calls back to back: a worker woken for one call wakes in a later one
        n = sizes[i % len(sizes)]
        h = s.intersect(src[n].copy(), threads=2)
        if not np.array_equal(h.view(np.uint32), ref[n].view(np.uint32)):
            bad.append(i)
    print(json.dumps(bad))
""")


def test_workers_woken_across_calls_claim_only_their_own_call():
    # worker delays around a call's length: workers that woke for one call meet later ones, and
    # a claim with an earlier call's job would trace the wrong rays (or freed memory)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    for delay_us in (0, 200, 1500):
        env = dict(os.environ, DACRT_TEST_WORKER_DELAY_US=str(delay_us))
        env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in sys.path if p])
        proc = subprocess.run([sys.executable, "-c", STRESS], env=env, cwd=root, capture_output=True, text=True,
                              timeout=120)
        assert proc.returncode == 0, f"delay {delay_us} us: {proc.stderr[-3000:]}"
        bad = json.loads(proc.stdout.strip().splitlines()[-1])
        assert not bad, f"delay {delay_us} us: calls {bad[:10]} differ from one thread's hits"
