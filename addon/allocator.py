"""The C allocator's policy while a frame renders (glibc only; elsewhere nothing changes).

A wavefront pass allocates and frees dozens of per-path arrays of megabytes each. glibc serves
such blocks with mmap and returns them on free, so the next pass takes a page fault and a zeroed
page per 4 KiB again, plus a TLB-shootdown IPI to the other tracer thread per munmap: measured
~18% of a Cornell-box render (perf: clear_page, page faults, smp_call_function). While a render
runs, freed blocks therefore stay in the heap for the next pass (mmap threshold up, trimming
off); when it ends, the thresholds go back to glibc's defaults and the heap is trimmed, so the
memory returns to the system (Blender's memory stays flat across renders). Nested uses (the
engine holds the heap for a whole frame: export, set-up and passes; the integrator for its
passes) act once, at the outermost.
"""
from __future__ import annotations

import ctypes
import platform
from contextlib import contextmanager

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_GLIBC_DEFAULT = 128 * 1024          # both thresholds' documented defaults (mallopt(3))
_HOLD_MMAP = (1 << 30, 32 << 20)     # the first glibc accepts (some cap it at 32 MiB)
_HOLD_TRIM = 2 ** 31 - 1             # mallopt takes an int: never trim


def _libc():
    if platform.system() != 'Linux' or platform.libc_ver()[0] != 'glibc':
        return None
    try:
        libc = ctypes.CDLL(None)
        return libc if hasattr(libc, 'mallopt') and hasattr(libc, 'malloc_trim') else None
    except OSError:
        return None


_LIBC = _libc()
_depth = 0


@contextmanager
def render_heap():
    """Keep freed blocks in the heap while any such block runs (see the module doc)."""
    global _depth
    _depth += 1
    if _LIBC is not None and _depth == 1:
        for size in _HOLD_MMAP:
            if _LIBC.mallopt(_M_MMAP_THRESHOLD, size):
                break
        _LIBC.mallopt(_M_TRIM_THRESHOLD, _HOLD_TRIM)
    try:
        yield
    finally:
        _depth -= 1
        if _LIBC is not None and _depth == 0:
            _LIBC.mallopt(_M_MMAP_THRESHOLD, _GLIBC_DEFAULT)
            _LIBC.mallopt(_M_TRIM_THRESHOLD, _GLIBC_DEFAULT)
            _LIBC.malloc_trim(0)
