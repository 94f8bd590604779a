"""Cycles reference images for the parity scenes, cached on disk.

Rendering Cycles with many seeds is the expensive part of the suite, and its result only
changes when the scene, the settings or Blender change. So the per-seed Cycles images are kept
in `build/parity-cache/<scene>-<key>.npz`, where the key hashes everything they depend on:
the source of scenes.py (the builders) and rendering.py (the fair settings and the EXR path),
the spec's settings and seeds, and the bpy version. Change any of these and the reference is
rendered again; an unchanged tree reuses it. Delete the folder to force a re-render. A lock
file per scene makes a second pytest-xdist worker that needs the same reference (a scene's
parity test and its statistics test) wait for the first one's render and read it, instead of
rendering it again alongside.
"""
import contextlib
import fcntl
import hashlib
import inspect
import json
import os
import pathlib
import tempfile
import time

import bpy
import numpy as np

from . import rendering, scenes

ROOT = pathlib.Path(__file__).resolve().parents[2]
CACHE_DIR = ROOT / "build" / "parity-cache"
CYCLES_SEED_BASE = 0          # Cycles seeds 0..M-1; DACRT uses its own range (test_parity.py)


def cycles_seeds(spec):
    return list(range(CYCLES_SEED_BASE, CYCLES_SEED_BASE + spec.cycles_seeds))


def cache_key(spec):
    description = dict(
        spec=spec.key(), seeds=cycles_seeds(spec),
        scenes_source=inspect.getsource(scenes), rendering_source=inspect.getsource(rendering),
        bpy=bpy.app.version_string, bpy_hash=bpy.app.build_hash.decode() if isinstance(
            bpy.app.build_hash, bytes) else str(bpy.app.build_hash))
    text = json.dumps(description, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def cache_path(spec):
    return CACHE_DIR / f"{spec.name}-{cache_key(spec)}.npz"


@contextlib.contextmanager
def _scene_lock(spec):
    CACHE_DIR.mkdir(parents=True, exist_ok=True)
    with open(CACHE_DIR / f"{spec.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)         # released when the file closes
        yield


def cycles_images(spec):
    """(cycles_seeds, H, W, 4) float32 Cycles renders of spec, from the cache or rendered now.
    Returns (images, seconds spent rendering, or None when cached)."""
    with _scene_lock(spec):
        return _cached_or_rendered(spec)


def _cached_or_rendered(spec):
    path = cache_path(spec)
    if path.exists():
        try:
            with np.load(path) as data:
                images = data["images"]
            if images.shape[0] == spec.cycles_seeds and np.isfinite(images).all():
                return images, None
        except (OSError, ValueError, KeyError):
            pass                                  # unreadable or partial: render again
    t0 = time.perf_counter()
    images = rendering.render_seeds(spec, 'CYCLES', cycles_seeds(spec))
    seconds = time.perf_counter() - t0
    for stale in CACHE_DIR.glob(f"{spec.name}-*.npz"):     # older keys of this scene
        stale.unlink(missing_ok=True)
    fd, tmp = tempfile.mkstemp(dir=CACHE_DIR, suffix=".npz.part")
    os.close(fd)
    with open(tmp, "wb") as f:
        np.savez_compressed(f, images=images, seconds=seconds)
    os.replace(tmp, path)                          # atomic: never a half-written reference
    return images, seconds
