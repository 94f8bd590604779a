"""The C allocator's policy while a frame renders (glibc only; elsewhere nothing changes).

A wavefront pass allocates and frees dozens of per-path arrays of megabytes each. glibc serves
such blocks with mmap and returns them on free, so the next pass takes a page fault and a zeroed
page per 4 KiB again, plus a TLB-shootdown IPI to the other tracer thread per munmap: measured
~18% of a Cornell-box render (perf: clear_page, page faults, smp_call_function). While a render
runs, freed blocks therefore stay in the heap for the next pass (mmap threshold up, trimming
off); when rendering stops (below), the thresholds go back to glibc's defaults and the heap is
trimmed, so the memory returns to the system (Blender's memory stays flat across renders).
Nested uses (the engine holds the heap for a whole frame: export, set-up and passes; the
integrator for its passes) act once, at the outermost.

The pages a frame faulted in are still zeroed by the kernel each time (clear_page: 7% of a
dragon render at 16 spp). So the heap is trimmed RELEASE_DELAY seconds after the last render
ends, not at once: the frames of an animation, or renders a script runs back to back, reuse the
previous frame's pages, and an artist's single F12 render still gives its memory back moments
later (release_heap() does it at once).

Transparent huge pages were measured and left out: growing the heap by a block marked
MADV_HUGEPAGE cut a render's page faults from 28K to ~1K, but the first render at a new size
then faulted in (and zeroed) whole 2 MiB pages it barely used (Cornell box, 64 spp, first render
in a process: 0.39 -> 0.58 s; later renders equal). For the same reason numpy's own per-array
huge-page advice (arrays of 4 MiB and more) is off while the heap is held: on this machine a
fresh 36 MiB array took 80-110 ms to first touch with it instead of 14 ms.

The release stays a timer thread started per render: one waiting thread for the process instead
made render_heap's enter + exit cheaper (0.4 -> 0.05 ms median, 8-12 -> 0.07 ms one time in ten
on two busy cores), but whole renders slower while it lived (32x24 Cornell box, alternating in one
process: 32 vs 20 ms a render, the same in three runs; why is not known).
"""
from __future__ import annotations

import ctypes
import os
import platform
import threading
import time
from contextlib import contextmanager

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_GLIBC_DEFAULT = 128 * 1024          # both thresholds' documented defaults (mallopt(3))
_HOLD_MMAP = (1 << 30, 32 << 20)     # the first glibc accepts (some cap it at 32 MiB)
_HOLD_TRIM = 2 ** 31 - 1             # mallopt takes an int: never trim
RELEASE_DELAY = 2.0                  # seconds without a render before the heap is trimmed


def _libc():
    if platform.system() != 'Linux' or platform.libc_ver()[0] != 'glibc':
        return None
    try:
        libc = ctypes.CDLL(None)
        return libc if hasattr(libc, 'mallopt') and hasattr(libc, 'malloc_trim') else None
    except OSError:
        return None


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in ('arena', 'ordblks', 'smblks', 'hblks', 'hblkhd', 'usmblks',
                                                     'fsmblks', 'uordblks', 'fordblks', 'keepcost')]


# glibc's mallinfo2 walks every free block of every arena: on a fragmented heap (a frame of 8000
# separate objects) one call took 36-63 ms, and a frame made 3-4 of them. Within a frame, a
# reading younger than HEAP_SPACING times the last call's own cost is used again (the frame
# then spends at most ~1/HEAP_SPACING of its time reading the heap); the frame's first reading
# (its baseline, render_heap) is always fresh, and nothing is kept past the frame.
HEAP_SPACING = 20.0


def _mallinfo(fresh):
    """(blocks in use (uordblks + hblkhd), free blocks (fordblks)) in bytes, or None where glibc's
    mallinfo2 cannot be read; a recent reading of the frame again unless fresh."""
    global _reading
    fn = getattr(_LIBC, 'mallinfo2', None) if _LIBC is not None else None
    if fn is None:
        return None
    start = time.perf_counter()
    last = _reading
    if not fresh and last is not None and start - last[0] < last[1] * HEAP_SPACING:
        return last[2]
    fn.restype = _MallInfo2
    info = fn()
    got = (int(info.uordblks) + int(info.hblkhd), int(info.fordblks))
    end = time.perf_counter()
    if _depth:                      # (a frame's: dropped when it ends, see render_heap)
        _reading = (end, end - start, got)
    return got


def heap_in_use(fresh=True):
    """Bytes the C heap has handed out and not got back (glibc's mallinfo2: every arena's
    blocks in use plus mmapped ones), or None where that cannot be read. numpy's arrays and
    Blender's own buffers come from it, so its growth over a render is what the render holds
    (the held heap's free blocks are not counted). fresh=False: a recent reading of the frame
    may be given again (HEAP_SPACING)."""
    got = _mallinfo(fresh)
    return None if got is None else got[0]


def heap_free(fresh=False):
    """Bytes of free blocks the C heap holds (glibc's mallinfo2 fordblks), 0 where that cannot
    be read: memory a frame gets back without asking the system (a held heap keeps the previous
    frame's, which the system does not count as available). A recent reading of the frame may
    be given again unless fresh (HEAP_SPACING)."""
    got = _mallinfo(fresh)
    return 0 if got is None else got[1]


def proc_kb(field, path='/proc/self/status'):
    """A 'Field: N kB' line's N of a Linux /proc file (this process's status, /proc/meminfo),
    or None where it cannot be read."""
    # (one read of the bytes: the file's lines through Python's text layer had taken 72-87 us
    # of a 32x24 render's few ms, where the kernel's part is ~40)
    key = field.encode('ascii') + b':'
    try:
        fd = os.open(path, os.O_RDONLY)
        try:
            data = os.read(fd, 1 << 16)
        finally:
            os.close(fd)
        if data.startswith(key):
            at = 0
        else:
            at = data.find(b'\n' + key) + 1
            if at == 0:
                return None
        end = data.find(b'\n', at)
        return int(data[at + len(key):end if end >= 0 else len(data)].split()[0])
    except (OSError, ValueError, IndexError):
        return None


def rss_peak_reset():
    """Reset the process's peak resident size to its current one (Linux clear_refs 5) and
    return that size in bytes, or None where it cannot be done."""
    try:
        with open('/proc/self/clear_refs', 'w') as f:
            f.write('5')
    except OSError:
        return None
    kb = proc_kb('VmRSS')
    return None if kb is None else kb * 1024


def rss_peak():
    """The process's peak resident size in bytes since rss_peak_reset (VmHWM), or None: it
    sees the export's temporaries (an 8K image's conversion) that heap samples between the
    passes miss."""
    kb = proc_kb('VmHWM')
    return None if kb is None else kb * 1024


def _numpy_madvise_switch():
    """numpy's switch for its per-array huge-page advice (returns the previous setting), or
    None where this numpy has none."""
    import numpy
    for mod in ('_core', 'core'):
        multiarray = getattr(getattr(numpy, mod, None), 'multiarray', None)
        switch = getattr(multiarray, '_set_madvise_hugepage', None)
        if switch is not None:
            return switch
    return None


_LIBC = _libc()
_depth = 0
_lock = threading.Lock()
_held = False                  # thresholds raised and the heap kept (during and just after renders)
_release_timer = None
_numpy_madvise = None          # numpy's setting before the hold (restored on release)
_reading = None                # the frame's last mallinfo2: (when, its cost, values) (_mallinfo)


@contextmanager
def render_heap():
    """Keep freed blocks in the heap while any such block runs and for RELEASE_DELAY seconds
    after the last one ends (see the module doc)."""
    global _depth, _held, _release_timer, _numpy_madvise, _reading
    with _lock:
        _depth += 1
        if _depth == 1:
            _reading = None
        if _LIBC is not None and _depth == 1:
            if _release_timer is not None:      # the previous frame's heap is still there: reuse it
                _release_timer.cancel()
                _release_timer = None
            if not _held:
                for size in _HOLD_MMAP:
                    if _LIBC.mallopt(_M_MMAP_THRESHOLD, size):
                        break
                _LIBC.mallopt(_M_TRIM_THRESHOLD, _HOLD_TRIM)
                switch = _numpy_madvise_switch()
                _numpy_madvise = None if switch is None else switch(False)
                _held = True
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                _reading = None
            if _LIBC is not None and _depth == 0:
                _release_timer = threading.Timer(RELEASE_DELAY, _release_if_idle)
                _release_timer.daemon = True
                _release_timer.start()


def _release_if_idle():
    with _lock:
        if _depth == 0:
            _release_locked()


def release_heap():
    """Return the kept heap to the system now (no-op while a render runs)."""
    global _release_timer
    with _lock:
        if _depth == 0:
            if _release_timer is not None:
                _release_timer.cancel()
                _release_timer = None
            _release_locked()


def _release_locked():
    global _held, _numpy_madvise
    if _LIBC is not None and _held:
        _LIBC.mallopt(_M_MMAP_THRESHOLD, _GLIBC_DEFAULT)
        _LIBC.mallopt(_M_TRIM_THRESHOLD, _GLIBC_DEFAULT)
        _LIBC.malloc_trim(0)
        if _numpy_madvise is not None:
            _numpy_madvise_switch()(_numpy_madvise)
            _numpy_madvise = None
        _held = False
