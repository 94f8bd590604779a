"""Per-vertex kernels at a render's batch sizes run on every thread, with one thread's results:
dacrt.shading.accumulate_masked (the light samples' add into the paths' radiance) had split
only from 2^17 columns per thread, so at every Cornell-box batch (10^4..2x10^5 paths) it ran
on the calling thread alone (0.07 s of CPU on one core while the other idled); uniform_pick
from 2^16. Which threads ran is read from /proc (CPU ticks), not timed."""

import threading

import dacrt
import numpy as np
import pytest
from dacrt import shading

from ..native.test_threads import _thread_cpu_seconds

F32 = np.float32
N_PATHS = 60_000         # a Cornell box 256 spp pass's shadow batch at its first bounces


def _batch(rng, N, n):
    L = rng.random((3, N)).astype(F32)
    pid = np.sort(rng.choice(N, n, replace=False)).astype(np.int64)   # the survivors, in order
    values = (rng.random((3, n)) * 20).astype(F32)
    mask = rng.random(n) < 0.5
    return L, pid, values, mask


def test_a_render_sized_batch_is_added_on_every_thread():
    if dacrt._core.hardware_threads() < 2 or _thread_cpu_seconds() is None:
        pytest.skip("needs two cores and Linux /proc to see which threads ran")
    rng = np.random.default_rng(3)
    L, pid, values, mask = _batch(rng, 4 * N_PATHS, N_PATHS)
    me = str(threading.get_native_id())
    before = _thread_cpu_seconds()
    mine = 0.0
    # /proc counts CPU time in 10 ms ticks: work for tens of them on this thread
    while mine < 0.3:
        for _ in range(200):
            shading.accumulate_masked(L, pid, values, mask, 10.0)
        after = _thread_cpu_seconds()
        mine = after[me] - before[me]
    others = sum(after[t] - before.get(t, 0.0) for t in after if t != me)
    assert others > 0.3 * mine, f"the calling thread {mine:.2f} s, the others {others:.2f} s"


@pytest.mark.parametrize("n", [1, 20_000, N_PATHS, 300_000])
def test_sums_match_one_thread_and_numpy(n):
    rng = np.random.default_rng(n)
    L, pid, values, mask = _batch(rng, n + 17, n)
    want = L.copy()
    clamped = values.copy()
    # clamp_light: a sample whose channels sum above the clamp is scaled to sum to it
    total = np.abs(clamped).sum(axis=0)
    over = total > 6.0
    clamped[:, over] *= F32(6.0) / total[over]
    want[:, pid[mask]] += clamped[:, mask]
    one = L.copy()
    with dacrt.thread_limit(1):
        shading.accumulate_masked(one, pid, values, mask, 6.0)
    shading.accumulate_masked(L, pid, values, mask, 6.0)
    np.testing.assert_array_equal(L, one)
    np.testing.assert_allclose(L, want, rtol=1e-6)


def test_a_render_sized_light_pick_is_drawn_on_every_thread():
    """uniform_pick (the light choice's and Russian roulette's numbers, once per bounce): the
    same split from 2^14 paths; below 2^16 per thread it had run on the calling thread alone."""
    if dacrt._core.hardware_threads() < 2 or _thread_cpu_seconds() is None:
        pytest.skip("needs two cores and Linux /proc to see which threads ran")
    keys = np.random.default_rng(5).integers(0, 2**32, (2, N_PATHS), dtype=np.uint32)
    with dacrt.thread_limit(1):
        one = shading.uniform_pick(keys, 7, 9)
    me = str(threading.get_native_id())
    before = _thread_cpu_seconds()
    mine = 0.0
    while mine < 0.3:
        for _ in range(200):
            got = shading.uniform_pick(keys, 7, 9)
        after = _thread_cpu_seconds()
        mine = after[me] - before[me]
    others = sum(after[t] - before.get(t, 0.0) for t in after if t != me)
    assert others > 0.3 * mine, f"the calling thread {mine:.2f} s, the others {others:.2f} s"
    assert all(np.array_equal(a, b) for a, b in zip(one, got))
