"""The native environment map of texels that stay the same from one frame to the next, kept
for the next frame instead of built again.

A Sky Texture's radiance map is made once per parameter set (export/sky.py keeps it, read-only,
and names it by those parameters: scenedata.Environment.texels_key); the map's tables (its copy
of the texels, the luminance, the CDFs and their guides, the cell pdfs) and the check that any
texel is bright were still made from it every frame: ~31 ms of CPU (a 1024 x 2048 Hosek-Wilkie
map) and ~61 ms (a 2048 x 2048 Multiple Scattering one) of a 160 x 120 1 spp frame's 53-55 and
85-92 ms. The native map is immutable once built, so a frame whose world has the same
texels, rotation, strength and lookup reuses it: the same object, the same samples and film.

Only the latest map is kept (an MS sky's is ~105 MB beside its 48 MB image), replaced by the
next keyed one.

An Environment Texture's image has no such name: its texels are read again every frame (from
its file, as Cycles reads it at each render, or from Blender's buffer), and what they are
follows the file, edits, reloads, the frame of a sequence and every colour setting. So the map
built from them is kept with those texels themselves, and a frame whose texels hold the very
same bits (and the same rotation, strength and lookup) reuses it: an exact comparison, a
chunked pass over both arrays (~15 ms for a 4K float image), where the map's build took ~120
ms of CPU. Kept for texels of up to _SAME_BYTES (a 4K x 2K float RGBA image): beyond that the
two arrays held between frames would be a gigabyte, so bigger maps are built every frame.

The world's check of an Environment Texture's texels (texel_stats: non-finite, negative and
bright values, export/world.py) is kept with the latest texels it scanned when those are a
read-only array (a file's texels export.readkeep gives again, the very same array each frame),
and the bright check of those texels reads it: that scan and the bright check's had cost ~28 ms
of CPU each of a 160 x 120 1 spp frame with a 4K float EXR HDRI (the first frame two scans, the
second one, every later frame one of its ~46 ms). Texels that can be written (Blender's buffer,
read into a new array each frame) are scanned every frame.
"""
from __future__ import annotations

import threading
import weakref

import dacrt
import numpy as np

from ..texture import any_positive_rgb

_kept: dict = {}          # {key: native map}: at most one entry
# the latest map of unkeyed texels: {'texels': the array it was built from, 'rest': _rest(...),
# 'native': the map}, or empty
_same: dict = {}
_SAME_BYTES = 4096 * 2048 * 4 * 4
_CHUNK = 1 << 20            # elements compared at a time (no temporaries the size of the image)
_asked: dict = {}           # {'env': weakref to the Environment last compared, 'same': the answer}
_bright: dict = {}        # {texels_key: any RGB above 0}: a bool per sky kept (few)
_BRIGHT_KEPT = 8
_stats: dict = {}         # {'texels': weakref to the read-only array last scanned, 'stats': its texel_stats}
# (a viewport's export and a final render's may run at once: a comparison and the map it answers
# for are read under one lock, so one thread's build cannot replace the map another was told it may reuse)
_lock = threading.Lock()


def _key(env, to_map, interpolation, strength):
    return (env.texels_key, np.asarray(to_map, np.float64).tobytes(), interpolation,
            np.asarray(strength, np.float32).tobytes())


def _rest(to_map, interpolation, strength):
    """What a map is made from besides its texels, as bytes."""
    return (np.asarray(to_map, np.float64).tobytes(), interpolation, np.asarray(strength, np.float32).tobytes())


def same_bits(a, b) -> bool:
    """Whether arrays a and b have the same shape, dtype and bytes (C-contiguous ones; others
    are not compared: False), a chunk at a time."""
    if a.shape != b.shape or a.dtype != b.dtype or not (a.flags.c_contiguous and b.flags.c_contiguous):
        return False
    word = next(w for w in (np.uint64, np.uint32, np.uint16, np.uint8) if a.nbytes % np.dtype(w).itemsize == 0)
    x, y = a.reshape(-1).view(word), b.reshape(-1).view(word)
    return all(np.array_equal(x[i:i + _CHUNK], y[i:i + _CHUNK]) for i in range(0, len(x), _CHUNK))


def native_map(env, to_map, interpolation, strength):
    """dacrt.lamps.environment_map of env's texels (float32, linear) with the strength folded
    in: the kept one when env.texels_key and the rest match the latest keyed build, or, without
    a key, when the texels hold the same bits as those of the latest unkeyed build (and the
    rest matches)."""
    with _lock:
        if env.texels_key is None:
            return _unkeyed_map(env, to_map, interpolation, strength)
        key = _key(env, to_map, interpolation, strength)
        native = _kept.get(key)
        if native is None:
            _kept.clear()          # (before the build: the old map's memory is free for the new one)
            _same.clear()
            _asked.clear()
            native = _kept[key] = dacrt.lamps.environment_map(env.pixels, to_map, interpolation, scale=strength)
        return native


def _matches_kept(env) -> bool:
    """Whether env (unkeyed) holds the bits of the kept map's texels: compared once per env
    (the export's bright check and the map's build ask for the same one). Texels in the kept
    array's own memory are not compared with it: written in place since, they would equal
    themselves (each frame's export reads its images into new arrays, but for a file's texels
    kept read-only by export.readkeep: the same array, unchanged)."""
    if not _same or _same['srgb']:
        return False
    if _asked.get('env') is not None and _asked['env']() is env:
        return _asked['same']
    texels = env.pixels
    # (the kept array itself, read-only with all it views, cannot have been written: a file's
    # texels export.readkeep gives again)
    same = isinstance(texels, np.ndarray) and ((texels is _same['texels'] and read_only(texels)) or (
        not np.may_share_memory(_same['texels'], texels) and same_bits(_same['texels'], texels)))
    if same:
        _same['texels'] = texels        # (the same bits: the older frame's array can go)
    _asked.clear()
    _asked.update(env=weakref.ref(env), same=same)
    return same


def read_only(a) -> bool:
    """Whether a and every array it views are read-only."""
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        a = a.base
    return True


def _unkeyed_map(env, to_map, interpolation, strength):
    texels = env.pixels
    if not isinstance(texels, np.ndarray) or texels.nbytes > _SAME_BYTES:
        return dacrt.lamps.environment_map(texels, to_map, interpolation, scale=strength)
    rest = _rest(to_map, interpolation, strength)
    if _matches_kept(env) and _same['rest'] == rest:
        return _same['native']
    _same.clear()              # (before the build, as above)
    _kept.clear()
    native = dacrt.lamps.environment_map(texels, to_map, interpolation, scale=strength)
    _same.update(texels=texels, rest=rest, native=native, srgb=False)
    _asked.clear()             # (an earlier answer was about the texels kept before)
    _asked.update(env=weakref.ref(env), same=True)
    return native


def encoded_map(encoded, to_map, interpolation, strength):
    """dacrt.lamps.environment_map of an sRGB-encoded image's texels (Environment.encoded: an
    8-bit image's bytes, or float32 encoded RGB), kept as the unkeyed linear ones are: reused
    for encoded texels of the same bits with the same rest."""
    with _lock:
        if not isinstance(encoded, np.ndarray) or encoded.nbytes > _SAME_BYTES:
            return dacrt.lamps.environment_map(encoded, to_map, interpolation, srgb=True, scale=strength)
        rest = _rest(to_map, interpolation, strength)
        if _same and _same['srgb'] and _same['rest'] == rest and not np.may_share_memory(_same['texels'], encoded) \
                and same_bits(_same['texels'], encoded):
            _same['texels'] = encoded       # (the same bits: the older frame's array can go)
            return _same['native']
        _same.clear()
        _kept.clear()
        _asked.clear()
        native = dacrt.lamps.environment_map(encoded, to_map, interpolation, srgb=True, scale=strength)
        _same.update(texels=encoded, rest=rest, native=native, srgb=True)
        return native


def any_positive(env) -> bool:
    """Whether any of env's texels has an RGB value above 0 (texture.any_positive_rgb), found
    once per keyed texels, and once per kept unkeyed ones."""
    with _lock:
        if env.texels_key is None:
            if not _matches_kept(env):
                return _any_positive_rgb(env.pixels)
            if 'bright' not in _same:
                _same['bright'] = _any_positive_rgb(_same['texels'])
            return _same['bright']
        found = _bright.get(env.texels_key)
        if found is None:
            if len(_bright) >= _BRIGHT_KEPT:
                _bright.clear()
            found = _bright[env.texels_key] = any_positive_rgb(env.pixels)
        return found


def _scanned(texels):
    """The latest scan's texel_stats if texels is the very array scanned then and it, with every
    array it views, is read-only (so its bits are those scanned); else None. Under _lock."""
    seen = _stats.get('texels')
    return _stats['stats'] if seen is not None and seen() is texels and read_only(texels) else None


def _any_positive_rgb(texels) -> bool:
    """texture.any_positive_rgb, from the latest scan where that scanned these texels. Under _lock."""
    stats = _scanned(texels)
    return any_positive_rgb(texels) if stats is None else bool(stats[2])


def texel_stats(texels):
    """dacrt.lamps.texel_stats(texels), taken again from the latest scan of the same read-only
    array (_scanned)."""
    with _lock:
        stats = _scanned(texels)
    if stats is not None:
        return stats
    stats = dacrt.lamps.texel_stats(texels)
    with _lock:
        _stats.clear()
        if isinstance(texels, np.ndarray) and read_only(texels):
            _stats.update(texels=weakref.ref(texels), stats=stats)
    return stats


def forget():
    """Drop what is kept (tests; a session that wants the memory back)."""
    with _lock:
        _stats.clear()
        _kept.clear()
        _same.clear()
        _asked.clear()
        _bright.clear()
