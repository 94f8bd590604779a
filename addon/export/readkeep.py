"""Texels read from an image file (float ones, or an 8-bit file's decoded bytes), kept for the next frame while the file and every
setting its conversion reads stay the same.

Cycles reads an image's file at every render, and so does the export (images._file_texels):
a 4K float EXR HDRI took ~0.63 s of a ~0.72 s 160 x 120 frame to read and convert. What the
conversion makes depends only on the file's bytes and on the image's settings it reads, so a
frame whose key matches gets the texels the last read made: the file by its resolved path and
os.stat identity and version (device, inode, size, mtime_ns, ctime_ns; taken before the read,
so a file rewritten during it is read again next time), and the image's name (in the
conversion's messages), alpha mode, colour space and its Non-Color flag, the lookup's
unassociation and the lazy byte form. The Texture Limit is not in it: it is applied to the
texels after (images._texture_limited); a sequence's frame and a UDIM tile pick the path. The
messages the read gave are given again with the texels.

Kept texels are read-only (numpy's writeable flag, on them and on the arrays they view): a
consumer that wrote into them would change the next frame's image, and raises instead. Only
ImageTexels (float32 arrays) are kept as texels: an 8-bit image's lazy ByteTexels are not
(the floats they make on first read would stay with them), but its decoded bytes are
(keep_bytes: a 4K x 2K PNG took ~280 ms of CPU to decode every frame), and each frame converts a
copy of them. At most _KEEP_BYTES are kept in all (two 4K x 2K float RGBA images), the least
recently used dropped first; a bigger image is not kept.
"""
from __future__ import annotations

import os
import threading

import numpy as np

from ..texture import ImageTexels

_kept: dict = {}          # {key: (texels, messages, bytes)}, oldest use first
_KEEP_BYTES = 2 * 4096 * 2048 * 4 * 4
_lock = threading.Lock()     # (a viewport's export and a final render's may run at once)


def file_key(path, img, unassociate, lazy):
    """The key of the file at `path` read as `img`'s texels, or None if it cannot be stat'ed."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    cs = img.colorspace_settings
    return (os.path.realpath(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns,
            img.name, img.alpha_mode, cs.name, bool(cs.is_data), bool(unassociate), bool(lazy))


def kept(key, reasons):
    """The texels kept under key (their read's messages appended to reasons), or None."""
    entry = _touch(key)
    if entry is None:
        return None
    reasons.extend(entry[1])
    return entry[0]


def _arrays(texels):
    """The arrays a kept ImageTexels holds: its own and its stored (lookup) texels."""
    stored = texels.stored
    return [texels] + ([stored.texels] if stored is not None and isinstance(stored.texels, np.ndarray) else [])


def _freeze(a):
    """a and the arrays it views made read-only."""
    while isinstance(a, np.ndarray):
        a.flags.writeable = False
        a = a.base


def keep(key, texels, messages):
    """Keep texels (what the read under key made, with its messages) if they are float
    ImageTexels within the byte limit; they are read-only from here on."""
    if key is None or type(texels) is not ImageTexels:
        return
    arrays = _arrays(texels)
    size = sum(a.nbytes for a in arrays)
    if size > _KEEP_BYTES:
        return
    for a in arrays:
        _freeze(a)
    _store(key, (texels, tuple(messages), size))


def kept_bytes(key):
    """The decoded bytes of an 8-bit file kept under key (keep_bytes: read-only), or None."""
    entry = None if key is None else _touch(('bytes',) + key)
    return None if entry is None else entry[0]


def keep_bytes(key, raw):
    """Keep an 8-bit file's decoded bytes (uint8, as images._read_flipped made them under key)
    within the byte limit; read-only from here on (a copy of it is what a frame converts)."""
    if key is None or not isinstance(raw, np.ndarray) or raw.dtype != np.uint8 or raw.nbytes > _KEEP_BYTES:
        return
    _freeze(raw)
    _store(('bytes',) + key, (raw, (), raw.nbytes))


def _touch(key):
    """The entry kept under key, now the most recently used, or None."""
    if key is None:
        return None
    with _lock:
        entry = _kept.pop(key, None)
        if entry is not None:
            _kept[key] = entry
    return entry


def _store(key, entry):
    """Keep entry (value, messages, bytes) under key, dropping the least recently used entries
    while all would exceed _KEEP_BYTES."""
    with _lock:
        _kept.pop(key, None)
        while _kept and sum(e[2] for e in _kept.values()) + entry[2] > _KEEP_BYTES:
            del _kept[next(iter(_kept))]
        _kept[key] = entry


def forget():
    """Drop what is kept (tests; a session that wants the memory back)."""
    with _lock:
        _kept.clear()
