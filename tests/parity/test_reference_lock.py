"""Two pytest-xdist workers that need the same Cycles reference at once (a scene's parity test
and its statistics test) render it once: the second waits on the scene's lock file and reads
the first one's cache. Threads stand in for the workers: flock locks conflict between separate
opens of the file, in one process as in two."""
import dataclasses
import threading
import time

import numpy as np

from . import reference, rendering
from .scenes import SPECS


def test_concurrent_requests_render_a_reference_once(monkeypatch, tmp_path):
    monkeypatch.setattr(reference, "CACHE_DIR", tmp_path)
    spec = dataclasses.replace(SPECS[0], cycles_seeds=2)
    renders = []

    def render_seeds(spec_, engine, seeds, workdir=None):
        renders.append(engine)
        time.sleep(0.5)                        # long enough for the other request to arrive
        return np.full((len(seeds), 3, 4, 4), len(renders), np.float32)

    monkeypatch.setattr(rendering, "render_seeds", render_seeds)
    got = [None, None]

    def request(i):
        got[i] = reference.cycles_images(spec)

    threads = [threading.Thread(target=request, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert renders == ['CYCLES'], f"the reference was rendered {len(renders)} times"
    (first, seconds_a), (second, seconds_b) = got
    assert np.array_equal(first, second) and first.shape == (2, 3, 4, 4)
    assert sorted([seconds_a is None, seconds_b is None]) == [False, True]   # one rendered, one read
