"""Blended world maps (export/worldmix.py: a world Mix Shader of a varying factor, an Add of two
maps) kept for the next export of the same world: at an HDRI's width a blend costs seconds of
CPU (~5.8 s a 4096 x 2048 image beside a colour), every frame of an animation and every viewport
update, where nothing of it changed.

What a map was made from is kept without the parts' texels themselves: a read-only array (a
file's texels export.readkeep gives again) by a weak reference, the same array meaning the same
bits; any other array, and the factor's values at every texel, by a digest of their bits, since a
writable array can be rewritten in place or its memory reused. At most _KEEP_BYTES of maps (three
4096 x 2048 ones: a Light Path mix's three worlds at a 4K HDRI's width, which an export asks for in
turn, so a budget of two would drop each before its reuse) are kept, the least recently used dropped
first; a bigger map is not kept. All is dropped when a file is loaded or a new one started (the add-on's
load_post handler, released_on_load), with the environment light's kept native maps."""

import hashlib
import itertools
import threading
import weakref
from dataclasses import replace

import bpy
import numpy as np

from ..lights import envkeep
from ..lights.envkeep import read_only
from . import worldmix

# the latest blended maps (a world with Light Path blends up to three per export: the lighting,
# the camera's and the bounces' worlds): [{'made': _made(...), 'env': Environment, 'bytes': n}],
# the most recently used last
_kept: list = []
_KEEP_BYTES = 3 * 4096 * 2048 * 3 * 4
_serial = itertools.count()
_lock = threading.Lock()


def kept_map(parts, directions_of, width, factor=None):
    """blended_map(parts, directions_of, width, factor), the very Environment an earlier call
    made where that call's parts and factor values are the same: each part's uniform colour,
    strength, rotation and interpolation equal, and its texels either named by the same
    texels_key (a Sky Texture's map) or the same bits (an Environment Texture's image: the same
    read-only array, or an array whose digest is the kept one's); the factor compared by the
    digest of its values at every texel centre of the map (computed anyway, a small part of the
    blend: a Gradient's 0.07 s of 5.8 s at 4096 x 2048), so no change of the nodes behind it can
    be missed. The map is made read-only and given a texels_key of its own, so the environment
    light's native map of it is kept too (lights/envkeep.py). A part whose texels are computed on
    read (texture.LazyTexels) is not compared: built each time."""
    width, height = worldmix.grid(parts, width)
    dirs = directions_of(width, height)
    values = None
    if factor is not None:
        flat = dirs.reshape(-1, 3)
        band = max(1, (1 << 18) // width) * width
        values = np.concatenate([np.asarray(factor(np.ascontiguousarray(flat[i:i + band], np.float32)),
                                            np.float32).reshape(-1, 1) for i in range(0, len(flat), band)])
    size = dirs.shape[0] * dirs.shape[1] * 3 * 4         # (the map's float32 RGB: all an entry holds)
    made = None if size > _KEEP_BYTES else _made(parts, values)
    with _lock:
        for i, entry in enumerate(_kept):
            if made is not None and _same_made(entry['made'], made):
                _kept.append(_kept.pop(i))          # (the most recently used last)
                return entry['env']
    offset = [0]

    def kept_factor(d):
        # (blended_map asks band by band, in order: the values computed above, once)
        f = values[offset[0]:offset[0] + len(d)]
        offset[0] += len(d)
        return f
    env = worldmix.blended_map(parts, lambda w, h: dirs, width, None if values is None else kept_factor)
    if made is None:
        return env
    env.pixels.setflags(write=False)
    env = replace(env, texels_key=('worldmix', next(_serial)))
    for part in made:
        if isinstance(part, tuple) and isinstance(part[1], _Texels):
            part[1].drop()
    with _lock:
        while _kept and sum(e['bytes'] for e in _kept) + size > _KEEP_BYTES:
            del _kept[0]
        _kept.append({'made': made, 'env': env, 'bytes': size})
    return env


def _digest(a):
    """The shape, dtype and a digest of the bits of array a."""
    a = np.ascontiguousarray(a)
    return a.shape, a.dtype.str, hashlib.sha256(a.reshape(-1).view(np.uint8)).digest()


def _made(parts, values):
    """What a blended map is made from, for _same_made; None where a part's texels cannot be compared."""
    made = [None if values is None else _digest(values)]
    for uniform, env in parts:
        made.append(np.asarray(uniform, np.float32).tobytes())
        if env is None:
            made.append(None)
            continue
        texels = env.pixels if env.encoded is None else env.encoded
        if env.texels_key is None and not isinstance(texels, np.ndarray):
            return None
        made.append((env.texels_key, None if env.texels_key is not None else _Texels(texels),
                     np.asarray(env.strength, np.float32).tobytes(), np.asarray(env.to_map, np.float64).tobytes(),
                     env.interpolation, env.encoded is None))
    return made


class _Texels:
    """A part's texels as kept: a read-only array by a weak reference (the same array, still
    read-only with all it views, holds the same bits), any other by the digest of its bits
    (taken when first asked: an array given again by identity is not hashed)."""
    __slots__ = ('_ref', '_texels', '_digest')

    def __init__(self, texels):
        self._ref = weakref.ref(texels) if read_only(texels) else None
        self._texels, self._digest = texels, None     # (the array only until kept: drop())

    def digest(self):
        if self._digest is None:
            self._digest = _digest(self._texels)
        return self._digest

    def drop(self):
        """Keep the digest (if not read-only), not the array."""
        if self._ref is None:
            self.digest()
        self._texels = None

    def same(self, new) -> bool:
        """Whether the new _Texels (not kept) holds these texels' bits."""
        if self._ref is not None and self._ref() is new._texels and read_only(new._texels):
            return True
        return self._ref is None and new.digest() == self._digest


def _same_made(a, b) -> bool:
    """Whether the kept _made record a and the new one b name the same blended map."""
    if a[0] != b[0] or len(a) != len(b):
        return False
    for x, y in zip(a[1:], b[1:]):
        if x is None or y is None or not isinstance(x, tuple):
            if x != y:
                return False
        elif x[0] != y[0] or x[2:] != y[2:] or (x[0] is None and not x[1].same(y[1])):
            return False
    return True


def forget():
    """Drop the kept maps (a file loaded or a new one; tests)."""
    with _lock:
        _kept.clear()


@bpy.app.handlers.persistent
def released_on_load(*_args):
    """load_post / load_factory_startup_post: the maps kept for the old file's worlds, and the
    environment light's kept native maps, are dropped (their memory back)."""
    forget()
    envkeep.forget()


_HANDLERS = ('load_post', 'load_factory_startup_post')


def register_handlers():
    for name in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if released_on_load not in handlers:
            handlers.append(released_on_load)


def unregister_handlers():
    for name in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        while released_on_load in handlers:
            handlers.remove(released_on_load)
