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
next keyed one; a world without a key (an Environment Texture's image, read from Blender each
frame) builds its own and leaves the kept one alone.
"""
from __future__ import annotations

import dacrt
import numpy as np

from ..texture import any_positive_rgb

_kept: dict = {}          # {key: native map}: at most one entry
_bright: dict = {}        # {texels_key: any RGB above 0}: a bool per sky kept (few)
_BRIGHT_KEPT = 8


def _key(env, to_map, interpolation, strength):
    return (env.texels_key, np.asarray(to_map, np.float64).tobytes(), interpolation,
            np.asarray(strength, np.float32).tobytes())


def native_map(env, to_map, interpolation, strength):
    """dacrt.lamps.environment_map of env's texels (float32, linear) with the strength folded
    in: the kept one when env.texels_key and the rest match the latest keyed build."""
    if env.texels_key is None:
        return dacrt.lamps.environment_map(env.pixels, to_map, interpolation, scale=strength)
    key = _key(env, to_map, interpolation, strength)
    native = _kept.get(key)
    if native is None:
        _kept.clear()          # (before the build: the old map's memory is free for the new one)
        native = _kept[key] = dacrt.lamps.environment_map(env.pixels, to_map, interpolation, scale=strength)
    return native


def any_positive(env) -> bool:
    """Whether any of env's texels has an RGB value above 0 (texture.any_positive_rgb), found
    once per keyed texels."""
    if env.texels_key is None:
        return any_positive_rgb(env.pixels)
    found = _bright.get(env.texels_key)
    if found is None:
        if len(_bright) >= _BRIGHT_KEPT:
            _bright.clear()
        found = _bright[env.texels_key] = any_positive_rgb(env.pixels)
    return found


def forget():
    """Drop what is kept (tests; a session that wants the memory back)."""
    _kept.clear()
    _bright.clear()
