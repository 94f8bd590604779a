"""The render-time allocator policy (addon/allocator.py): active on glibc, harmless around
errors, and a render inside it gives the same image as one outside it."""
import contextlib
import platform

import numpy as np
import pytest

import addon.integrator as integrator_module
from addon import allocator

from . import scenes


def test_policy_is_active_on_glibc():
    if platform.system() == 'Linux' and platform.libc_ver()[0] == 'glibc':
        assert allocator._LIBC is not None
    else:
        assert allocator._LIBC is None


def test_policy_restores_after_an_error():
    with pytest.raises(RuntimeError):
        with allocator.render_heap():
            raise RuntimeError("boom")
    with allocator.render_heap():          # usable again afterwards
        big = np.ones(8 << 20, np.float32)
        assert big.sum() == 8 << 20


def test_image_does_not_depend_on_the_policy(monkeypatch):
    sd = scenes.cornell_box(width=24, height=18, samples=4, max_bounces=2, area_light=True)
    held = scenes.render(sd).film.combined()
    monkeypatch.setattr(integrator_module, 'render_heap', contextlib.nullcontext)
    plain = scenes.render(sd).film.combined()
    np.testing.assert_array_equal(held, plain)


def test_nested_and_interleaved_uses_restore_once():
    outer, inner = allocator.render_heap(), allocator.render_heap()
    outer.__enter__()
    inner.__enter__()
    outer.__exit__(None, None, None)          # the outer one may end first (generators)
    assert allocator._depth == 1
    inner.__exit__(None, None, None)
    assert allocator._depth == 0


def _glibc_malloc_serves():
    """Whether glibc's malloc serves this process (the sanitizer build's ASan replaces it and
    maps its own memory: no brk heap to hold or trim)."""
    import ctypes
    return allocator._LIBC is not None and not hasattr(ctypes.CDLL(None), '__asan_init')


_NEEDS_GLIBC_MALLOC = pytest.mark.skipif(not _glibc_malloc_serves(),
                                         reason="glibc's malloc does not serve this process (non-glibc "
                                                "platform, or the AddressSanitizer build)")


def _heap_kib():
    """Resident size of the process's brk heap in KiB (0 when it has none). Resident, not
    mapped: malloc_trim returns free pages below live blocks with MADV_DONTNEED, which leaves
    the mapping's size as it was."""
    size, in_heap = 0, False
    for line in open('/proc/self/smaps'):
        if line[0] in '0123456789abcdef' and '-' in line.split()[0]:
            in_heap = line.rstrip().endswith('[heap]')
        elif in_heap and line.startswith('Rss:'):
            size += int(line.split()[1])
    return size


@_NEEDS_GLIBC_MALLOC
def test_release_heap_returns_the_memory():
    allocator.release_heap()                     # an earlier render's heap may still be held
    with allocator.render_heap():
        arrays = [np.ones(1 << 20, np.uint8) for _ in range(64)]   # 1 MiB each: from the heap
        assert all(a[-1] == 1 for a in arrays)
        inside = _heap_kib()
        del arrays
    assert inside >= 64 << 10
    allocator.release_heap()                     # what the delayed release does when idle
    assert _heap_kib() < inside - (32 << 10), "release_heap() did not trim the heap"


@_NEEDS_GLIBC_MALLOC
def test_heap_kept_between_renders_then_released_when_idle(monkeypatch):
    import resource
    import time
    allocator.release_heap()                     # an earlier render's heap may still be held
    monkeypatch.setattr(allocator, 'RELEASE_DELAY', 0.3)
    with allocator.render_heap():
        arrays = [np.ones(1 << 20, np.uint8) for _ in range(32)]
        del arrays
    f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    with allocator.render_heap():                  # the next frame, right away: same pages
        arrays = [np.ones(1 << 20, np.uint8) for _ in range(32)]
        del arrays
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0
    assert faults < 200, f"{faults} page faults: the heap was not kept for the next frame"
    kept = _heap_kib()
    deadline = time.monotonic() + 10
    while allocator._held and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not allocator._held, "the heap was not released after the delay"
    assert _heap_kib() < kept - (16 << 10)
    with allocator.render_heap():                  # a render starting later gets a fresh policy
        assert allocator._held
    allocator.release_heap()
    assert not allocator._held


@pytest.mark.skipif(allocator._LIBC is None or allocator._numpy_madvise_switch() is None,
                    reason="needs glibc and a numpy with a huge-page switch")
def test_numpy_huge_page_advice_off_while_held_and_restored():
    allocator.release_heap()                     # an earlier render's heap may still be held
    switch = allocator._numpy_madvise_switch()
    before = switch(True)
    switch(before)
    with allocator.render_heap():
        current = switch(False)
        switch(current)
        assert current is False
    allocator.release_heap()
    after = switch(before)
    assert after == before
