"""The frame's memory budget: how many triangles the machine can hold, checked before they are made.

DACRT copies every triangle of a frame out of Blender (each instance's, in world space) and
tessellates point clouds and hair, which have no triangles of their own, into spheres and tubes.
Linux overcommits memory: an array too big for the machine is granted, and the process (Blender,
with the artist's unsaved work) is killed by the kernel when its pages are touched, so numpy's
MemoryError never comes (a hunt: 4M points as 80M triangles grew to 23.5 GB and were killed
without a word). So before tessellating, the export sets the frame's need against the memory
available: point clouds and hair go coarser than their usual level, then the biggest of them are
left out (named, with the numbers), and a frame whose meshes alone cannot fit is refused.
"""
from __future__ import annotations

import ctypes
import os
import sys
from dataclasses import dataclass

from .. import allocator

# Peak bytes a frame triangle costs over export, set-up and tracing (the engine's
# memory_peak_mb, 32x24 pixels, 1 sample): a 1000x1000 grid placed 2 and 4 times (4M -> 8M
# triangles) 246 per triangle; point clouds of 100K and 200K points as spheres (2M, 4M triangles)
# 296 and 292; 20K and 40K hair curves as tubes 294 (the tessellation's float64 temporaries)
MESH_BYTES = 250
STRAND_BYTES = 300
HEADROOM = 0.9          # of the available memory, for images, rays and the rest of the frame
# Peak bytes a film pixel costs over a frame (process growth rendering a plane at 1 sample:
# 2000x2000 and 4000x4000 pixels 193 and 192), plus each channel of the requested passes (their
# float64 sums and Blender's float32 result: 20 channels of passes 525 at 2000x2000)
PIXEL_BYTES = 200
PASS_CHANNEL_BYTES = 16
# Peak bytes a texel of an image file costs from its read to the render, by the file's depth and
# how its colour space is read (colorspaces.space_kind): process growth rendering a plane
# textured by a 4096 x 4096 RGBA file (1 sample, less the untextured render). 8-bit: sRGB 16.5
# (kept as its bytes), linear 40, Non-Color 36, ACEScg 122; deeper (16-bit PNG, half and float
# EXR, read as floats): linear and Non-Color 21, sRGB 72 (16-bit PNG) and 100 (float EXR, its
# alpha stored associated), ACEScg 106 (the decodes' float temporaries)
TEXEL_BYTES = {(True, 'srgb'): 17, (True, 'linear'): 40, (True, 'data'): 40, (True, 'convert'): 122,
               (False, 'srgb'): 100, (False, 'linear'): 21, (False, 'data'): 21, (False, 'convert'): 106}


def _cgroup_room():
    """Bytes left under this process's cgroup v2 memory limit (containers, systemd slices), or
    None without one."""
    try:
        with open('/proc/self/cgroup') as f:
            path = next((line.strip()[3:] for line in f if line.startswith('0::')), None)
        if path is None:
            return None
        base = os.path.join('/sys/fs/cgroup', path.lstrip('/'))
        with open(os.path.join(base, 'memory.max')) as f:
            limit = f.read().strip()
        if limit == 'max':
            return None
        with open(os.path.join(base, 'memory.current')) as f:
            return max(int(limit) - int(f.read().strip()), 0)
    except (OSError, ValueError):
        return None


def _windows_available():
    class Status(ctypes.Structure):
        _fields_ = [('dwLength', ctypes.c_ulong), ('dwMemoryLoad', ctypes.c_ulong)] + \
                   [(n, ctypes.c_ulonglong) for n in ('ullTotalPhys', 'ullAvailPhys', 'ullTotalPageFile',
                                                      'ullAvailPageFile', 'ullTotalVirtual', 'ullAvailVirtual',
                                                      'ullAvailExtendedVirtual')]
    status = Status()
    status.dwLength = ctypes.sizeof(Status)
    try:
        if ctypes.windll.kernel32.GlobalMemoryStatusEx(ctypes.byref(status)):
            return int(status.ullAvailPhys)
    except (AttributeError, OSError):
        pass
    return None


def available_bytes():
    """Memory a frame may still take, in bytes, or None where the system does not say (macOS:
    no budget is applied): the system's available memory (Linux MemAvailable, or the cgroup's
    limit where lower; Windows' available physical memory) plus the free blocks the render heap
    holds (allocator.py)."""
    if sys.platform == 'win32':
        room = _windows_available()
    elif sys.platform.startswith('linux'):
        kb = allocator.proc_kb('MemAvailable', '/proc/meminfo')
        room = None if kb is None else kb * 1024
        cgroup = _cgroup_room()
        if cgroup is not None:
            room = cgroup if room is None else min(room, cgroup)
    else:
        room = None
    return None if room is None else room + allocator.heap_free()


def film_bytes(pixels, pass_channels):
    """Bytes a film of `pixels` pixels with `pass_channels` channels of passes besides Combined
    takes to render."""
    return pixels * (PIXEL_BYTES + pass_channels * PASS_CHANNEL_BYTES)


def texture_bytes(texels, byte, kind):
    """Bytes an image file of `texels` texels takes to read and render: 8-bit (`byte`) or
    deeper, its colour space read as `kind` (colorspaces: 'srgb', 'linear', 'data', 'convert')."""
    return texels * TEXEL_BYTES[byte, kind]


@dataclass
class Strands:
    """One point cloud, Curves object or hair system for the budget: its key, its kind
    ('spheres' or 'tubes'), its triangles at a level (a function) and how many times the frame
    places it."""
    key: object
    kind: str
    triangles_at: object
    copies: int

    def need(self, level):
        return self.triangles_at(level) * self.copies * STRAND_BYTES


def fit(mesh_triangles, strands, start, ladders, available):
    """(level per kind, the Strands left out) so that the frame fits in `available` bytes
    (None: no budget, the start levels). Starting from `start` (kind -> level, the usual level
    for the frame's points), the kind that needs the most memory goes one step down its ladder
    (kind -> levels, finest first) until the frame fits; when every kind is at its coarsest, the
    strands that need the most are left out, one at a time."""
    levels = dict(start)
    if available is None:
        return levels, []
    limit = available * HEADROOM - mesh_triangles * MESH_BYTES
    kept = list(strands)
    dropped = []

    def kind_need(kind):
        return sum(s.need(levels[kind]) for s in kept if s.kind == kind)
    while kept and sum(s.need(levels[s.kind]) for s in kept) > limit:
        finer = [k for k in levels if any(s.kind == k for s in kept) and levels[k] != ladders[k][-1]]
        if finer:
            kind = max(finer, key=kind_need)
            ladder = ladders[kind]
            levels[kind] = ladder[ladder.index(levels[kind]) + 1]
        else:
            biggest = max(kept, key=lambda s: s.need(levels[s.kind]))
            kept.remove(biggest)
            dropped.append(biggest)
    return levels, dropped


def gigabytes(n):
    """A size in bytes as people read it: 22.3 GB, 512 MB, 703 KB."""
    for unit, size in (('GB', 2**30), ('MB', 2**20), ('KB', 2**10)):
        if n >= size / (10 if unit == 'GB' else 1):
            return f"{n / size:.1f} GB" if unit == 'GB' else f"{n / size:.0f} {unit}"
    return f"{n:.0f} bytes"
