"""numpy's BLAS kept on the calling thread while a frame renders (OpenBLAS; elsewhere nothing
changes).

numpy's OpenBLAS hands even a 3x3 inverse to its worker threads (np.linalg.inv: dgesv's
triangular solves, gemm_thread_n), and a worker woken so then spins in sched_yield before it
parks: per 4-spp render ~13 ms of CPU on the second core (the dragon's two smooth-normal
inverses in the export; many_lights makes 21 such calls a render), beside the tracer's own
workers, and the caller waits for the wake-up (12-16 ms wall on a busy machine, 0.1 ms on one
thread). A render's numpy matrices are all tiny: on one thread they take microseconds and give
the same bits (the five benchmark scenes' images identical; inv, solve and det of 360K random
matrices identical with OPENBLAS_NUM_THREADS=1). So while any frame renders (nested or
concurrent uses count: the F12 render, a viewport's session) OpenBLAS runs on one thread, and
its setting from before returns when the last one ends.

OpenBLAS is found among the libraries the process has loaded (/proc/self/maps) by its
num-threads functions under the names numpy's builds give them (plain, the 64-bit interface's
'64_', scipy-openblas's 'scipy_' prefix); none found (another BLAS, no /proc): nothing to do.
(threadpoolctl does this for every BLAS, but the extension would have to bundle it as a second
wheel beside the native one for this one OpenBLAS call pair.)
"""
from __future__ import annotations

import ctypes
import os
import threading
from contextlib import contextmanager

_PREFIXES = ('', 'scipy_')
_SUFFIXES = ('64_', '', '_64')

_lock = threading.Lock()
_depth = 0
_saved = None                 # OpenBLAS's thread count before the outermost use
_found = []                   # [(get, set) or None], looked up once


def _mapped_openblas():
    """Paths of the loaded shared libraries whose file name says OpenBLAS."""
    try:
        with open('/proc/self/maps') as f:
            lines = f.read().splitlines()
    except OSError:
        return []
    paths = []
    for line in lines:
        parts = line.split(None, 5)
        if len(parts) == 6 and parts[5].startswith('/') and 'openblas' in os.path.basename(parts[5]).lower():
            paths.append(parts[5].strip())
    return list(dict.fromkeys(paths))


def controls():
    """(get, set) of the loaded OpenBLAS's thread count (ctypes functions), or None."""
    if not _found:
        _found.append(_lookup())
    return _found[0]


def _lookup():
    mode = getattr(os, 'RTLD_NOLOAD', 0) | getattr(os, 'RTLD_LAZY', 1)
    for path in _mapped_openblas():
        try:
            lib = ctypes.CDLL(path, mode=mode)     # (the loaded copy: NOLOAD never loads another)
        except OSError:
            continue
        for prefix in _PREFIXES:
            for suffix in _SUFFIXES:
                get = getattr(lib, f'{prefix}openblas_get_num_threads{suffix}', None)
                put = getattr(lib, f'{prefix}openblas_set_num_threads{suffix}', None)
                if get is not None and put is not None:
                    get.restype, get.argtypes = ctypes.c_int, []
                    put.restype, put.argtypes = None, [ctypes.c_int]
                    return get, put
    return None


@contextmanager
def blas_on_caller():
    """OpenBLAS on one thread while any such block runs (see the module doc)."""
    global _depth, _saved
    api = controls()
    if api is None:
        yield
        return
    get, put = api
    with _lock:
        _depth += 1
        if _depth == 1:
            _saved = int(get())
            if _saved != 1:
                put(1)
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _saved is not None and _saved != 1:
                put(_saved)
