"""Next-event estimation's shadow rays come out in block order, numbered by position, whichever
worker shades which block and whenever it finishes (native/cpp/nextevent.cpp event_blocks: a
block's rays are moved to follow the block before by whichever worker finds that block done,
while the other worker still shades later blocks).

shade_bounce and next_event on two threads against the same calls on one thread (one thread
places every block after the one before, in order; its next_event against its blocks called
one at a time), bit for bit, over passes of many blocks with samples that add no ray. The calls run in a subprocess with DACRT_TEST_WORKER_DELAY_US
(read once per process): the pool worker then starts each call late, so the caller shades the
first blocks and the worker's blocks finish out of order with the caller's (the placing worker
has to wait for, and then catch up past, a block the other still holds)."""

import json
import os
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import json
    import numpy as np
    import dacrt
    from dacrt import shading
    from tests.integrator.test_shading_fused import _bounce_inputs, _lights, SHORTEN, BLOCK
    from tests.native.test_shading import _unit

    F32 = np.float32
    bad = []

    def same(a, b):
        if isinstance(a, (tuple, list)):
            return len(a) == len(b) and all(same(p, q) for p, q in zip(a, b))
        if isinstance(a, np.ndarray):
            return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
        return a == b

    for seed, blocks in ((1, 37), (2, 64), (3, 5)):
        rng = np.random.default_rng(seed)
        lc = _lights(rng, lamps=True, triangles=True)
        n = blocks * BLOCK - 123
        x = _bounce_inputs(rng, n)

        def bounce():
            return shading.shade_bounce(lc, x['hits'], x['hit'], x['live'], x['albedo'], x['thr'], x['u_rr'],
                                        x['geo'], x['normals'], x['D'], x['pid'], x['keys'], x['pick'], (11, 12),
                                        SHORTEN, True, (21, 22))
        P = (np.array([0.3, -0.7, 1.2], F32)[:, None] + rng.normal(size=(3, n)) * 1.5).astype(F32)
        ns = _unit(rng, n)
        P_off = (P + ns * F32(1e-4)).astype(F32)
        thr = rng.uniform(0.0, 1.0, (3, n)).astype(F32)
        keys = rng.integers(0, 2 ** 32, (2, n), dtype=np.uint64).astype(np.uint32)
        pick, prim = rng.random(n), rng.integers(0, 40, n).astype(np.int32)

        def nee():
            return shading.next_event(lc, P, P_off, ns, None, thr, keys, 7, 8, pick=pick, prim=prim,
                                      shorten=SHORTEN, skip_work=True)
        with dacrt.thread_limit(1):
            ref = bounce(), nee()
            # and one thread's next_event is its blocks' results one block at a time, in order
            parts = [(b, shading.next_event(lc, P[:, b:b + BLOCK], P_off[:, b:b + BLOCK], ns[:, b:b + BLOCK], None,
                                            thr[:, b:b + BLOCK], keys[:, b:b + BLOCK], 7, 8, pick=pick[b:b + BLOCK],
                                            prim=prim[b:b + BLOCK], shorten=SHORTEN, skip_work=True))
                     for b in range(0, n, BLOCK)]
        whole = np.concatenate([p[2] for _, p in parts])
        whole['id'] = np.arange(len(whole))
        if not (same(ref[1][2], whole) and same(ref[1][3], np.concatenate([p[3] + b for b, p in parts]))
                and ref[1][5] == sum(p[5] for _, p in parts)):
            bad.append(('next_event one thread', seed))
        rays = ref[0][3][2]
        assert 0 < len(rays) < n and np.array_equal(rays['id'], np.arange(len(rays)))
        for rep in range(6):
            got = bounce(), nee()
            if not same(got[0], ref[0]):
                bad.append(('shade_bounce', seed, rep))
            if not same(got[1], ref[1]):
                bad.append(('next_event', seed, rep))
    print(json.dumps(bad))
""")


def test_shadow_rays_in_block_order_whichever_worker_finishes_first():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    for delay_us in (0, 300):
        env = dict(os.environ, DACRT_TEST_WORKER_DELAY_US=str(delay_us))
        env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in sys.path if p])
        proc = subprocess.run([sys.executable, "-c", SCRIPT], env=env, cwd=root, capture_output=True, text=True,
                              timeout=300)
        assert proc.returncode == 0, f"delay {delay_us} us: {proc.stderr[-3000:]}"
        bad = json.loads(proc.stdout.strip().splitlines()[-1])
        assert not bad, f"delay {delay_us} us: two threads' results differ from one thread's: {bad}"
